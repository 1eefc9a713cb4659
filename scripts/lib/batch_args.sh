# shellcheck shell=bash
# The argument checks shared by scripts/slurm/submit.sh and scripts/parallel/run.sh (sourced).
# Each function exits 2 with a message prefixed by $script, the caller's name.

# COMMAND is one of the batch commands the recipes shard.
batch_check_command() {
  case "$1" in
    report | visibility | estimate | evaluate) ;;
    *) echo "$script: COMMAND must be report, visibility, estimate or evaluate, not $1" >&2
       exit 2 ;;
  esac
}

# batch_check_count OPTION VALUE: a whole number >= 1.
batch_check_count() {
  [[ "$2" =~ ^[1-9][0-9]*$ ]] || { echo "$script: $1 must be >= 1, got $2" >&2; exit 2; }
}

# batch_refuse_set_options WHAT_SETS_THEM OPTIONS...: the recipe sets --out, --shard and --jobs.
batch_refuse_set_options() {
  local sets="$1" option
  shift
  for option in "$@"; do
    case "$option" in
      --out | --out=* | --shard | --shard=* | -j | --jobs | --jobs=*)
        echo "$script: $option is set by the script ($sets)" >&2
        exit 2 ;;
    esac
  done
}

# batch_find_binary PATH_OR_EMPTY: prints the executable to run, by default build/clutterscope
# of this checkout when it exists, else clutterscope on PATH.
batch_find_binary() {
  local binary="$1"
  if [ -z "$binary" ]; then
    binary="$(dirname "${BASH_SOURCE[0]}")/../../build/clutterscope"
    [ -x "$binary" ] || binary="$(command -v clutterscope || true)"
  fi
  [ -x "$binary" ] || { echo "$script: no clutterscope executable (--binary PATH)" >&2; exit 2; }
  echo "$binary"
}
