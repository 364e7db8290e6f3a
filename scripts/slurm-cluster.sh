#!/usr/bin/env bash
# Starts, stops and reports a single-node Slurm cluster on this machine (localhost), for the test
# suite and for trying vtex's Slurm support without a real cluster. Run as root.
#   bash scripts/slurm-cluster.sh start DIR    install slurm-wlm and munge if missing, start
#       munged if it is not answering, write DIR/slurm.conf, start slurmctld and slurmd, wait
#       (60 s at most) until the node is idle, then print `export SLURM_CONF=DIR/slurm.conf`
#       on stdout; use it as   eval "$(bash scripts/slurm-cluster.sh start DIR)"
#   bash scripts/slurm-cluster.sh stop DIR     cancel this cluster's jobs, stop slurmd then
#       slurmctld and wait for them to exit (exit 0 if they were not running)
#   bash scripts/slurm-cluster.sh status DIR   print `running` or `stopped` (exit 0 either way)
# Everything the cluster writes (slurm.conf, state, spool, pid files, logs: slurmctld.log,
# slurmd.log, jobcomp.log) is under DIR; delete DIR after a stop for a clean slate (job IDs and
# finished jobs otherwise carry over to the next start). `start` on a running DIR only says so
# and prints the export line again.
# The node has at least 8 job slots (on this 2-core machine: 8 "cores", with
# SlurmdParameters=config_overrides so that slurmd accepts more than it has) and the machine's
# memory, so several small jobs run at once and --mem works; jobs without --mem get 1/8 of it
# each. One partition, `vtex`, the default. No accounting (no sacct); finished jobs stay visible
# to squeue/scontrol for 10 minutes (MinJobAge=600).
# munged is started if needed and left running by `stop`: other clusters on this machine may use
# it. Slurm's default ports (6817 slurmctld, 6818 slurmd) are used, so only one such cluster runs
# on a machine at a time.
# This is for one machine only: on a real cluster Slurm is already set up by its administrators
# and vtex uses that one (see docs/cluster.md).
set -euo pipefail

usage() {
    echo "usage: bash ${BASH_SOURCE[0]} start|stop|status DIR" >&2
    exit 2
}
(($# == 2)) || usage
cmd=$1
case $cmd in start | stop | status) ;; *) usage ;; esac
[[ -n $2 ]] || usage
if [[ $cmd == start ]]; then
    mkdir -p "$2"
fi
if [[ -d $2 ]]; then
    dir=$(cd "$2" && pwd)
else
    dir=$2 # stop/status on a DIR that never existed: nothing runs there
fi
conf=$dir/slurm.conf

say() { echo "slurm-cluster: $*" >&2; }

# The pid in DIR/NAME.pid if that process is alive and is NAME, else nothing.
daemon_pid() {
    local pid
    pid=$(cat "$dir/$1.pid" 2>/dev/null) || return 1
    [[ $pid =~ ^[0-9]+$ ]] || return 1
    [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$1" ]] || return 1
    echo "$pid"
}

# Sends SIGTERM to daemon NAME and waits (30 s, then SIGKILL) until it has exited.
stop_daemon() {
    local pid i
    pid=$(daemon_pid "$1") || return 0
    kill -TERM "$pid" 2>/dev/null || return 0
    for ((i = 0; i < 300; i++)); do
        [[ -e /proc/$pid ]] && [[ $(cat "/proc/$pid/comm" 2>/dev/null) == "$1" ]] || return 0
        sleep 0.1
    done
    say "$1 (pid $pid) did not exit 30 s after SIGTERM; killing it"
    kill -KILL "$pid" 2>/dev/null || true
    for ((i = 0; i < 50; i++)); do
        [[ -e /proc/$pid ]] || return 0
        sleep 0.1
    done
}

# The slurmstepd processes of this cluster's jobs (they carry its SLURM_CONF in their environment).
our_steps() {
    local p
    for p in $(pgrep -x slurmstepd 2>/dev/null || true); do
        if tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qxF "SLURM_CONF=$conf"; then
            echo "$p"
        fi
    done
}

stop_cluster() {
    local i jobs
    if daemon_pid slurmctld >/dev/null && daemon_pid slurmd >/dev/null; then
        # Cancel the jobs first, so that their processes end with them rather than outlive slurmd.
        jobs=$(SLURM_CONF=$conf timeout 10 squeue -h -o %i 2>/dev/null) || true
        if [[ -n $jobs ]]; then
            # shellcheck disable=SC2086 # one job ID a word
            SLURM_CONF=$conf timeout 10 scancel --full $jobs >/dev/null 2>&1 || true
            for ((i = 0; i < 100; i++)); do
                [[ -n $(our_steps) ]] || break
                sleep 0.1
            done
        fi
    fi
    stop_daemon slurmd
    # Steps that outlived slurmd.
    for i in $(our_steps); do
        kill -KILL "$i" 2>/dev/null || true
    done
    stop_daemon slurmctld
}

is_running() {
    daemon_pid slurmctld >/dev/null && daemon_pid slurmd >/dev/null
}

# Fails the start: the reason, the tail of each LOG given, stop what this run started, exit 1.
fail() {
    local log
    say "$1"
    shift
    for log in "$@"; do
        if [[ -s $log ]]; then
            echo "--- last lines of $log:" >&2
            tail -n 12 "$log" >&2
        fi
    done
    stop_cluster
    exit 1
}

case $cmd in
status)
    if is_running; then echo running; else echo stopped; fi
    exit 0
    ;;
stop)
    stop_cluster
    exit 0
    ;;
esac

