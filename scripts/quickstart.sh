#!/usr/bin/env bash
# The README's first command: installs dependencies, builds, and runs the main job — the
# clutter report — on the bundled tray6 sample. Prints the path of report.html and a summary.
# Installs and builds only what the main job needs (no test tools, browser or Jupyter, no test
# suites); scripts/test.sh adds the rest.
# Usage: scripts/quickstart.sh [OUT_DIR]   (default out/tray6; re-running reuses finished work)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh --runtime-only
bash scripts/build.sh --runtime-only
out="${1:-out/tray6}"
./build/clutterscope report datasets/samples/tray6 --out "$out" --overlays
