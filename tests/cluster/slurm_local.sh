#!/usr/bin/env bash
# slurm_local.sh - throw-away single-node Slurm cluster on localhost, for tests.
#
#   slurm_local.sh install        apt-get the Debian 12 packages (idempotent)
#   slurm_local.sh start DIR      munged + slurmctld + slurmd, all state under DIR;
#                                 prints `export SLURM_CONF=...` to eval; exit 77
#                                 (= SKIP) with "slurm_local: cannot start: ..."
#   slurm_local.sh stop DIR       stop what `start DIR` started (idempotent)
#   slurm_local.sh selftest       start, run/cancel job arrays, stop; PASS/FAIL
#
# Written for Debian 12 (slurm-wlm 22.05, munge 0.5.15), run as root, without
# systemd: daemons are started directly and never read /etc/slurm or /etc/munge.
# Env: SLURM_LOCAL_CTLD_PORT (16817), SLURM_LOCAL_SLURMD_PORT (16818),
#      SLURM_LOCAL_START_TIMEOUT (30 s until the node must be idle).
set -euo pipefail

PKGS=(slurmctld slurmd slurm-client munge)
CTLD_PORT=${SLURM_LOCAL_CTLD_PORT:-16817}
SLURMD_PORT=${SLURM_LOCAL_SLURMD_PORT:-16818}
START_TIMEOUT=${SLURM_LOCAL_START_TIMEOUT:-30}
SKIP=77
# Daemons live in /usr/sbin, which a non-login root shell may lack in PATH.
export PATH="$PATH:/usr/sbin:/sbin"

log() { echo "slurm_local: $*" >&2; }

usage() {
  echo "usage: $0 install | start DIR | stop DIR | selftest" >&2
  exit 2
}

# ---------------------------------------------------------------- install ---
pkg_installed() {
  [ "$(dpkg-query -W -f='${db:Status-Status}' "$1" 2>/dev/null)" = installed ]
}

