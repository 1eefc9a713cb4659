#!/usr/bin/env bash
# Byte comparison of clutterscope's outputs between two builds (issue #15's regression check for
# a restructuring that must change no behaviour).
#
# Usage:
#   scripts/compare-outputs.sh record MANIFEST [BINARY]  run everything, write MANIFEST
#   scripts/compare-outputs.sh check  MANIFEST [BINARY]  run everything again, compare with
#                                                        MANIFEST: exit 0 identical, 1 with the
#                                                        list of differing files, 2 usage or
#                                                        run error
#   BINARY defaults to build/clutterscope of this checkout (a relative BINARY is taken from the
#   current directory).
#
# Typical use, before/after a change:
#   git worktree add /tmp/old OLD_COMMIT && (cd /tmp/old && cmake -S . -B build -G Ninja \
#       -DCMAKE_BUILD_TYPE=Release && cmake --build build)
#   scripts/compare-outputs.sh record /tmp/old.manifest /tmp/old/build/clutterscope
#   scripts/build.sh && scripts/compare-outputs.sh check /tmp/old.manifest build/clutterscope
# Both passes read the samples of THIS checkout (datasets/samples, or $CLUTTERSCOPE_SAMPLES_DIR),
# copied into a scratch folder, so only the binary differs.
#
# What runs (into SCRATCH/out/NAME; every run with its default --jobs 2 given explicitly, -q /
# --quiet, stdout kept as SCRATCH/out/stdout/NAME.txt; a run that exits non-zero stops the script
# with exit 2). All with the commands' default estimator settings (one pass takes about 40 s
# on 2 shared cores, so no option is reduced):
#   report      tray6 --overlays --no-time (scripts/quickstart.sh's report, made byte-reproducible
#               by --no-time); ycbv_real --no-time
#   visibility  tray6, tray10, ycbv_real with --masks --overlays --write-bop-info; ycbv_real in
#               --mode bop19 (--masks --write-bop-info) and bop18; tray6 bop19 --delta-mm 5
#               --pixel-center integer
#   estimate    (all --no-time) tray6 --save-beliefs --confidence-radius-cm 1; tray6 with its
#               detections_test.json and --amodal-below-score 0.1; tray10 --save-beliefs; tray10
#               --observation synthetic --sensor xtion; ycbv_real (measured depth)
#   simulate    tray10 scene 0 image 0; tray6 scene 2 image 0 --compare-thresholds 0.25,2.5,25
#               --sensor xtion --seed 3
#   generate    the two commands that made tray6 and tray10 (datasets/samples/README.md); shelf
#               (2 scenes, seed 5); pile (2 scenes, seed 6, d435, duplicates and false positives)
#
# The manifest: "SHA256  PATH" per file, PATH relative to SCRATCH, sorted by PATH; lines starting
# with # are comments. It lists the outputs (SCRATCH/out) and the inputs (SCRATCH/in, the copied
# samples: a check against a manifest recorded on other samples shows them as differing inputs).
# Before hashing, a python3 filter (write_manifest below) makes the following reproducible;
# nothing else is touched:
#   - excluded: */.batch/file_digests.tsv, the resume cache of input-file hashes: it holds the
#     inputs' modification times (ns) and absolute paths, and leaves out files modified less than
#     2 s before the run (input_digest.cpp, kRacyNs), so its bytes depend on when the samples
#     were copied.
#   - normalised: every run.json (batch commands' and report's): the values of "seconds",
#     "seconds_per_image" and "images_per_second", at any depth, become null (wall times), and
#     "peak_memory_mib" (the process's), "git_commit" and "git_tree_dirty" (the build's; all
#     added after the baseline was recorded) are left out; the rest (computed/resumed/failed
#     counts, jobs, version) is compared.
#   - normalised: in every file without a NUL byte (text: JSON, CSV, TSV, HTML, SVG, ipynb,
#     stdout), the scratch folder's absolute path becomes @SCRATCH@: the dataset (and
#     --detections) paths in summary.json (visibility, estimate, report, simulate), in the
#     .batch/job.json and .report/job.json fingerprints and in report.html.
#     Binary files (PNG, binary PLY) are hashed as written.
# Environment: LC_ALL=C for every run. CLUTTERSCOPE_COMPARE_KEEP=1 keeps the scratch folder
# (it is also kept, and its path printed, when check finds differences).
set -euo pipefail

