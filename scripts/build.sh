#!/usr/bin/env bash
# Configures and builds clutterscope into build/ (Release). Uses ccache when it is installed.
#   scripts/build.sh [CMAKE_ARGS...]                 everything: the executable, its libraries,
#                                                    the test suites and the fuzz regressions
#   scripts/build.sh --runtime-only [CMAKE_ARGS...]  the executable and its libraries only
#                                                    (-DCLUTTERSCOPE_BUILD_TESTS=OFF
#                                                    -DCLUTTERSCOPE_PYTHON=OFF;
#                                                    scripts/quickstart.sh)
# The options are set either way, so a tree configured by one is switched by the other.
set -euo pipefail
cd "$(dirname "$0")/.."
tests=ON
python=ON
if [ "${1:-}" = --runtime-only ]; then
  tests=OFF
  python=OFF  # the Python module needs pybind11, a package of the test set
  shift
fi
jobs="${CLUTTERSCOPE_BUILD_JOBS:-$(nproc)}"
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DCLUTTERSCOPE_BUILD_TESTS="$tests" \
  -DCLUTTERSCOPE_PYTHON="$python" "${launcher[@]}" "$@" >/dev/null
cmake --build build --parallel "$jobs"
