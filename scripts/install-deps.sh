#!/usr/bin/env bash
# Installs the Debian packages clutterscope needs.
#   scripts/install-deps.sh                 everything: build, run and test (scripts/test.sh, CI)
#   scripts/install-deps.sh --runtime-only  only what builds and runs the executable
#                                           (scripts/quickstart.sh): no test tools, browser,
#                                           Jupyter or Slurm
# Idempotent: packages already present are skipped by apt. Uses sudo when not root.
set -euo pipefail

usage() {
  sed -n '3,6p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}
runtime_only=0
case "${1:-}" in
  "") ;;
  --runtime-only) runtime_only=1 ;;
  *) usage ;;
esac
[ "$#" -le 1 ] || usage

# What the executable and its libraries need to build and run.
runtime_packages=(
  # toolchain (ccache is used when present)
  build-essential cmake ninja-build pkg-config git ccache
  # libraries
  libeigen3-dev nlohmann-json3-dev libcli11-dev libglm-dev libnanoflann-dev
  libassimp-dev libembree-dev
  libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev
  # headless OpenGL through libglvnd + Mesa (libgl1-mesa-dri is the software renderer)
  libegl-dev libopengl-dev libgl-dev libegl1 libopengl0 libegl-mesa0 libgl1-mesa-dri
)

# What only the tests need (tests/CMakeLists.txt and scripts/test.sh's stages).
test_packages=(
  # the sanitizer tree: clang with libFuzzer and the sanitizer runtimes (scripts/test-sanitizers.sh,
  # scripts/fuzz.sh)
  clang libclang-rt-14-dev
  # test suites; the renderer's tests compare with OpenCV's projection (calib3d)
  googletest libgtest-dev libgmock-dev libopencv-calib3d-dev python3
  # the .deb test (cpack -G DEB runs dpkg-shlibdeps)
  dpkg-dev
  # report checks: a real browser and Jupyter to execute the exported notebook
  chromium
  jupyter-nbconvert python3-nbclient python3-nbformat python3-ipykernel
  python3-pandas python3-matplotlib python3-jsonschema
  # the Python module (tools/python) and its pytest suite
  pybind11-dev python3-dev python3-numpy python3-pytest python3-tqdm
  # the scheduler recipes' tests (tests/scripts): a one-node Slurm cluster and GNU parallel
  slurm-wlm munge parallel
)

packages=("${runtime_packages[@]}")
if [ "$runtime_only" -eq 0 ]; then packages+=("${test_packages[@]}"); fi

missing=()
for package in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$package")
  fi
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
