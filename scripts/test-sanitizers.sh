#!/usr/bin/env bash
# Tests under AddressSanitizer + UndefinedBehaviorSanitizer, in build-san/ (clang; the tree of
# scripts/fuzz.sh, see scripts/sanitizer-env.sh).
#
#   scripts/test-sanitizers.sh [STEP...]          the whole suite, GL and end-to-end included
#                                                 (but three repetition tests, below): for
#                                                 larger changes
#   scripts/test-sanitizers.sh --unit [STEP...]   CI's part (scripts/test.sh): the library
#                                                 suites, without GL and without running the
#                                                 binary (every parser, the estimator core,
#                                                 batch, report, notebooks, render's and
#                                                 visibility's CPU parts, scene estimation,
#                                                 simulation), and every fuzz regression input;
#                                                 builds only their targets and the fuzz targets
#
# STEPs: build, suite, fuzz-regressions (default: all three, in this order). Arguments after
# `--` go to every ctest run.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/sanitizer-env.sh
jobs="${CLUTTERSCOPE_BUILD_JOBS:-$(nproc)}"

unit=0
steps=()
ctest_args=()
while [ "$#" -gt 0 ]; do
  case "$1" in
    --unit) unit=1 ;;
    build | suite | fuzz-regressions) steps+=("$1") ;;
    --) shift; ctest_args=("$@"); break ;;
    *) echo "test-sanitizers: unknown argument '$1'" >&2; exit 2 ;;
  esac
  shift
done
if [ "${#steps[@]}" -eq 0 ]; then steps=(build suite fuzz-regressions); fi

build() {
  configure_sanitizer_tree
  if [ "$unit" = 1 ]; then
    cmake --build "$sanitizer_tree" --parallel "$jobs" \
      --target clutterscope_library_test_suites clutterscope_fuzz_targets
  else
    cmake --build "$sanitizer_tree" --parallel "$jobs"
  fi
}

# ctest in the tree; --no-tests=error: a selection that matches nothing fails, never passes.
run_ctest() {
  (cd "$sanitizer_tree" && ctest --output-on-failure --no-tests=error --timeout 1800 "$@" \
    "${ctest_args[@]}")
}