usage() {
  sed -n '5,12p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
}
[[ $# -ge 2 && $# -le 3 ]] || usage
mode="$1"
manifest="$2"
[[ "$mode" == record || "$mode" == check ]] || usage
repo="$(cd "$(dirname "$0")/.." && pwd)"
binary="${3:-$repo/build/clutterscope}"
[[ "$binary" == /* ]] || binary="$PWD/$binary"
[[ -x "$binary" ]] || { echo "compare-outputs: no executable binary at $binary" >&2; exit 2; }
samples="${CLUTTERSCOPE_SAMPLES_DIR:-$repo/datasets/samples}"
for sample in tray6 tray10 ycbv_real; do
  [[ -d "$samples/$sample" ]] || { echo "compare-outputs: no sample $samples/$sample" >&2; exit 2; }
done
if [[ "$mode" == check && ! -f "$manifest" ]]; then
  echo "compare-outputs: no manifest $manifest (write one with record)" >&2
  exit 2
fi
[[ "$manifest" == /* ]] || manifest="$PWD/$manifest"

scratch="$(mktemp -d "${TMPDIR:-/tmp}/clutterscope-compare.XXXXXX")"
keep="${CLUTTERSCOPE_COMPARE_KEEP:-0}"
cleanup() {
  if [[ "$keep" == 1 ]]; then echo "scratch kept: $scratch" >&2; else rm -rf "$scratch"; fi
}
trap cleanup EXIT
export LC_ALL=C

mkdir -p "$scratch/in" "$scratch/out/stdout" "$scratch/logs"
for sample in tray6 tray10 ycbv_real; do cp -R "$samples/$sample" "$scratch/in/$sample"; done
cd "$scratch"

# run NAME ARGS...: the binary with ARGS, stdout to out/stdout/NAME.txt, stderr to logs/NAME.txt.
run() {
  local name="$1"
  shift
  local rc=0
  nice -n 19 "$binary" "$@" >"out/stdout/$name.txt" 2>"logs/$name.txt" || rc=$?
  if [[ $rc -ne 0 ]]; then
    echo "compare-outputs: '$name' (clutterscope $*) exited $rc:" >&2
    tail -n 20 "logs/$name.txt" >&2
    exit 2
  fi
}

start=$SECONDS
# report: scripts/quickstart.sh's main job, plus --no-time.
run report_tray6 report in/tray6 --out out/report_tray6 --overlays --no-time -j 2 -q
run report_ycbv_real report in/ycbv_real --out out/report_ycbv_real --no-time -j 2 -q

bop_extras=(--masks --overlays --write-bop-info)
run visibility_tray6 visibility in/tray6 --out out/visibility_tray6 "${bop_extras[@]}" -j 2 -q
run visibility_tray10 visibility in/tray10 --out out/visibility_tray10 "${bop_extras[@]}" -j 2 -q
run visibility_ycbv_real visibility in/ycbv_real --out out/visibility_ycbv_real \
  "${bop_extras[@]}" -j 2 -q
run visibility_ycbv_real_bop19 visibility in/ycbv_real --out out/visibility_ycbv_real_bop19 \
  --mode bop19 --masks --write-bop-info -j 2 -q
run visibility_ycbv_real_bop18 visibility in/ycbv_real --out out/visibility_ycbv_real_bop18 \
  --mode bop18 --write-bop-info -j 2 -q
run visibility_tray6_bop19_integer visibility in/tray6 --out out/visibility_tray6_bop19_integer \
  --mode bop19 --delta-mm 5 --pixel-center integer --write-bop-info -j 2 -q

run estimate_tray6 estimate in/tray6 --out out/estimate_tray6 --save-beliefs \
  --confidence-radius-cm 1 --no-time -j 2 -q
run estimate_tray6_detections estimate in/tray6 --out out/estimate_tray6_detections \
  --detections in/tray6/detections_test.json --amodal-below-score 0.1 --no-time -j 2 -q
run estimate_tray10 estimate in/tray10 --out out/estimate_tray10 --save-beliefs --no-time -j 2 -q
run estimate_tray10_synthetic estimate in/tray10 --out out/estimate_tray10_synthetic \
  --observation synthetic --sensor xtion --no-time -j 2 -q
run estimate_ycbv_real estimate in/ycbv_real --out out/estimate_ycbv_real --no-time -j 2 -q

run simulate_tray10 simulate in/tray10 --scene 0 --image 0 --out out/simulate_tray10 --quiet
run simulate_tray6_compare simulate in/tray6 --scene 2 --image 0 \
  --out out/simulate_tray6_compare --compare-thresholds 0.25,2.5,25 --sensor xtion --seed 3 --quiet

# generate: the sample datasets' own commands (datasets/samples/README.md), then the other presets.
run generate_tray6 generate --out out/generate_tray6 --scenes 6 --objects 6 --max-stack 3 \
  --views 1 --hidden 1 --seed 4 --tessellation 800 --rgb --quiet
run generate_tray10 generate --out out/generate_tray10 --scenes 1 --objects 10 --max-stack 3 \
  --views 1 --hidden 2 --seed 7 --tessellation 800 --rgb --quiet
run generate_shelf generate --out out/generate_shelf --preset shelf --scenes 2 --seed 5 \
  --tessellation 400 --quiet
run generate_pile generate --out out/generate_pile --preset pile --scenes 2 --seed 6 \
  --tessellation 400 --sensor d435 --duplicates 0.1 --false-positives 0.5 --quiet
echo "compare-outputs: ran the outputs in $((SECONDS - start)) s" >&2

# The manifest of SCRATCH/out on stdout (see the header for what is excluded or normalised).
write_manifest() {
  python3 - "$scratch" <<'EOF'
import hashlib, json, os, sys

scratch = sys.argv[1]
roots = sorted({scratch, os.path.realpath(scratch)}, key=len, reverse=True)
TIMES = {"seconds", "seconds_per_image", "images_per_second"}
# Of this run's process and build (the commit differs with every commit), newer than the baseline.
MACHINE = {"peak_memory_mib", "git_commit", "git_tree_dirty"}

def drop_times(value):
    if isinstance(value, dict):
        return {k: None if k in TIMES else drop_times(v)
                for k, v in value.items() if k not in MACHINE}
    if isinstance(value, list):
        return [drop_times(v) for v in value]
    return value

print("# clutterscope compare-outputs manifest: SHA256  PATH (relative to the scratch folder)")
lines = []
walk = [w for top in ("in", "out") for w in os.walk(os.path.join(scratch, top))]
for folder, dirs, files in walk:
    for name in files:
        path = os.path.join(folder, name)
        rel = os.path.relpath(path, scratch)
        if name == "file_digests.tsv" and os.path.basename(folder) == ".batch":
            continue  # resume cache: input mtimes, absolute paths, racy entries left out
        with open(path, "rb") as f:
            data = f.read()
        if name == "run.json":
            data = (json.dumps(drop_times(json.loads(data)), indent=2) + "\n").encode()
        if b"\0" not in data:
            for root in roots:
                data = data.replace(root.encode(), b"@SCRATCH@")
        lines.append(f"{hashlib.sha256(data).hexdigest()}  {rel}")
print("\n".join(sorted(lines, key=lambda line: line.split("  ", 1)[1])))
EOF
}

if [[ "$mode" == record ]]; then
  write_manifest >"$manifest.tmp"
  mv "$manifest.tmp" "$manifest"
  echo "compare-outputs: wrote $manifest ($(grep -vc '^#' "$manifest") files)" >&2
  exit 0
fi

write_manifest >"$scratch/manifest"
rc=0
python3 - "$manifest" "$scratch/manifest" <<'EOF' || rc=$?
import sys

def read(path):
    entries = {}
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            digest, rel = line.rstrip("\n").split("  ", 1)
            entries[rel] = digest
    return entries

old, new = read(sys.argv[1]), read(sys.argv[2])
report = []
for rel in sorted(old.keys() | new.keys()):
    if rel not in new:
        report.append(f"missing (only in the manifest): {rel}")
    elif rel not in old:
        report.append(f"new (not in the manifest):      {rel}")
    elif old[rel] != new[rel]:
        report.append(f"differs:                        {rel}")
if report:
    print("\n".join(report))
    print(f"compare-outputs: {len(report)} of {len(old.keys() | new.keys())} files differ")
    sys.exit(1)
print(f"compare-outputs: identical ({len(new)} files)")
EOF
if [[ $rc -ne 0 ]]; then
  keep=1
  exit 1
fi
