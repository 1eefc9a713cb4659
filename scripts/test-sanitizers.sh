#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer: builds build-asan/
# (gcc, optimised, line tables) and runs ctest there. Extra arguments go to ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer-env.sh
jobs="${CLUTTERSCOPE_BUILD_JOBS:-$(nproc)}"
start=$SECONDS
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS=-g1 \
  -DCLUTTERSCOPE_ASAN=ON -DCLUTTERSCOPE_UBSAN=ON "${CLUTTERSCOPE_LAUNCHER[@]}" >/dev/null
cmake --build build-asan --parallel "$jobs"
echo "sanitizers: build took $((SECONDS - start)) s"
start=$SECONDS
(cd build-asan && ctest --output-on-failure --timeout 1800 -j "$jobs" "$@")
echo "sanitizers: test suite took $((SECONDS - start)) s"
