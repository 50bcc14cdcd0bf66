#!/usr/bin/env bash
# A real single-node Slurm on this machine, for the cluster integration test
# (tests/slurm_cluster.rs). Needs root and access to the Debian package archive.
#
#   scripts/slurm-local.sh start   install slurm-wlm and munge if missing (apt-get), write a
#                                  minimal slurm.conf, start munged, slurmctld and slurmd by hand
#                                  (no systemd), wait until the node is idle; prints timings
#   scripts/slurm-local.sh stop    stop the daemons this script started, by their pid files
#   scripts/slurm-local.sh status  whether the daemons are up
#
# Configuration: proctrack/linuxproc, task/none, no accounting; the node's CPUs and memory are
# what `slurmd -C` reports. Everything the daemons write (state, spool, logs, pid files, munge
# socket) lives under $WETGRAN_SLURM_DIR (default /tmp/wetgran-slurm); the only file written
# outside it is /etc/slurm/slurm.conf, which the Slurm commands read. An existing slurm.conf that
# this script did not write is never overwritten (the script stops with an error instead).
#
# Exit status: 0 started / stopped; 3 not root; 4 the packages cannot be installed; 1 any other
# failure (the daemon logs are printed).
set -euo pipefail

STATE=${WETGRAN_SLURM_DIR:-/tmp/wetgran-slurm}
CONF=/etc/slurm/slurm.conf
MARK="# written by wetgran scripts/slurm-local.sh"

log() { echo "slurm-local: $*" >&2; }
now() { date +%s.%N; }
secs() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", b - a }'; }

# pid_alive PIDFILE: the pid file names a live process whose command is the file's name
# (munged.pid -> munged): a stale file whose pid was reused by another program does not count.
pid_alive() {
    local pid
    [[ -f "$1" ]] || return 1
    pid=$(cat "$1")
    kill -0 "$pid" 2>/dev/null && [[ "$(cat "/proc/$pid/comm" 2>/dev/null)" == "$(basename "$1" .pid)" ]]
}

install_packages() {
    if command -v slurmctld >/dev/null && command -v slurmd >/dev/null && command -v munged >/dev/null \
        && command -v sbatch >/dev/null; then
        log "slurm-wlm and munge already installed"
        return 0
    fi
    local t0 added_policy=0
    t0=$(now)
    # Keep the packages' init scripts from starting daemons during the install: they are started
    # by hand below (a container has no systemd, and a daemon started by dpkg is not ours to stop).
    if [[ ! -e /usr/sbin/policy-rc.d ]]; then
        printf '#!/bin/sh\nexit 101\n' >/usr/sbin/policy-rc.d
        chmod +x /usr/sbin/policy-rc.d
        added_policy=1
    fi
    local ok=0
    export DEBIAN_FRONTEND=noninteractive
    if apt-get install -y -qq --no-install-recommends slurm-wlm munge >"$STATE/apt.log" 2>&1; then
        ok=1
    else
        log "apt-get install failed; updating the package lists and trying again"
        if apt-get update -qq >>"$STATE/apt.log" 2>&1 \
            && apt-get install -y -qq --no-install-recommends slurm-wlm munge >>"$STATE/apt.log" 2>&1; then
            ok=1
        fi
    fi
    if [[ $added_policy == 1 ]]; then rm -f /usr/sbin/policy-rc.d; fi
    if [[ $ok != 1 ]]; then
        tail -n 20 "$STATE/apt.log" >&2
        log "cannot install slurm-wlm and munge (no package access?)"
        exit 4
    fi
    log "installed slurm-wlm and munge in $(secs "$t0" "$(now)") s"
}

