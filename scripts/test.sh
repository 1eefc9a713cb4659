#!/usr/bin/env bash
# The README's test command: installs dependencies, builds, and runs the whole test suite; then
# the same suite under ASan + UBSan (scripts/test-sanitizers.sh, build-asan/) and a short run of
# every fuzz target (scripts/fuzz.sh, build-fuzz/). Extra arguments go to the first ctest.
# CLUTTERSCOPE_QUICK=1 stops after the first suite (for a quick local run; CI runs everything).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
(cd build && ctest --output-on-failure --timeout 900 -j "${CLUTTERSCOPE_BUILD_JOBS:-$(nproc)}" "$@")
if [ "${CLUTTERSCOPE_QUICK:-0}" = 1 ]; then
  echo "test: CLUTTERSCOPE_QUICK=1, sanitizer suite and fuzz smoke skipped"
  exit 0
fi
bash scripts/test-sanitizers.sh
bash scripts/fuzz.sh
