#!/usr/bin/env bash
# The README's first command: installs dependencies, builds, and runs the main job — the
# clutter report — on the bundled tray6 sample. Prints the path of report.html and a summary.
# Usage: scripts/quickstart.sh [OUT_DIR]   (default out/tray6; re-running reuses finished work)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
out="${1:-out/tray6}"
./build/clutterscope report datasets/samples/tray6 --out "$out" --overlays
