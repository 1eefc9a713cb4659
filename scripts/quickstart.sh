#!/usr/bin/env bash
# The README's first command: installs dependencies, builds, and runs the main job on the
# bundled tray6 sample, printing where the results are.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
out="${1:-out/tray6}"
./build/clutterscope visibility datasets/samples/tray6 --out "$out/visibility" --overlays
echo "visibility tables: $out/visibility/objects.csv, $out/visibility/images.csv, $out/visibility/summary.json"
