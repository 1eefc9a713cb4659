# Sourced by scripts/test-sanitizers.sh and scripts/fuzz.sh: sanitizer runtime options, the
# ccache launcher (when ccache is installed) and the one sanitizer tree both use.
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# Stop at the first error, with a stack; leaks are errors too, except the GL driver's
# (tests/sanitizers/lsan.supp says why each is there).
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:print_summary=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:print_summary=1"
export LSAN_OPTIONS="suppressions=$root/tests/sanitizers/lsan.supp:print_suppressions=0"
CLUTTERSCOPE_LAUNCHER=()
if command -v ccache >/dev/null; then
  CLUTTERSCOPE_LAUNCHER=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi

# build-san/: clang, ASan + UBSan on everything, our code at -O1 with line tables, test code at
# -O0 (tests/CMakeLists.txt), and libFuzzer's coverage instrumentation, so that the same objects
# serve the test suites and the fuzz targets (CLUTTERSCOPE_FUZZ, cmake/ClutterscopeTarget.cmake).
# No Python module: a sanitized extension would need the ASan runtime preloaded into python3.
# No unity build: this tree compiles each .cpp on its own, so an #include that a file lacks (and
# that another file of its library's unit supplies in build/) fails here.
sanitizer_tree="$root/build-san"
configure_sanitizer_tree() {
  cmake -S "$root" -B "$sanitizer_tree" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_CXX_FLAGS=-g1 -DCMAKE_CXX_COMPILER=clang++ -DCLUTTERSCOPE_FUZZ=ON \
    -DCLUTTERSCOPE_PYTHON=OFF -DCLUTTERSCOPE_UNITY_BUILD=OFF \
    "${CLUTTERSCOPE_LAUNCHER[@]}" >/dev/null
}
