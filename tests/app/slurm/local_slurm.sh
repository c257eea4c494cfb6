#!/usr/bin/env bash
# Start and stop a private one-node Slurm cluster on this machine, for tests.
#
#   local_slurm.sh start STATE_DIR   # prints: export SLURM_CONF=STATE_DIR/slurm.conf
#   local_slurm.sh stop  STATE_DIR   # idempotent
#
# STATE_DIR is an existing, preferably empty, folder the caller owns (e.g. from mktemp -d).
# Everything the cluster needs lives in it: its own munge key and munged (socket, pid, log,
# seed), slurm.conf, the controller's state, slurmd's spool, the daemons' pid and log files.
# Nothing in /etc is read or written, no system munged or slurm is touched, and the ports are
# picked at random among free ones, so several clusters (or the stale remains of a killed run)
# can coexist on one machine.
#
# Typical use, from a test:
#   dir=$(mktemp -d)
#   trap 'local_slurm.sh stop "$dir"; rm -rf "$dir"' EXIT
#   exports=$(local_slurm.sh start "$dir")    # fails (set -e) if the cluster did not come up;
#   eval "$exports"                           # sets SLURM_CONF for sbatch, squeue, sinfo...
#   sbatch --wait --array=0-3 --wrap '...'
#
# Needs (Debian 12): slurm-wlm (slurmctld, slurmd, client commands; 22.05) and munge, and root
# (SlurmUser=root; jobs run as their submitter). Meant for containers: no cgroups
# (proctrack/linuxproc, task/none), no accounting (so no sacct: use squeue -t all, scontrol).
# The ports are checked free when chosen; in the rare race where something else takes one
# before the daemon binds it, start fails (with the logs) and can simply be retried.
#
# Only the export line goes to stdout; progress and, on failure, the daemons' logs go to
# stderr. The daemons' stdio is redirected to files so that a caller capturing our output
# ($(...), CTest) does not wait for them.
set -euo pipefail

readonly WAIT_IDLE_S=60   # bound on waiting for the node to come up idle
readonly WAIT_STOP_S=10   # bound on waiting for a daemon to exit after SIGTERM
readonly CLUSTER_NAME=hgrasp-test

log() { echo "local_slurm: $*" >&2; }
die() { log "error: $*"; exit 1; }

usage() {
  echo "usage: $0 start|stop STATE_DIR" >&2
  exit 2
}

# ---------------------------------------------------------------------------------------------
# Helpers