write_conf() {
    local host node
    host=$(hostname -s)
    # `slurmd -C` prints the node line (NodeName=... CPUs=... RealMemory=...) and an UpTime line.
    node=$(slurmd -C | grep '^NodeName=')
    node=$(sed -E "s/^NodeName=[^ ]+/NodeName=$host/" <<<"$node")
    if [[ -f $CONF ]] && ! grep -qF "$MARK" "$CONF"; then
        log "$CONF exists and was not written by this script: not touching it"
        exit 1
    fi
    mkdir -p /etc/slurm "$STATE/ctld" "$STATE/spool" "$STATE/log"
    cat >"$CONF" <<EOF
$MARK
ClusterName=wetgranci
SlurmctldHost=$host(127.0.0.1)
AuthType=auth/munge
CryptoType=crypto/munge
SlurmUser=root
SlurmdUser=root
SlurmctldPort=6817
SlurmdPort=6818
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/spool
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
# A small test cluster: look for startable jobs every second, not every 30 s.
SchedulerParameters=bf_interval=1
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
MinJobAge=300
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
    log "wrote $CONF ($node)"
}

start_munge() {
    if [[ ! -f /etc/munge/munge.key ]]; then
        mkdir -p /etc/munge
        if command -v mungekey >/dev/null; then
            mungekey --create --keyfile=/etc/munge/munge.key
        else
            dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
        fi
        chmod 400 /etc/munge/munge.key
    fi
    chown root:root /etc/munge/munge.key
    mkdir -p "$STATE/munge"
    chmod 755 "$STATE/munge"
    # The socket in its default place, so that slurm's auth/munge finds it.
    mkdir -p /run/munge
    munged --force --key-file=/etc/munge/munge.key --socket=/run/munge/munge.socket.2 \
        --pid-file="$STATE/munged.pid" --log-file="$STATE/log/munged.log" \
        --seed-file="$STATE/munge/munged.seed"
    for _ in $(seq 50); do
        if munge -n </dev/null | unmunge >/dev/null 2>&1; then return 0; fi
        sleep 0.1
    done
    log "munged does not answer"
    cat "$STATE/log/munged.log" >&2 || true
    exit 1
}

start() {
    if [[ $(id -u) != 0 ]]; then
        log "needs root (to install packages and run slurmd); not started"
        exit 3
    fi
    mkdir -p "$STATE"
    if pid_alive "$STATE/slurmctld.pid" && pid_alive "$STATE/slurmd.pid"; then
        log "already running (pids in $STATE)"
        return 0
    fi
    install_packages
    local t0
    t0=$(now)
    write_conf
    pid_alive "$STATE/munged.pid" || start_munge
    # -i: ignore (and start without) any saved state of an earlier run.
    slurmctld -i
    slurmd
    for _ in $(seq 300); do
        if sinfo -h -o '%t' 2>/dev/null | grep -qE '^idle'; then
            log "slurmctld, slurmd and munged up, node idle, in $(secs "$t0" "$(now)") s"
            return 0
        fi
        sleep 0.1
    done
    log "the node did not become idle within 30 s:"
    sinfo >&2 || true
    tail -n 30 "$STATE/log/slurmctld.log" "$STATE/log/slurmd.log" >&2 || true
    exit 1
}

stop_one() {
    local name=$1 pidfile=$STATE/$1.pid pid
    if ! pid_alive "$pidfile"; then
        rm -f "$pidfile"
        return 0
    fi
    pid=$(cat "$pidfile")
    kill "$pid"
    for _ in $(seq 100); do
        kill -0 "$pid" 2>/dev/null || break
        sleep 0.1
    done
    if kill -0 "$pid" 2>/dev/null; then
        log "$name (pid $pid) did not stop within 10 s; killing it"
        kill -9 "$pid" || true
    fi
    rm -f "$pidfile"
    log "stopped $name (pid $pid)"
}

stop() {
    stop_one slurmd
    stop_one slurmctld
    stop_one munged
}

status() {
    local rc=0
    for d in munged slurmctld slurmd; do
        if pid_alive "$STATE/$d.pid"; then
            echo "$d running (pid $(cat "$STATE/$d.pid"))"
        else
            echo "$d not running"
            rc=1
        fi
    done
    return $rc
}

case "${1:-}" in
    start) start ;;
    stop) stop ;;
    status) status ;;
    *)
        echo "usage: $0 start|stop|status" >&2
        exit 2
        ;;
esac
