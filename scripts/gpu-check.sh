#!/usr/bin/env bash
# Checks clutterscope on an NVIDIA GPU (issue 16): builds a Release build in build-gpu/ (the
# clutterscope executable and the GL test executables only), selects the NVIDIA EGL device,
# prints GL_RENDERER, runs `bench visibility` (default and --dense), `bench estimate` (the tiled
# against one-by-one scoring ratio), `bench evaluate` and the GL tests, teeing everything into a
# log. Fails when
# an NVIDIA device exists but rendering runs on a software rasteriser, and when any step fails
# (the other steps still run). On a machine without an NVIDIA GPU it says so and runs everything
# on the renderer it finds. About 5 minutes on 16 cores.
#
# Usage: scripts/gpu-check.sh [--quick] [--log PATH]
#   --quick     small benchmark workloads and the renderer's and visibility's GL tests only
#               (to try the script on a small machine in a few minutes)
#   --log PATH  where the log goes (default: gpu-check.log in the repository root)
# Environment: GPU_CHECK_NVIDIA=auto|yes|no overrides the detection of an NVIDIA device (yes:
# assume one, so a software renderer fails the check; no: assume none). CLUTTERSCOPE_EGL_DEVICE,
# when already set, is kept instead of the script's choice.
set -euo pipefail
cd "$(dirname "$0")/.."
root="$(pwd)"

quick=0
log="$root/gpu-check.log"
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --log)
      [ $# -ge 2 ] || { echo "gpu-check: --log needs a path" >&2; exit 2; }
      log="$2"
      shift
      ;;
    -h | --help)
      sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
      exit 0
      ;;
    *)
      echo "gpu-check: unknown argument '$1' (see --help)" >&2
      exit 2
      ;;
  esac
  shift
