#!/usr/bin/env bash
# Installation tests (issue 27), run by ctest from the build folder:
#   install_test.sh consumer BUILD SAMPLES  `cmake --install` into a temporary prefix; the installed
#       clutterscope runs, and a tiny consumer project (tests/install/consumer) configures with
#       find_package(clutterscope CONFIG), builds and runs against it.
#   install_test.sh deb BUILD SAMPLES [python]  `cpack -G DEB`; the runtime package's dependencies are
#       Debian runtime packages (Mesa's EGL and llvmpipe included); unpacked into a temporary root
#       its clutterscope prints its version and computes visibility on a bundled sample, and the
#       Python module imports from there (with `python`: the build has the module, so the
#       package must carry it).
set -euo pipefail
mode="$1"
build="$(cd "$2" && pwd)"
samples="$(cd "$3" && pwd)"
here="$(cd "$(dirname "$0")" && pwd)"
scratch="$(mktemp -d "${TMPDIR:-/tmp}/clutterscope_install_test.XXXXXX")"
trap 'rm -rf "$scratch"' EXIT

fail() { echo "FAIL: $*" >&2; exit 1; }

# A visibility run of the installed executable on its installed copy of tray6; the per-object
# table must equal the build tree's on the same data.
check_visibility() {
  local exe="$1" dataset="$2"
  "$exe" visibility "$dataset" --images 0 --out "$scratch/vis_installed" > "$scratch/vis.log" 2>&1 ||
    { cat "$scratch/vis.log"; fail "installed $exe visibility failed"; }
  "$build/clutterscope" visibility "$samples/tray6" --images 0 --out "$scratch/vis_build" > /dev/null 2>&1 ||
    fail "build tree's visibility run failed"
  cmp "$scratch/vis_installed/objects.csv" "$scratch/vis_build/objects.csv" ||
    fail "installed and build-tree objects.csv differ"
  echo "visibility on the installed sample: $(($(wc -l < "$scratch/vis_installed/objects.csv") - 1)) rows, equal to the build tree's"
}

case "$mode" in
  consumer)
    prefix="$scratch/prefix"
    cmake --install "$build" --prefix "$prefix" > "$scratch/install.log" ||
      { cat "$scratch/install.log"; fail "cmake --install"; }
    "$prefix/bin/clutterscope" --version
    check_visibility "$prefix/bin/clutterscope" "$prefix/share/clutterscope/samples/tray6"
    cmake -S "$here/consumer" -B "$scratch/consumer-build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_PREFIX_PATH="$prefix" > "$scratch/configure.log" 2>&1 ||
      { cat "$scratch/configure.log"; fail "consumer configure with find_package(clutterscope CONFIG)"; }
    cmake --build "$scratch/consumer-build" > "$scratch/build.log" 2>&1 ||
      { cat "$scratch/build.log"; fail "consumer build"; }
    output="$("$scratch/consumer-build/consumer" "$samples/tray6")"
    echo "$output"
    [ "$output" = "$(printf 'images 6\nobject visibility 0.25')" ] || fail "consumer printed: $output"
    ;;
  deb)
    (cd "$scratch" && cpack -G DEB --config "$build/CPackConfig.cmake" > cpack.log 2>&1) ||
      { cat "$scratch/cpack.log"; fail "cpack -G DEB"; }
    runtime=$(ls "$scratch"/clutterscope_*.deb 2> /dev/null | head -1)
    dev=$(ls "$scratch"/clutterscope-dev_*.deb 2> /dev/null | head -1)
    [ -n "$runtime" ] && [ -n "$dev" ] || { ls "$scratch"; fail "cpack made no clutterscope_*.deb and clutterscope-dev_*.deb"; }
    depends="$(dpkg-deb -f "$runtime" Depends)"
    echo "Depends: $depends"
    for needed in libegl-mesa0 libgl1-mesa-dri libopencv-core libassimp; do
      grep -q "$needed" <<< "$depends" || fail "runtime package does not depend on $needed"
    done
    if grep -q -- "-dev" <<< "$depends"; then fail "runtime package depends on a -dev package"; fi
    root="$scratch/root"
    dpkg-deb -x "$runtime" "$root"
    "$root/usr/bin/clutterscope" --version
    check_visibility "$root/usr/bin/clutterscope" "$root/usr/share/clutterscope/samples/tray6"
    if [ "${4:-}" = python ]; then
      # The package clutterscope/ (tools/python): __init__.py beside the extension _clutterscope.
      module=$(find "$root/usr/lib" -name '_clutterscope*.so' -path '*python3*/clutterscope/*' |
        head -1)
      [ -n "$module" ] || fail "the runtime package has no Python module under usr/lib/python3*"
      (cd "$scratch" && PYTHONPATH="$(dirname "$(dirname "$module")")" /usr/bin/python3 -c \
        "import clutterscope, sys; print('python module', clutterscope.__file__); sys.exit(0 if clutterscope.__file__.startswith('$root') else 1)") ||
        fail "python3 -c 'import clutterscope' from the unpacked package"
    fi
    ;;
  *) fail "unknown mode $mode" ;;
esac
echo "PASS: $mode"
