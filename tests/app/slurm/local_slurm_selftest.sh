#!/usr/bin/env bash
# Self-test of local_slurm.sh: start a private one-node cluster, run a 4-task job array through
# it, check every task's output, note whether two tasks ran at once, stop the cluster.
#
#   local_slurm_selftest.sh        # exit 0 on success; KEEP=1 keeps the state folder
#
# Exits 77 (CTest: SKIP_RETURN_CODE 77) when not root or when slurm-wlm / munge are missing.
# Prints how long start, the array job and stop took. The array's tasks are done in ~4 s;
# sbatch --wait only notices at 10 s: it polls the controller 2 s, 10 s, 42 s, then every
# 32 s after submission (sbatch.c _job_wait). A test that wants to be quick can poll
# `squeue -h -j JOBID` itself after `sbatch --parsable`.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cluster=$here/local_slurm.sh

now() { date +%s.%N; }
elapsed() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f s", b - a }'; }
fail() { echo "selftest: FAIL: $*" >&2; exit 1; }

for tool in slurmctld slurmd munged sbatch; do
  command -v "$tool" >/dev/null || { echo "selftest: SKIP: no $tool" >&2; exit 77; }
done
((EUID == 0)) || { echo "selftest: SKIP: needs root" >&2; exit 77; }

dir=$(mktemp -d "${TMPDIR:-/tmp}/local_slurm.XXXXXX")
cleanup() {
  "$cluster" stop "$dir" || true
  if [[ -n ${KEEP:-} ]]; then echo "selftest: kept $dir" >&2; else rm -rf "$dir"; fi
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM   # so that CTest's or a user's kill still stops the cluster

t0=$(now)
# Two steps: eval "$(...)" alone would hide a failing start (eval "" succeeds).
exports=$("$cluster" start "$dir") || fail "local_slurm.sh start failed"
eval "$exports"
t1=$(now)
[[ ${SLURM_CONF:-} == "$dir/slurm.conf" ]] || fail "start did not print the SLURM_CONF export"

# Each task records when it started and ended; the sleep makes overlap observable.
cat >"$dir/job.sh" <<'EOF'
#!/bin/bash
start=$(date +%s.%N)
echo "task $SLURM_ARRAY_TASK_ID on $(hostname)"
sleep 1
echo "times $start $(date +%s.%N)"
EOF

sbatch --wait --quiet --array=0-3 --chdir="$dir" --output="$dir/out_%a.txt" "$dir/job.sh" ||
  fail "sbatch --wait failed (rc $?)"
t2=$(now)

host=$(hostname)
for a in 0 1 2 3; do
  out=$dir/out_$a.txt
  [[ -f $out ]] || fail "no output from task $a"
  first=$(head -n 1 "$out")
  [[ $first == "task $a on $host" ]] || fail "task $a wrote '$first'"
  grep -q '^times ' "$out" || fail "task $a did not finish: $(cat "$out")"
done

# Two tasks overlapped when one started before the other ended (CR_Core: 1 task per core).
overlap=$(cat "$dir"/out_?.txt | awk 'BEGIN { n = 0 } $1 == "times" { s[n] = $2; e[n] = $3; n++ }
  END { k = 0
        for (i = 0; i < n; i++) for (j = i + 1; j < n; j++)
          if (s[i] < e[j] && s[j] < e[i]) k++
        print k }')
if ((overlap > 0)); then
  echo "selftest: $overlap pair(s) of tasks ran at the same time" >&2
else
  echo "selftest: note: no two tasks overlapped (nproc = $(nproc))" >&2
fi

"$cluster" stop "$dir"
t3=$(now)

echo "selftest: OK: start $(elapsed "$t0" "$t1"), array job $(elapsed "$t1" "$t2")," \
  "stop $(elapsed "$t2" "$t3")" >&2