# ---- start ----------------------------------------------------------------------------------
if [[ $(id -u) -ne 0 ]]; then
    say "must run as root (it starts munged, slurmctld and slurmd)"
    exit 1
fi
if is_running && [[ -f $conf ]]; then
    say "already running in $dir"
    echo "export SLURM_CONF=$conf"
    exit 0
fi
# One daemon left over from an earlier run: start again from nothing.
stop_cluster

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null; then
    say "installing slurm-wlm and munge (apt-get)"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >&2 || true
    if ! apt-get install -y -qq --no-install-recommends slurm-wlm munge >"$dir/apt.log" 2>&1; then
        say "apt-get install slurm-wlm munge failed"
        tail -n 15 "$dir/apt.log" >&2
        exit 1
    fi
fi

# munge: Slurm's authentication. Started here only if it is not already answering.
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    if [[ ! -s /etc/munge/munge.key ]]; then
        runuser -u munge -- mungekey --create >/dev/null 2>&1 ||
            fail "no /etc/munge/munge.key and mungekey --create failed"
    fi
    mkdir -p /run/munge
    chown munge:munge /run/munge
    chmod 0755 /run/munge
    if ! runuser -u munge -- /usr/sbin/munged </dev/null >/dev/null 2>&1; then
        fail "munged failed to start" /var/log/munge/munged.log
    fi
    ok=0
    for ((i = 0; i < 50; i++)); do
        if munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then ok=1 && break; fi
        sleep 0.1
    done
    ((ok)) || fail "munged started but 'munge -n | unmunge' fails" /var/log/munge/munged.log
fi

# The node as slurmd sees it: its sockets and memory go into slurm.conf.
host=$(hostname -s)
hw=$(slurmd -C 2>/dev/null | head -n 1) || true
field() { sed -n "s/.*\b$1=\([0-9]*\).*/\1/p" <<<"$hw"; }
boards=$(field Boards) sockets=$(field SocketsPerBoard) cores=$(field CoresPerSocket)
threads=$(field ThreadsPerCore) mem=$(field RealMemory)
[[ -n $boards && -n $sockets && -n $cores && -n $threads && -n $mem ]] ||
    fail "cannot read the node's topology from 'slurmd -C' (got: ${hw:-nothing})"
# At least 8 job slots. slurmctld resets a CPUs= that is not Sockets*CoresPerSocket*ThreadsPerCore
# (and every client then prints that error), and a core never holds two jobs once ThreadsPerCore
# is above 1, so the slots are cores: the sockets of `slurmd -C` with enough cores each, one
# thread a core (1 socket x 8 cores here).
real_cpus=$((boards * sockets * cores * threads))
slots=$((real_cpus > 8 ? real_cpus : 8))
cores=$(((slots + boards * sockets - 1) / (boards * sockets)))
threads=1
cpus=$((boards * sockets * cores))
for port in 6817 6818; do
    if ss -Htln "sport = :$port" 2>/dev/null | grep -q .; then
        fail "port $port is already in use (another Slurm cluster on this machine?)"
    fi
done

mkdir -p "$dir/state" "$dir/spool"
cat >"$conf" <<EOF
# Single-node test cluster written by scripts/slurm-cluster.sh; rewritten by each start.
ClusterName=vtex
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
SwitchType=switch/none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/jobcomp.log
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
DefMemPerCPU=$((mem / cpus))
SchedulerType=sched/backfill
SchedulerParameters=sched_interval=1,bf_interval=1
DependencyParameters=kill_invalid_depend
MailProg=/bin/true
ReturnToService=2
MinJobAge=600
KillWait=5
InactiveLimit=0
SlurmdParameters=config_overrides
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus Boards=$boards SocketsPerBoard=$sockets CoresPerSocket=$cores ThreadsPerCore=$threads RealMemory=$mem State=UNKNOWN
PartitionName=vtex Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF

export SLURM_CONF=$conf
# Both daemonise; what they print (config errors, before their logs open) goes to DIR/*.out, so
# that a caller's $(...) does not wait on them.
rm -f "$dir/slurmctld.pid" "$dir/slurmd.pid"
slurmctld </dev/null >"$dir/slurmctld.out" 2>&1 ||
    fail "slurmctld failed to start" "$dir/slurmctld.out" "$dir/slurmctld.log"
slurmd </dev/null >"$dir/slurmd.out" 2>&1 ||
    fail "slurmd failed to start" "$dir/slurmd.out" "$dir/slurmd.log"

state=
deadline=$((SECONDS + 60))
while ((SECONDS < deadline)); do
    # The pid files appear once the daemons have forked; give them 10 s for that.
    daemon_pid slurmctld >/dev/null || [[ ! -f $dir/slurmctld.pid && $SECONDS -lt $((deadline - 50)) ]] ||
        fail "slurmctld exited" "$dir/slurmctld.out" "$dir/slurmctld.log"
    daemon_pid slurmd >/dev/null || [[ ! -f $dir/slurmd.pid && $SECONDS -lt $((deadline - 50)) ]] ||
        fail "slurmd exited" "$dir/slurmd.out" "$dir/slurmd.log"
    state=$(timeout 5 sinfo -h -N -o %T 2>/dev/null | head -n 1) || true
    # (mixed or allocated: up, running jobs recovered from an earlier run's state)
    [[ $state == idle || $state == mixed || $state == allocated ]] && break
    sleep 0.2
done
[[ $state == idle || $state == mixed || $state == allocated ]] ||
    fail "node $host not idle after 60 s (sinfo says: ${state:-nothing})" \
        "$dir/slurmd.out" "$dir/slurmd.log" "$dir/slurmctld.log"
echo "export SLURM_CONF=$conf"