done
case "$log" in /*) ;; *) log="$root/$log" ;; esac
case "${GPU_CHECK_NVIDIA:-auto}" in
  auto | yes | no) ;;
  *)
    echo "gpu-check: GPU_CHECK_NVIDIA must be auto, yes or no, got '$GPU_CHECK_NVIDIA'" >&2
    exit 2
    ;;
esac

build="$root/build-gpu"
binary="$build/clutterscope"
bench_timeout=240  # seconds per benchmark
tests_timeout=420  # seconds for the GL tests
failures=()

# The NVIDIA device, if any: "yes (how it was found)" or "no".
detect_nvidia() {
  case "${GPU_CHECK_NVIDIA:-auto}" in
    yes) echo "yes (GPU_CHECK_NVIDIA=yes)" ;;
    no) echo "no (GPU_CHECK_NVIDIA=no)" ;;
    *)
      local listed
      if command -v nvidia-smi >/dev/null && listed="$(nvidia-smi -L 2>/dev/null)" &&
        [ -n "$listed" ]; then
        echo "yes (nvidia-smi -L: $(echo "$listed" | head -n 1))"
      elif [ -e /dev/nvidia0 ]; then
        echo "yes (/dev/nvidia0)"
      elif [ -e /usr/share/glvnd/egl_vendor.d/10_nvidia.json ]; then
        echo "yes (/usr/share/glvnd/egl_vendor.d/10_nvidia.json)"
      else
        echo "no"
      fi
      ;;
  esac
}

is_software_renderer() {
  case "$1" in *llvmpipe* | *softpipe* | *swrast* | *Mesa* | *lavapipe*) return 0 ;; esac
  return 1
}

# GL_RENDERER of the context `bench visibility` gets with CLUTTERSCOPE_EGL_DEVICE=$1 (empty:
# the automatic choice), from a one-image workload. Without one: its last line of output on
# stderr, exit status 1.
renderer_of() {
  local output renderer
  if output="$(CLUTTERSCOPE_EGL_DEVICE="$1" "$binary" bench visibility --images 1 --objects 1 \
    --triangles 12 --width 16 --height 16 --jobs 1 2>&1)"; then
    renderer="$(echo "$output" | sed -n 's/^renderer: //p' | head -n 1)"
    if [ -n "$renderer" ]; then
      echo "$renderer"
      return 0
    fi
    output="no 'renderer: ' line in the output of bench visibility"
  fi
  echo "$output" | tail -n 1 >&2
  return 1
}

# Runs a named step, recording a failure instead of stopping.
step() {
  local name="$1"
  shift
  echo
  echo "=== $name: $*"
  local start=$SECONDS status=0
  "$@" || status=$?
  if [ "$status" -eq 0 ]; then
    echo "=== $name: ok ($((SECONDS - start)) s)"
  else
    echo "=== $name: FAILED with exit code $status ($((SECONDS - start)) s)"
    failures+=("$name")
  fi
}

main() {
  local started=$SECONDS
  set -e
  echo "gpu-check: $(date -u '+%Y-%m-%d %H:%M:%S UTC') on $(uname -n), $(nproc) cores$(
    [ "$quick" = 1 ] && echo ', --quick')"
  echo "commit: $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"

  # 1. The NVIDIA device.
  local nvidia
  nvidia="$(detect_nvidia)"
  echo "NVIDIA device: $nvidia"
  if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1 || true
  fi

  # 2. The build: only the executable and the GL test executables.
  if ! command -v cmake >/dev/null || ! command -v ninja >/dev/null; then
    echo "cmake or ninja missing: running scripts/install-deps.sh (needs the Debian archive)"
    bash scripts/install-deps.sh
  fi
  local launcher=()
  if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
  local targets=(clutterscope) file
  for file in tests/*/*_gl_test.cpp; do
    targets+=("$(basename "$(dirname "$file")")_gl_tests")
  done
  mapfile -t targets < <(printf '%s\n' "${targets[@]}" | sort -u)
  echo
  echo "=== build: ${targets[*]}"
  local start=$SECONDS
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" >/dev/null
  cmake --build "$build" --parallel "$(nproc)" --target "${targets[@]}"
  echo "=== build: ok ($((SECONDS - start)) s)"

  # 3. The EGL device: a hardware one if the devices' renderers tell one apart.
  echo
  echo "=== EGL devices"
  if [ -n "${CLUTTERSCOPE_EGL_DEVICE:-}" ]; then
    echo "CLUTTERSCOPE_EGL_DEVICE=$CLUTTERSCOPE_EGL_DEVICE given: kept"
  else
    local index renderer chosen=""
    for index in 0 1 2 3 4 5 6 7; do
      if renderer="$(renderer_of "$index" 2>&1)"; then
        echo "device $index: $renderer"
        if [ -z "$chosen" ] && ! is_software_renderer "$renderer"; then chosen="$index"; fi
      else
        echo "device $index: $renderer"
        case "$renderer" in *"devices exist"*) break ;; esac  # past the last device
      fi
    done
    if [ -n "$chosen" ]; then
      export CLUTTERSCOPE_EGL_DEVICE="$chosen"
      echo "CLUTTERSCOPE_EGL_DEVICE=$chosen (a hardware renderer)"
    else
      echo "no hardware renderer among the EGL devices: the automatic choice is kept"
    fi
  fi
  local renderer
  renderer="$(renderer_of "${CLUTTERSCOPE_EGL_DEVICE:-}")" || {
    echo "gpu-check: no GL context on the selected EGL device (see above)"
    return 1
  }
  echo "renderer: $renderer"
  if [ "${nvidia%% *}" = yes ]; then
    if is_software_renderer "$renderer"; then
      echo "gpu-check: FAILED: an NVIDIA device exists ${nvidia#yes } but GL_RENDERER is" \
        "'$renderer'."
      echo "  The NVIDIA EGL driver is not reachable: check that libEGL_nvidia.so.0 and"
      echo "  /usr/share/glvnd/egl_vendor.d/10_nvidia.json are installed (in a container the"
      echo "  driver capabilities must include 'graphics': NVIDIA_DRIVER_CAPABILITIES=all)."
      return 1
    fi
    echo "NVIDIA device in use: $renderer"
  else
    echo "no NVIDIA device: running on $renderer"
  fi

  # 4. The benchmarks and the GL tests.
  local tray10="$root/datasets/samples/tray10"
  if [ "$quick" = 1 ]; then
    step "bench visibility" timeout "$bench_timeout" "$binary" bench visibility --images 4 \
      --objects 3 --triangles 200 --width 160 --height 120 --jobs 2
    step "bench visibility --dense" timeout "$bench_timeout" "$binary" bench visibility --dense \
      --images 2 --models 3 --triangles-min 2000 --triangles-max 4000 --job-images 20
    step "bench estimate" timeout "$bench_timeout" "$binary" bench estimate "$tray10" --images 1 \
      --particles 10 --iterations 1 --particles-list 8,10 --rounds 2
    step "bench evaluate" timeout "$bench_timeout" "$binary" bench evaluate --images 4 \
      --distinct-images 2 --objects 2 --models 3 --triangles-min 2000 --triangles-max 3000 \
      --full-frame-images 2
    step "GL tests" timeout "$tests_timeout" ctest --test-dir "$build" -L gl -j"$(nproc)" \
      --output-on-failure --timeout 240 \
      -R '^(ContextGl|RendererGl|BopRendererGl|VisibilityGl|Modes/VisibilityBopToolkit|EmbreeReference|EmbreeReferenceGl)\.'
  else
    step "bench visibility" timeout "$bench_timeout" "$binary" bench visibility
    step "bench visibility --dense" timeout "$bench_timeout" "$binary" bench visibility --dense
    step "bench estimate" timeout "$bench_timeout" "$binary" bench estimate "$tray10" --images 2 \
      --particles-list 50,100 --rounds 5
    step "bench evaluate" timeout "$bench_timeout" "$binary" bench evaluate
    step "GL tests" timeout "$tests_timeout" ctest --test-dir "$build" -L gl -j"$(nproc)" \
      --output-on-failure --timeout 240
  fi

  echo
  echo "gpu-check: renderer '$renderer', $((SECONDS - started)) s in all"
  if [ "${#failures[@]}" -gt 0 ]; then
    echo "gpu-check: FAILED: ${failures[*]}"
    return 1
  fi
  echo "gpu-check: every step passed"
}

# Not `main | tee || ...`: errexit would be off inside main.
set +e
main 2>&1 | tee "$log"
status=${PIPESTATUS[0]}
echo "gpu-check: log in $log"
exit "$status"
