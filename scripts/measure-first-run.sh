#!/usr/bin/env bash
# Measures the README's first command (scripts/quickstart.sh) on a fresh Debian 12 root, as
# docs/testing.md's "First run on a fresh Debian 12 machine" reports it. Run as root.
#
# Usage: scripts/measure-first-run.sh PRISTINE_ROOT [COMMIT]   (COMMIT defaults to HEAD)
#
# PRISTINE_ROOT is a Debian 12 root that is never changed, made once with
#   debootstrap bookworm /tmp/fresh-pristine http://deb.debian.org/debian
#   (then add the bookworm-updates and bookworm-security sources of a fresh install:
#    scripts/measure-first-run.sh does it in its copy when they are missing)
# Each run copies it (cp -a) to PRISTINE_ROOT.run (removed first), mounts /proc, /sys and /dev
# there, puts `git archive COMMIT` in /root/clutterscope (no build/, no ccache) and runs the
# three lines of scripts/quickstart.sh one by one under `nice -n 19`, as root with a clean
# environment, timing each (wall, user, sys). The load average is sampled every 5 s. Everything
# is unmounted at the end, also on failure; the copy is kept for a look (remove it after).
# Prints one table row per stage and the total; the log of each stage is in
# PRISTINE_ROOT.run/root/measure-*.log.
set -euo pipefail

[ "$#" -ge 1 ] && [ "$#" -le 2 ] || { sed -n '5p' "$0" | sed 's/^# //' >&2; exit 2; }
[ "$(id -u)" -eq 0 ] || { echo "measure-first-run: run as root (chroot, mount)" >&2; exit 2; }
pristine="$(cd "$1" && pwd)"
commit="${2:-HEAD}"
repo="$(cd "$(dirname "$0")/.." && pwd)"
[ -x "$pristine/usr/bin/apt-get" ] || { echo "measure-first-run: $pristine is no Debian root" >&2; exit 2; }
sha="$(git -C "$repo" rev-parse --short "$commit")"

# The stages must be quickstart.sh's own lines at that commit.
quickstart="$(git -C "$repo" show "$commit:scripts/quickstart.sh")"
stages=(
  "bash scripts/install-deps.sh --runtime-only"
  "bash scripts/build.sh --runtime-only"
  "./build/clutterscope report datasets/samples/tray6 --out out/tray6 --overlays"
)
for stage in "${stages[@]:0:2}"; do
  grep -qxF "$stage" <<<"$quickstart" || { echo "measure-first-run: quickstart.sh at $sha no longer runs: $stage" >&2; exit 2; }
done
grep -qF './build/clutterscope report datasets/samples/tray6 --out "$out" --overlays' <<<"$quickstart" \
  || { echo "measure-first-run: quickstart.sh at $sha no longer runs the tray6 report" >&2; exit 2; }

root="$pristine.run"
mounted=()
cleanup() {
  local i
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do umount -R "${mounted[$i]}" || umount -R -l "${mounted[$i]}" || true; done
  [ -z "${sampler:-}" ] || kill "$sampler" 2>/dev/null || true
}
trap cleanup EXIT

rm -rf "$root"
cp -a "$pristine" "$root"
sources="$root/etc/apt/sources.list"
grep -q bookworm-updates "$sources" || echo "deb http://deb.debian.org/debian bookworm-updates main" >>"$sources"
grep -q bookworm-security "$sources" || echo "deb http://deb.debian.org/debian-security bookworm-security main" >>"$sources"
cp /etc/resolv.conf "$root/etc/resolv.conf"
for fs in proc sys dev; do
  mount --rbind "/$fs" "$root/$fs"
  mount --make-rslave "$root/$fs"
  mounted+=("$root/$fs")
done
mkdir -p "$root/root/clutterscope"
git -C "$repo" archive "$commit" | tar -x -C "$root/root/clutterscope"

loads="$root/root/measure-loadavg.txt"
(while sleep 5; do cut -d' ' -f1 /proc/loadavg; done) >"$loads" &
sampler=$!

echo "measure-first-run: commit $sha, $(nproc) cores, started $(date -u '+%Y-%m-%d %H:%M:%S') UTC"
printf '| stage | wall | CPU (user + sys) |\n|---|---|---|\n'
total_wall=0 total_user=0 total_sys=0
names=(packages build "main job")
for i in 0 1 2; do
  log="$root/root/measure-${names[$i]// /-}.log"
  # %e %U %S of GNU time would need the time package in the root; bash's times of the
  # children of one chroot'ed shell are the same figures.
  start=$(date +%s.%N)
  chroot "$root" env -i HOME=/root PATH=/usr/sbin:/usr/bin:/sbin:/bin \
    nice -n 19 bash -c "cd /root/clutterscope && ${stages[$i]} >/root/$(basename "$log") 2>&1; rc=\$?; times >/root/times.txt; exit \$rc" \
    || { echo "measure-first-run: stage '${stages[$i]}' failed, see $log" >&2; exit 1; }
  end=$(date +%s.%N)
  # The second line of `times`: the children's user and sys, as 1m2.345s.
  read -r user sys < <(sed -n 2p "$root/root/times.txt" | awk '
    function secs(t) { split(t, p, "m"); sub("s", "", p[2]); return p[1] * 60 + p[2] }
    { printf "%.1f %.1f\n", secs($1), secs($2) }')
  wall=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')
  printf '| %s | %s s | %.1f s (%s + %s) |\n' "${names[$i]}" "$wall" "$(awk -v u="$user" -v s="$sys" 'BEGIN { print u + s }')" "$user" "$sys"
  total_wall=$(awk -v a="$total_wall" -v b="$wall" 'BEGIN { print a + b }')
  total_user=$(awk -v a="$total_user" -v b="$user" 'BEGIN { print a + b }')
  total_sys=$(awk -v a="$total_sys" -v b="$sys" 'BEGIN { print a + b }')
done
printf '| **quickstart.sh** | **%.1f s** | **%.1f s** (%.1f + %.1f) |\n' "$total_wall" \
  "$(awk -v u="$total_user" -v s="$total_sys" 'BEGIN { print u + s }')" "$total_user" "$total_sys"
echo "measure-first-run: finished $(date -u '+%H:%M:%S') UTC; load average (1 min) over the run:" \
  "mean $(awk '{ s += $1; n++ } END { if (n) printf "%.1f", s / n; else print "n/a" }' "$loads")," \
  "max $(sort -g "$loads" | tail -1)"
tail -3 "$root/root/measure-main-job.log"
