#!/usr/bin/env bash
# `hgrasp sweep --slurm` for real: a private one-node Slurm (local_slurm.sh: slurmctld, slurmd
# and munged from Debian's packages, on localhost) runs a small sweep as a job array of two
# shards; `--slurm-wait` waits for it and merges. The merged result must equal the same sweep
# run here with --jobs 2, timings and paths aside.
#
#   sweep_slurm_test.sh HGRASP_BINARY
#
# Needs root (Slurm's daemons); exits 77 (CTest: skipped) otherwise. A missing Slurm or munge is
# a failure: they are dependencies (the Makefile installs them).
set -euo pipefail

hgrasp=${1:?usage: sweep_slurm_test.sh HGRASP_BINARY}
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cluster=$here/local_slurm.sh
fail() { echo "sweep_slurm_test: FAIL: $*" >&2; exit 1; }

((EUID == 0)) || { echo "sweep_slurm_test: SKIP: Slurm's daemons need root" >&2; exit 77; }
for tool in slurmctld slurmd munged sbatch squeue; do
  command -v "$tool" >/dev/null ||
    fail "no $tool: install Debian's slurm-wlm and munge (make deps)"
done

dir=$(mktemp -d "${TMPDIR:-/tmp}/sweep_slurm.XXXXXX")
cleanup() { "$cluster" stop "$dir/cluster" || true; rm -rf "$dir"; }
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
mkdir "$dir/cluster"
exports=$("$cluster" start "$dir/cluster") || fail "local_slurm.sh start failed"
eval "$exports"

scenes=(--family random_boxes --seeds 21..23 --stage model)
t0=$(date +%s.%N)
"$hgrasp" sweep "${scenes[@]}" --out "$dir/slurm" --slurm --slurm-wait --shards 2 ||
  fail "the Slurm sweep failed (exit $?)"
t1=$(date +%s.%N)
"$hgrasp" sweep "${scenes[@]}" --out "$dir/local" --jobs 2 || fail "the local sweep failed"
t2=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" -v c="$t2" \
  'BEGIN { printf "sweep_slurm_test: Slurm sweep %.1f s, local sweep %.1f s\n", b - a, c - b }'

# Both shards ran, each its own scenes.
for shard in 0 1; do
  [[ -s $dir/slurm/slurm/shard_$shard.log ]] || fail "no log of array task $shard"
done

/usr/bin/python3 - "$dir/slurm/summary.json" "$dir/local/summary.json" <<'PY'
import json, sys
def rows(path):
    s = json.load(open(path))
    assert s["sweep"]["complete"], path
    out = []
    for r in s["scenes"]:
        for k in ("wall_s", "file", "dir", "pictures", "score"):
            r.pop(k, None)
        out.append(r)
    return out
slurm, local = rows(sys.argv[1]), rows(sys.argv[2])
assert len(slurm) == 3, len(slurm)
assert [r["scene"] for r in slurm] == ["random_21", "random_22", "random_23"]
for a, b in zip(slurm, local):
    assert a == b, "%s differs:\n%s\n%s" % (a["scene"], json.dumps(a), json.dumps(b))
print("sweep_slurm_test: the merged Slurm sweep equals the local one (%d scenes)" % len(slurm))
PY
