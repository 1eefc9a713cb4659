# Sourced by scripts/test-sanitizers.sh and scripts/fuzz.sh: sanitizer runtime options and the
# ccache launcher (when ccache is installed).
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