suite() {
  local memory_test
  memory_test='^(Generator\.ThousandScenesOfTenObjectsRunInConstantMemory|Batch\.ResultsAreNotHeldInMemory)$'
  # Without --unit, the end-to-end suites too (tests/CMakeLists.txt).
  local leave_out='fuzz-regression|end-to-end'
  if [ "$unit" = 0 ]; then leave_out='fuzz-regression'; fi
  # Left out (it runs in the normal suite): the decimation of a 500k-triangle sphere, the code
  # Decimate.SphereMeetsTheCapClosedAndOutward runs under the sanitizers on 16k triangles; it
  # took 523 s under ASan + UBSan (clang, 2 loaded cores, 2026-12-04), 3.7 s CPU in Release.
  local left_out='^Decimate\.ScanSizedSphereReachesTheCap$'
  # Under --unit (CI) also left out: three tests that repeat code other tests run under the
  # sanitizers too, many times over (Nbp.* and Potentials.* run the same NBP and overlap code on
  # smaller cases; RayCastReference.FrontoParallelBoxMatchesClosedForm the same ray caster).
  # They took 242, 176 and 87 s of the suite's 1255 s CPU (clang, idle 2 cores, 2026-12-04).
  # Also the exact-answer NBP tests on the chain of five and the 2x2 grid (each with the fixed
  # and the adaptive proposal) and the many-sweep Gibbs product: statistical tests that repeat
  # the NBP and Gibbs code that Nbp.PerMessageProducts*, Nbp.ProductWithoutReceiver*,
  # Nbp.AdaptiveBeliefProposal* and Product.* run under the sanitizers on fewer samples; they
  # took 85 + 60 + 59 + 52 + 55 = 311 s of the suite's 997 s CPU (clang, 2 cores, 2026-12-05).
  if [ "$unit" = 1 ]; then
    left_out="$left_out|^(Nbp\.ErrorsShrinkWithParticles|Potentials\.OrientedNonContactAgreesWithBruteForceOverlap|RayCastReference\.OccluderAndTruncation)$"
    left_out="$left_out|^Nbp\.(AdaptiveProposal)?(LoopyGrid2x2MatchesExactJointMarginals|ChainOfFive3DMatchesExactMarginals)$"
    left_out="$left_out|^Product\.GibbsWithManySweepsMatchesExactProduct$"
    # And two more of the same kind (39 and 30 s there, cold CI run of de64528): the preset noise
    # statistics repeat the sensor code of Sensor.NoiseOnAFrontalPlaneMatchesTheModel, the
    # cylinder the decimation of Decimate.SphereMeetsTheCapClosedAndOutward.
    left_out="$left_out|^(Sensor\.PresetNoiseOnAFrontalPlaneMatchesItsPublishedFormula|Decimate\.CylinderKeepsTheSidesItsChordErrorNeeds)$"
    # And the thousand generated layouts (137 s wall under the sanitizers, the longest test
    # here, against 0.9 s in the release suite; cold CI run of 4d642c9): its claim, constant
    # memory, is measured in the release suite, and the layout code it repeats 1,000 times runs
    # under the sanitizers in the other Generator.* tests.
    left_out="$left_out|^Generator\.ThousandScenesOfTenObjectsRunInConstantMemory$"
    memory_test='^Batch\.ResultsAreNotHeldInMemory$'
  fi
  # 1. Every test without GL, leaks included (the fuzz regressions are their own step).
  run_ctest -j "$jobs" -L unit -LE "$leave_out" -E "$memory_test|$left_out"
  # 2. The constant-memory tests measure RSS: ASan's quarantine keeps freed blocks (256 MB by
  #    default), so without it RSS shows our allocations, not the quarantine filling up
  #    (Batch.ResultsAreNotHeldInMemory: 423 MB growth with it, 12 MB without, clang 14).
  #    Each measures its own process, so they run side by side.
  ASAN_OPTIONS="$ASAN_OPTIONS:quarantine_size_mb=0" run_ctest -j "$jobs" -R "$memory_test"
  if [ "$unit" = 1 ]; then return; fi
  # 3. GL tests, ASan and UBSan errors fail them, but not leaks: Mesa's DRI driver makes one-time
  #    allocations in eglInitialize (pthread_once inside the driver) and is dlclosed by
  #    eglTerminate, so at exit those blocks are unreachable and their stacks end in an unloaded
  #    module (realloc <- <unknown module> ...), which no LeakSanitizer suppression can name with
  #    the fast unwinder (the full stack, fast_unwind_on_malloc=0, reaches libEGL_mesa.so.0 and
  #    render/src/context.cpp's eglInitialize). Measured 2026-12-01: every GL test's only report
  #    was this leak (128-256 bytes).
  #    Left out (they run in the normal suite): the accuracy tests repeat `estimate` over 20
  #    trays each and the estimate benchmark times 200 mixture products three ways, code that
  #    the EstimateGl.*, Product.* and Nbp.* tests run under the sanitizers too; together they
  #    took 538 s of the GL tests' 1161 s under ASan + UBSan (gcc, 2026-12-03).
  local repetition_tests
  repetition_tests='^(EstimateAccuracyGl\..*|BenchCliGl\.EstimatePrintsTheBreakdownAndTheTiledComparisons)$'
  ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" \
    run_ctest -j "$jobs" -L gl -E "$repetition_tests"
}

# Every input of tests/fuzz/corpus and tests/fuzz/regressions, once, through its libFuzzer target.
fuzz-regressions() {
  run_ctest -j "$jobs" -L fuzz-regression
}

for step in "${steps[@]}"; do
  start=$SECONDS
  "$step"
  echo "test-sanitizers: $step took $((SECONDS - start)) s"
done
