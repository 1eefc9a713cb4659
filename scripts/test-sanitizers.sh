#!/usr/bin/env bash
# The test suite under AddressSanitizer + UndefinedBehaviorSanitizer (all but three repetition
# tests, below): builds build-asan/ (gcc, -O1 with line tables, test code at -O0) and runs ctest
# there. Extra arguments go to every ctest run.
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
memory_test='^Generator\.ThousandScenesOfTenObjectsRunInConstantMemory$'
# Left out here (they run in the normal suite): the accuracy tests repeat `estimate` over 20
# trays each and the estimate benchmark times 200 mixture products three ways, code that the
# EstimateGl.*, Product.* and Nbp.* tests run under the sanitizers too; together they took 538 s
# of the GL tests' 1161 s under ASan + UBSan (2026-12-03), and CI has 90 minutes.
repetition_tests='^(EstimateAccuracyGl\..*|BenchCliGl\.EstimatePrintsTheBreakdownAndTheTiledComparisons)$'
cd build-asan
# 1. Every test without GL, leaks included.
ctest --output-on-failure --timeout 1800 -j "$jobs" -LE gl -E "$memory_test" "$@"
# 2. The constant-memory test measures RSS: ASan's quarantine keeps freed blocks (256 MB by
#    default), so without it RSS shows our allocations, not the quarantine filling up.
ASAN_OPTIONS="$ASAN_OPTIONS:quarantine_size_mb=0" \
  ctest --output-on-failure --timeout 1800 -R "$memory_test" "$@"
# 3. GL tests, ASan and UBSan errors fail them, but not leaks: Mesa's DRI driver makes one-time
#    allocations in eglInitialize (pthread_once inside the driver) and is dlclosed by
#    eglTerminate, so at exit those blocks are unreachable and their stacks end in an unloaded
#    module (realloc <- <unknown module> ...), which no LeakSanitizer suppression can name with
#    the fast unwinder (the full stack, fast_unwind_on_malloc=0, reaches libEGL_mesa.so.0 and
#    render/src/context.cpp's eglInitialize). Measured 2026-12-01: every GL test's only report
#    was this leak (128-256 bytes).
ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" \
  ctest --output-on-failure --timeout 1800 -j "$jobs" -L gl -E "$repetition_tests" "$@"
echo "sanitizers: test suite took $((SECONDS - start)) s"