cmd_install() {
  local missing=() p
  for p in "${PKGS[@]}"; do pkg_installed "$p" || missing+=("$p"); done
  if [ ${#missing[@]} -eq 0 ]; then
    log "already installed: ${PKGS[*]}"
    return 0
  fi
  [ "$(id -u)" -eq 0 ] || { log "install needs root"; return 1; }
  log "installing: ${PKGS[*]} (+ deps liblua5.1-0 slurm-wlm-basic-plugins)"
  # Keep maintainer scripts from starting the packaged services: without
  # systemd invoke-rc.d already declines (unknown runlevel), but a temporary
  # policy-rc.d makes that explicit wherever the image has none of its own.
  local policy=/usr/sbin/policy-rc.d aptlog
  aptlog=$(mktemp)
  # Traps expand now: the locals are gone when the script exits.
  # shellcheck disable=SC2064
  if [ ! -e "$policy" ]; then
    trap "rm -f '$policy' '$aptlog'" EXIT
    printf '#!/bin/sh\nexit 101\n' >"$policy"
    chmod 755 "$policy"
  else
    trap "rm -f '$aptlog'" EXIT
  fi
  apt_install() {
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
      --no-install-recommends "${PKGS[@]}" >>"$aptlog" 2>&1
  }
  # Fresh containers have no package lists; only then pay for an update.
  local rc=0
  apt_install || { apt-get update -qq >>"$aptlog" 2>&1 && apt_install; } || rc=$?
  if [ $rc -ne 0 ]; then
    tail -n 20 "$aptlog" >&2
    log "apt-get install failed (rc=$rc)"
    return $rc
  fi
  log "installed: ${PKGS[*]}"
}

# ------------------------------------------------------------ pid helpers ---
# pid from FILE if that process is alive and its command line mentions DIR
# (guards against a stale pid file whose pid was reused by something else).
live_pid() {
  local file=$1 dir=$2 pid
  [ -s "$file" ] || return 1
  pid=$(tr -dc 0-9 <"$file")
  [ -n "$pid" ] && [ -r "/proc/$pid/cmdline" ] || return 1
  tr '\0' ' ' <"/proc/$pid/cmdline" | grep -qF -- "$dir/" || return 1
  echo "$pid"
}

# True while pid $1 runs. Zombies count as gone: the daemons are reparented
# to PID 1, which in containers may reap them late (or never).
running() {
  [ -r "/proc/$1/status" ] && ! grep -q '^State:[[:space:]]*Z' "/proc/$1/status" 2>/dev/null
}

# SIGTERM the pids, wait up to $1 s, then SIGKILL the survivors.
kill_wait() {
  local secs=$1 p i alive
  shift
  [ $# -gt 0 ] || return 0
  kill -TERM "$@" 2>/dev/null || true
  for ((i = 0; i < secs * 10; i++)); do
    alive=
    for p in "$@"; do running "$p" && alive=1; done
    [ -n "$alive" ] || return 0
    sleep 0.1
  done
  kill -KILL "$@" 2>/dev/null || true
}

# Pid plus all its descendants (job processes under a slurmstepd).
tree_pids() {
  local p
  echo "$1"
  for p in $(ps -o pid= --ppid "$1" 2>/dev/null); do tree_pids "$p"; done
}

# slurmstepd processes of the cluster in DIR. Their environment is
# overwritten by the process title, but they inherit slurmd's log file.
stepd_pids() {
  local dir=$1 p fd
  for p in $(ps -e -o pid= -o comm= | awk '$2 == "slurmstepd" {print $1}'); do
    for fd in /proc/"$p"/fd/*; do
      if [ "$(readlink "$fd" 2>/dev/null)" = "$dir/slurmd.log" ]; then
        echo "$p"
        break
      fi
    done
  done
  return 0
}

# ------------------------------------------------------------------- stop ---
cmd_stop() {
  local dir=$1 pid pids=() p
  [ -d "$dir" ] || return 0
  # Cancel jobs while the controller is up, so job processes do not outlive it.
  if pid=$(live_pid "$dir/slurmctld.pid" "$dir") && [ -f "$dir/slurm.conf" ]; then
    local jobs
    jobs=$(SLURM_CONF=$dir/slurm.conf timeout 5 squeue -h -o %i 2>/dev/null || true)
    if [ -n "$jobs" ]; then
      # shellcheck disable=SC2086
      SLURM_CONF=$dir/slurm.conf timeout 5 scancel $jobs 2>/dev/null || true
      for ((p = 0; p < 50; p++)); do
        [ -z "$(stepd_pids "$dir")" ] && break
        sleep 0.1
      done
    fi
  fi
  # slurmd before slurmctld (no node-down noise), munged last (both use it).
  for p in slurmd slurmctld; do
    pid=$(live_pid "$dir/$p.pid" "$dir") && pids+=("$pid")
  done
  kill_wait 10 "${pids[@]}"
  # Leftover steps (slurmd killed hard, or scancel failed) and their jobs.
  pids=()
  for p in $(stepd_pids "$dir"); do
    mapfile -t -O ${#pids[@]} pids < <(tree_pids "$p")
  done
  [ ${#pids[@]} -eq 0 ] || kill -KILL "${pids[@]}" 2>/dev/null || true
  pids=()
  pid=$(live_pid "$dir/munged.pid" "$dir") && pids+=("$pid")
  kill_wait 5 "${pids[@]}"
  rm -f "$dir/slurmd.pid" "$dir/slurmctld.pid" "$dir/munged.pid"
  return 0
}

# ------------------------------------------------------------------ start ---
START_DIR=
STARTED=
# Print the reason (one line) and a log tail, undo the start, exit 77.
cannot_start() {
  local reason=$1 logf=${2:-}
  echo "slurm_local: cannot start: $reason" >&2
  if [ -n "$logf" ] && [ -s "$logf" ]; then
    echo "--- last lines of $logf:" >&2
    tail -n 15 "$logf" >&2
  fi
  [ -z "$STARTED" ] || cmd_stop "$START_DIR" || true
  exit $SKIP
}

# True if something listens on TCP port $1 on localhost.
port_busy() {
  if command -v ss >/dev/null; then
    [ -n "$(ss -Htln "sport = :$1" 2>/dev/null)" ]
  else
    (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null
  fi
}

# Wait up to $2 s for pid file $1 (written by a daemonizing process).
wait_pidfile() {
  local file=$1 secs=$2 dir=$3 i
  for ((i = 0; i < secs * 10; i++)); do
    live_pid "$file" "$dir" >/dev/null && return 0
    sleep 0.1
  done
  return 1
}

write_conf() {
  local dir=$1 host=$2 cpus=$3 mem=$4
  cat >"$dir/slurm.conf" <<EOF
# Generated by slurm_local.sh: single-node throw-away cluster, state in $dir
ClusterName=slurmlocal
# Address given explicitly so no DNS / /etc/hosts entry is needed.
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$CTLD_PORT
SlurmdPort=$SLURMD_PORT
SlurmUser=root
SlurmdUser=root
# Both daemons and all client commands use the munged started in $dir.
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$dir/munge.socket
# No cgroups: track processes through /proc, no task containment/accounting.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
# Finished jobs are appended here (JobState=COMPLETED/CANCELLED/...).
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/jobcomp.log
MpiDefault=none
MailProg=/bin/true
PlugStackConfig=$dir/plugstack.conf
# CPUs are the only consumable: any two 1-CPU jobs share a 2-CPU node, and
# jobs without --mem do not grab all the node's memory.
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
# Start jobs right after submit/completion instead of batching them.
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0,sched_interval=5
# Keep finished jobs visible to 'scontrol show job' for 10 minutes.
MinJobAge=600
# Cancelled jobs get SIGKILL 2 s after SIGTERM (default 30).
KillWait=2
InactiveLimit=0
ReturnToService=2
SlurmdTimeout=30
MessageTimeout=10
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
NodeName=$host NodeAddr=127.0.0.1 NodeHostname=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  : >"$dir/plugstack.conf"
}

cmd_start() {
  local dir=$1
  # slurm.conf cannot quote paths, so no blanks either.
  case "$dir" in
    *[[:space:]]*) log "start: DIR must not contain blanks"; exit 2 ;;
    /*) ;;
    *) log "start: DIR must be an absolute path"; exit 2 ;;
  esac
  START_DIR=$dir
  [ "$(id -u)" -eq 0 ] || cannot_start "must run as root (SlurmUser=root)"
  local b
  for b in munged mungekey munge slurmctld slurmd sinfo sbatch; do
    command -v "$b" >/dev/null ||
      cannot_start "$b not found (run: $0 install)"
  done
  mkdir -p "$dir"
  # Clean up a previous (possibly killed) run from the same DIR, then start
  # from empty state so old jobs are neither recovered nor requeued.
  cmd_stop "$dir"
  rm -rf "$dir/state" "$dir/spool" "$dir/munge.socket" "$dir/munge.socket.lock" \
    "$dir"/{munged,slurmctld,slurmd,jobcomp}.log "$dir"/warmup.{out,err}
  mkdir -p "$dir/state" "$dir/spool"
  local p
  for p in "$CTLD_PORT" "$SLURMD_PORT"; do
    ! port_busy "$p" || cannot_start "TCP port $p is in use (set SLURM_LOCAL_CTLD_PORT / SLURM_LOCAL_SLURMD_PORT)"
  done

  local host cpus mem
  host=$(hostname -s 2>/dev/null || uname -n | cut -d. -f1)
  cpus=$(nproc)
  # RealMemory a bit below the machine's: slurmd drains a node that reports
  # less memory than configured.
  mem=$(awk '/^MemTotal:/ {printf "%d", $2 / 1024 * 0.9}' /proc/meminfo)
  write_conf "$dir" "$host" "$cpus" "$mem"
  STARTED=1

  # munged: --force because DIR may not be world-searchable (mktemp -d).
  [ -s "$dir/munge.key" ] || mungekey --create --keyfile="$dir/munge.key" ||
    cannot_start "mungekey failed"
  chmod 600 "$dir/munge.key"
  munged --force --socket="$dir/munge.socket" --key-file="$dir/munge.key" \
    --pid-file="$dir/munged.pid" --log-file="$dir/munged.log" \
    --seed-file="$dir/munged.seed" </dev/null >>"$dir/munged.log" 2>&1 ||
    cannot_start "munged failed to start" "$dir/munged.log"
  wait_pidfile "$dir/munged.pid" 5 "$dir" ||
    cannot_start "munged did not write its pid file" "$dir/munged.log"
  munge -S "$dir/munge.socket" -n </dev/null | unmunge -S "$dir/munge.socket" >/dev/null 2>&1 ||
    cannot_start "munge credential round trip failed" "$dir/munged.log"

  # Slurm daemons fork into the background and write their pid files; their
  # stdio must not hold the caller's $(...) pipe open.
  export SLURM_CONF=$dir/slurm.conf
  slurmctld -f "$dir/slurm.conf" </dev/null >>"$dir/slurmctld.log" 2>&1 ||
    cannot_start "slurmctld exited with an error" "$dir/slurmctld.log"
  wait_pidfile "$dir/slurmctld.pid" 10 "$dir" ||
    cannot_start "slurmctld did not stay up" "$dir/slurmctld.log"
  slurmd -f "$dir/slurm.conf" -N "$host" </dev/null >>"$dir/slurmd.log" 2>&1 ||
    cannot_start "slurmd exited with an error" "$dir/slurmd.log"
  wait_pidfile "$dir/slurmd.pid" 10 "$dir" ||
    cannot_start "slurmd did not stay up" "$dir/slurmd.log"

  # The node must register and turn idle; down/drain shows up in sinfo.
  local i state=
  for ((i = 0; i < START_TIMEOUT * 5; i++)); do
    state=$(timeout 5 sinfo -h -N -n "$host" -o %T 2>/dev/null || true)
    [ "$state" = idle ] && break
    live_pid "$dir/slurmctld.pid" "$dir" >/dev/null ||
      cannot_start "slurmctld died" "$dir/slurmctld.log"
    live_pid "$dir/slurmd.pid" "$dir" >/dev/null ||
      cannot_start "slurmd died" "$dir/slurmd.log"
    sleep 0.2
  done
  if [ "$state" != idle ]; then
    local reason
    reason=$(timeout 5 sinfo -h -N -n "$host" -o %E 2>/dev/null || true)
    cannot_start "node $host not idle after ${START_TIMEOUT}s (state '${state:-?}'${reason:+, reason: $reason})" "$dir/slurmd.log"
  fi

  # End-to-end check with a warm-up job: proves job launch works here
  # (munge credentials, slurmstepd) and absorbs slurmctld's ~3 s start-up
  # hold before its first scheduling pass, so callers' jobs start at once.
  local wj
  wj=$(timeout 15 sbatch --parsable -J slurm_local_warmup --chdir="$dir" \
    -o "$dir/warmup.out" --wrap 'echo ok' 2>"$dir/warmup.err") ||
    cannot_start "sbatch of the warm-up job failed: $(head -n1 "$dir/warmup.err")" "$dir/slurmctld.log"
  for ((i = 0; i < START_TIMEOUT * 5; i++)); do
    [ -z "$(timeout 5 squeue -h -j "$wj" -o %i 2>/dev/null)" ] && break
    sleep 0.2
  done
  [ "$(cat "$dir/warmup.out" 2>/dev/null)" = ok ] ||
    cannot_start "warm-up job $wj did not run within ${START_TIMEOUT}s ($(timeout 5 squeue -h -j "$wj" -o '%T %R' 2>/dev/null))" "$dir/slurmd.log"
  log "cluster up in $dir (node $host, $cpus CPUs, ports $CTLD_PORT/$SLURMD_PORT)"
  echo "export SLURM_CONF=$dir/slurm.conf"
}

# --------------------------------------------------------------- selftest ---
now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN {printf "%.2f", b - a}'; }

# Wait up to $2 s until squeue no longer lists job $1.
wait_gone() {
  local i
  for ((i = 0; i < $2 * 5; i++)); do
    [ -z "$(squeue -h -j "$1" -o %i 2>/dev/null)" ] && return 0
    sleep 0.2
  done
  return 1
}

job_state() {
  scontrol show job "$1" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | head -n1 | cut -d= -f2
}

cmd_selftest() {
  local t0 tmp out fails=0 j1 j2 j3 t_sub t_start lat i st self
  t0=$(now)
  self=$(readlink -f "$0")
  tmp=$(mktemp -d /tmp/slurm_local.XXXXXX)
  out=$tmp/out
  mkdir -p "$out"
  # shellcheck disable=SC2064
  trap "bash '$self' stop '$tmp/cluster'; rm -rf '$tmp'" EXIT
  fail() { echo "FAIL: $*"; fails=$((fails + 1)); }

  local env rc=0
  env=$(bash "$self" start "$tmp/cluster") || rc=$?
  if [ $rc -ne 0 ]; then
    echo "SKIP: slurm_local start failed (rc=$rc)"
    return $rc
  fi
  eval "$env"
  echo "started in $(secs "$t0" "$(now)") s: $env"

  # 1) two-element array; each element records the array variables.
  t_sub=$(now)
  j1=$(sbatch --parsable --array=0-1 --cpus-per-task=1 --mem=100M -o "$out/j1_%a.log" \
    --wrap "echo \"\$SLURM_ARRAY_TASK_ID count=\${SLURM_ARRAY_TASK_COUNT-unset} min=\${SLURM_ARRAY_TASK_MIN-unset} max=\${SLURM_ARRAY_TASK_MAX-unset}\" >$out/a_\$SLURM_ARRAY_TASK_ID; date +%s.%N >$out/start_\$SLURM_ARRAY_TASK_ID; sleep 2; date +%s.%N >$out/end_\$SLURM_ARRAY_TASK_ID")
  wait_gone "$j1" 30 || fail "array $j1 still queued after 30 s"
  for i in 0 1; do
    [ "$(cat "$out/a_$i" 2>/dev/null)" = "$i count=2 min=0 max=1" ] ||
      fail "element $i wrote '$(cat "$out/a_$i" 2>/dev/null)', want '$i count=2 min=0 max=1'"
    st=$(job_state "${j1}_$i")
    [ "$st" = COMPLETED ] || fail "${j1}_$i state '$st', want COMPLETED"
  done
  if [ -s "$out/start_0" ] && [ -s "$out/start_1" ]; then
    t_start=$(sort -n "$out/start_0" "$out/start_1" | head -n1)
    lat=$(secs "$t_sub" "$t_start")
    echo "array 1: submit -> first start $lat s, elements started $(secs "$(cat "$out/start_0")" "$(cat "$out/start_1")") s apart, done after $(secs "$t_sub" "$(now)") s"
    # With 2+ CPUs both 1-CPU elements must overlap in time.
    if [ "$(nproc)" -ge 2 ] && awk -v s0="$(cat "$out/start_0")" -v s1="$(cat "$out/start_1")" \
      -v e0="$(cat "$out/end_0")" -v e1="$(cat "$out/end_1")" 'BEGIN {exit !(s0 >= e1 || s1 >= e0)}'; then
      fail "array elements did not run concurrently"
    fi
  fi

  # 2) cancel element 1 while it runs; element 0 must still complete.
  t_sub=$(now)
  j2=$(sbatch --parsable --array=0-1 --cpus-per-task=1 --mem=100M -o "$out/j2_%a.log" \
    --wrap "if [ \"\$SLURM_ARRAY_TASK_ID\" = 1 ]; then sleep 60; fi; echo ok >$out/b_\$SLURM_ARRAY_TASK_ID")
  for ((i = 0; i < 100; i++)); do
    [ "$(squeue -h -j "${j2}_1" -o %T 2>/dev/null)" = RUNNING ] && break
    sleep 0.2
  done
  [ "$(squeue -h -j "${j2}_1" -o %T 2>/dev/null)" = RUNNING ] ||
    fail "${j2}_1 not RUNNING 20 s after submit"
  echo "array 2: element 1 running after $(secs "$t_sub" "$(now)") s; scancel ${j2}_1"
  scancel "${j2}_1"
  wait_gone "$j2" 20 || fail "array $j2 still queued 20 s after scancel"
  st=$(job_state "${j2}_1")
  [ "$st" = CANCELLED ] || fail "${j2}_1 state '$st', want CANCELLED"
  st=$(job_state "${j2}_0")
  [ "$st" = COMPLETED ] || fail "${j2}_0 state '$st', want COMPLETED"
  [ -f "$out/b_0" ] || fail "element 0 of $j2 did not write its output"
  [ ! -f "$out/b_1" ] || fail "cancelled element 1 of $j2 wrote its output"
  echo "array 2: done after $(secs "$t_sub" "$(now)") s"
  if sacct -n -X -j "$j2" -o JobID,State >"$tmp/sacct.txt" 2>&1; then
    echo "sacct: $(tr -s ' \n' ' ' <"$tmp/sacct.txt")"
  else
    echo "sacct unavailable: $(head -n1 "$tmp/sacct.txt")"
  fi

  # 3) resubmit the cancelled element alone.
  t_sub=$(now)
  j3=$(sbatch --parsable --array=1 -o "$out/j3_%a.log" \
    --wrap "echo \"\$SLURM_ARRAY_TASK_ID count=\${SLURM_ARRAY_TASK_COUNT-unset} min=\${SLURM_ARRAY_TASK_MIN-unset}\" >$out/c_\$SLURM_ARRAY_TASK_ID")
  wait_gone "$j3" 20 || fail "resubmitted $j3 still queued after 20 s"
  [ "$(cat "$out/c_1" 2>/dev/null)" = "1 count=1 min=1" ] ||
    fail "resubmitted element wrote '$(cat "$out/c_1" 2>/dev/null)', want '1 count=1 min=1'"
  st=$(job_state "${j3}_1")
  [ "$st" = COMPLETED ] || fail "${j3}_1 state '$st', want COMPLETED"
  echo "array 3 (resubmit): done after $(secs "$t_sub" "$(now)") s"

  local t_stop
  t_stop=$(now)
  bash "$self" stop "$tmp/cluster"
  echo "stopped in $(secs "$t_stop" "$(now)") s"
  if [ $fails -eq 0 ]; then
    echo "PASS (total $(secs "$t0" "$(now)") s)"
  else
    echo "FAIL: $fails check(s) failed (total $(secs "$t0" "$(now)") s)"
    return 1
  fi
}

case "${1:-}" in
  install) [ $# -eq 1 ] || usage; cmd_install ;;
  start) [ $# -eq 2 ] || usage; cmd_start "$2" ;;
  stop) [ $# -eq 2 ] || usage; cmd_stop "$2" ;;
  selftest) [ $# -eq 1 ] || usage; cmd_selftest ;;
  *) usage ;;
esac