# proc_stat PID: sets STAT to /proc/PID/stat ("pid (comm) state ppid ...") of a live,
# non-zombie process; fails otherwise. Builtins only, no subshell: forking is slow in some
# containers (gVisor), and cluster_pids calls this for every process.
proc_stat() {
  STAT=""
  { IFS= read -r STAT <"/proc/$1/stat"; } 2>/dev/null || return 1
  [[ ${STAT##*) } != Z* ]]   # a zombie is dead, only not yet reaped
}

# alive PIDFILE NAME: true when PIDFILE names a live process whose command is NAME (the check
# on the name guards against a recycled pid from a long-gone run).
alive() {
  local pidfile=$1 name=$2 pid STAT
  [[ -s $pidfile ]] || return 1
  { IFS= read -r pid <"$pidfile"; } 2>/dev/null || return 1
  [[ $pid =~ ^[0-9]+$ ]] && proc_stat "$pid" && [[ $STAT == *"($name) "* ]]
}

# port_free PORT: true when nothing listens on TCP PORT.
port_free() {
  local port=$1
  if command -v ss >/dev/null; then
    [[ -z $(ss -Hltn "( sport = :$port )" 2>/dev/null) ]]
  else
    if (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then return 1; fi
  fi
}

# pick_port [EXCLUDE]: a random free high port (not EXCLUDE).
pick_port() {
  local exclude=${1:-0} port i
  for i in $(seq 100); do
    port=$((20000 + (RANDOM * 32768 + RANDOM) % 40000))
    [[ $port != "$exclude" ]] && port_free "$port" && { echo "$port"; return 0; }
  done
  die "found no free TCP port"
}

# stop_daemon PIDFILE NAME: SIGTERM, then SIGKILL after WAIT_STOP_S; removes PIDFILE.
stop_daemon() {
  local pidfile=$1 name=$2 pid i
  if alive "$pidfile" "$name"; then
    pid=$(<"$pidfile")
    log "stopping $name (pid $pid)"
    kill -TERM "$pid" 2>/dev/null || true
    for ((i = 0; i < WAIT_STOP_S * 10; i++)); do
      alive "$pidfile" "$name" || break
      sleep 0.1
    done
    if alive "$pidfile" "$name"; then
      log "$name (pid $pid) ignored SIGTERM, killing it"
      kill -KILL "$pid" 2>/dev/null || true
    fi
  fi
  rm -f "$pidfile"
}

# cluster_pids DIR: the processes this cluster's jobs left behind: its slurmstepds (SLURM_CONF
# in their environment names our slurm.conf), the jobs' processes (sbatch sets
# SLURM_WORKING_CLUSTER=name:host:port:..., and our controller's port is unique among live
# clusters), and all their descendants. Never this script itself.
cluster_pids() {
  local dir=$1 port proc pid STAT ppid var
  port=$(sed -n 's/^SlurmctldPort=//p' "$dir/slurm.conf" 2>/dev/null)
  [[ -n $port ]] || return 0
  local -A keep=() parent=()
  local -a env
  for proc in /proc/[0-9]*; do
    pid=${proc#/proc/}
    [[ $pid == "$$" || $pid == "$BASHPID" ]] && continue
    proc_stat "$pid" || continue
    ppid=${STAT##*) }; ppid=${ppid#* }; parent[$pid]=${ppid%% *}
    { mapfile -d '' -t env <"$proc/environ"; } 2>/dev/null || continue
    for var in "${env[@]}"; do
      if [[ $var == "SLURM_CONF=$dir/slurm.conf" && $STAT == *"(slurmstepd) "* ]] ||
        [[ $var == "SLURM_WORKING_CLUSTER=$CLUSTER_NAME:localhost:$port:"* ]]; then
        keep[$pid]=1
        break
      fi
    done
  done
  # Add descendants until nothing changes.
  local changed=1
  while ((changed)); do
    changed=0
    for pid in "${!parent[@]}"; do
      if [[ -z ${keep[$pid]:-} && -n ${keep[${parent[$pid]}]:-} ]]; then
        keep[$pid]=1; changed=1
      fi
    done
  done
  unset "keep[$$]" "keep[$BASHPID]"
  echo "${!keep[@]}"
}

# ---------------------------------------------------------------------------------------------
# stop

do_stop() {
  local dir=$1

  # Cancel what still runs, so slurmstepd tears the jobs down cleanly (bounded wait).
  if alive "$dir/slurmctld.pid" slurmctld && [[ -f $dir/slurm.conf ]]; then
    local jobs i
    jobs=$(SLURM_CONF=$dir/slurm.conf timeout 5 squeue -h -o %A 2>/dev/null || true)
    if [[ -n $jobs ]]; then
      log "cancelling jobs: ${jobs//$'\n'/ }"
      # shellcheck disable=SC2086  # word splitting wanted: one job id per word
      SLURM_CONF=$dir/slurm.conf timeout 5 scancel $jobs 2>/dev/null || true
      for ((i = 0; i < WAIT_STOP_S * 2; i++)); do
        [[ -z $(SLURM_CONF=$dir/slurm.conf timeout 5 squeue -h -t R,CG -o %A 2>/dev/null) ]] &&
          break
        sleep 0.5
      done
    fi
  fi

  stop_daemon "$dir/slurmd.pid" slurmd
  stop_daemon "$dir/slurmctld.pid" slurmctld
  stop_daemon "$dir/munged.pid" munged

  # Whatever is left (slurmstepds and job tasks orphaned by a killed run): TERM, a short wait,
  # then KILL (slurmstepd ignores SIGTERM; normally slurmd tells it what to do).
  local pids pid left i STAT
  pids=$(cluster_pids "$dir")
  if [[ -n $pids ]]; then
    log "terminating leftover processes: $pids"
    # shellcheck disable=SC2086  # word splitting wanted: one pid per word
    kill -TERM $pids 2>/dev/null || true
    for ((i = 0; i < 30; i++)); do
      left=""
      for pid in $pids; do proc_stat "$pid" && left+=" $pid"; done
      [[ -z $left ]] && break
      sleep 0.1
    done
    if [[ -n $left ]]; then
      log "killing$left"
      # shellcheck disable=SC2086
      kill -KILL $left 2>/dev/null || true
    fi
  fi
  return 0
}

# ---------------------------------------------------------------------------------------------
# start

dump_logs() {
  local dir=$1 f
  for f in "$dir"/log/*.log; do
    [[ -f $f ]] || continue
    echo "----- $f -----" >&2
    tail -n 60 "$f" >&2
  done
}

# start_munged DIR: a private munged with its own key, socket, pid, log and seed files.
start_munged() {
  local dir=$1 i
  # munged refuses keys that others can read; 1 KiB of randomness is what mungekey makes.
  rm -f "$dir/munge/munge.key"
  dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
  chmod 0400 "$dir/munge/munge.key"

  # --force: munged wants every folder above its socket searchable by all, which a private
  # mktemp -d folder (0700, perhaps under a 0700 home) is not; only root uses this socket.
  munged --force \
    --key-file="$dir/munge/munge.key" \
    --socket="$dir/munge/munge.socket" \
    --pid-file="$dir/munged.pid" \
    --log-file="$dir/log/munged.log" \
    --seed-file="$dir/munge/munged.seed" \
    </dev/null >>"$dir/log/munged.log" 2>&1 ||
    die "munged did not start"

  # munged forks and returns once it is ready; check it round-trips a credential.
  for ((i = 0; i < 50; i++)); do
    if munge -S "$dir/munge/munge.socket" -n 2>/dev/null |
      unmunge -S "$dir/munge/munge.socket" >/dev/null 2>&1; then
      return 0
    fi
    sleep 0.1
  done
  die "munged does not answer on $dir/munge/munge.socket"
}

# write_config DIR: slurm.conf for one node (this machine) and one partition.
write_config() {
  local dir=$1 node cpus mem_mb ctld_port slurmd_port
  node=$(hostname -s)
  cpus=$(nproc)
  # RealMemory must not exceed what slurmd measures, or the node is drained: take 90 % of the
  # memory available now (in MiB).
  mem_mb=$(awk '/^MemAvailable:/ { printf "%d", $2 / 1024 * 0.9 }' /proc/meminfo)
  ctld_port=$(pick_port)
  slurmd_port=$(pick_port "$ctld_port")

  # An empty plugin stack, so nothing from /etc/slurm/plugstack.conf(.d) is loaded.
  : >"$dir/plugstack.conf"

  cat >"$dir/slurm.conf" <<EOF
# Private one-node cluster written by local_slurm.sh; everything lives under $dir.
ClusterName=$CLUSTER_NAME
SlurmctldHost=localhost
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root

# Our own munged: daemons and clients (which read this file through SLURM_CONF) talk to it.
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge/munge.socket

StateSaveLocation=$dir/ctld
SlurmdSpoolDir=$dir/slurmd
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$dir/plugstack.conf
MailProg=/bin/true

# No cgroups (this runs in containers): track processes through /proc, bind nothing.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SwitchType=switch/none

# No accounting, no slurmdbd.
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none

# Allocate cores, not whole nodes, so one task per core runs at once.
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
# A node that was down comes back as soon as its slurmd registers.
ReturnToService=2
# A cancelled job gets 5 s between SIGTERM and SIGKILL (default 30). Finished jobs stay
# visible to squeue -t all / scontrol show job for 5 min, as there is no sacct.
KillWait=5
MinJobAge=300

NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
}

do_start() {
  local dir=$1 conf=$1/slurm.conf i state

  ((EUID == 0)) || die "must run as root (slurmd launches the jobs; SlurmUser=root)"
  if alive "$dir/slurmctld.pid" slurmctld || alive "$dir/slurmd.pid" slurmd ||
    alive "$dir/munged.pid" munged; then
    die "a cluster already runs from $dir (run: $0 stop $dir)"
  fi
  # The munge socket path must fit in a sockaddr_un (108 bytes).
  ((${#dir} < 80)) || die "STATE_DIR path too long for a unix socket: $dir"
  local tool
  for tool in munged munge unmunge slurmctld slurmd sinfo; do
    command -v "$tool" >/dev/null || die "$tool not found (apt-get install slurm-wlm munge)"
  done

  # From here on, any failure shows the logs and undoes what was started.
  trap 'rc=$?; if ((rc != 0)); then log "start failed"; dump_logs "$dir";
        do_stop "$dir" || true; fi' EXIT

  mkdir -p "$dir/munge" "$dir/ctld" "$dir/slurmd" "$dir/log"
  chmod 0700 "$dir/munge"

  start_munged "$dir"
  write_config "$dir"

  # Both daemons fork into the background and write their pid files; -f names our config
  # and SLURM_CONF is set too, for anything they spawn (slurmstepd) and for sinfo below.
  # slurmctld -c: start afresh, recover no jobs from a STATE_DIR used before.
  export SLURM_CONF=$conf
  slurmctld -f "$conf" -c \
    </dev/null >>"$dir/log/slurmctld.log" 2>&1 || die "slurmctld did not start"
  slurmd -f "$conf" \
    </dev/null >>"$dir/log/slurmd.log" 2>&1 || die "slurmd did not start"

  # Wait until the node reports idle (bounded), failing fast if a daemon died.
  local node deadline=$((SECONDS + WAIT_IDLE_S))
  node=$(hostname -s)
  for ((i = 0; SECONDS < deadline; i++)); do
    state=$(timeout 5 sinfo -h -N -n "$node" -o %T 2>/dev/null || true)
    [[ $state == idle ]] && break
    if ((i > 10)); then   # give the pid files a moment to appear
      alive "$dir/slurmctld.pid" slurmctld || die "slurmctld exited"
      alive "$dir/slurmd.pid" slurmd || die "slurmd exited"
    fi
    sleep 0.2
  done
  [[ $state == idle ]] || die "node $node not idle after ${WAIT_IDLE_S} s (state: '${state}')"

  log "cluster up: node $node idle, config $conf"
  echo "export SLURM_CONF=$conf"
}

# ---------------------------------------------------------------------------------------------

(($# == 2)) || usage
cmd=$1
[[ -d $2 ]] || die "STATE_DIR $2 is not a folder"
state_dir=$(cd "$2" && pwd -P)   # absolute: it goes into slurm.conf

case $cmd in
  start) do_start "$state_dir" ;;
  stop) do_stop "$state_dir" ;;
  *) usage ;;
esac
