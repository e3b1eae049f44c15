#!/usr/bin/env bash
# Runs examples/slurm/submit.sh on a one-node Slurm started on this machine (Debian's
# slurm-wlm with munge; root needed to start it), with 4 shards of scenarios/ci-guard.toml
# and CPUS=1, and compares the merged summary.json and trials.csv with an unsharded run.
#   scripts/slurm-one-node.sh CALBENCH_BINARY
# Exit 0: the bytes agree; 1: they do not, or a step failed; 2: Slurm is not available
# here (not installed and cannot be installed, or not root) and nothing was run.
set -uo pipefail
BIN=$(readlink -f "${1:?usage: slurm-one-node.sh CALBENCH_BINARY}")
ROOT=$(cd "$(dirname "$0")/.." && pwd)
TMP=$(mktemp -d /tmp/calbench-slurm.XXXXXX)
up() { sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; }
STARTED=()
cleanup() {
    scancel --user="$(id -un)" 2>/dev/null
    for p in "${STARTED[@]}"; do [ -f "$p" ] && kill "$(cat "$p")" 2>/dev/null; done
    rm -rf "$TMP"
}
trap cleanup EXIT
if ! up; then
    if ! command -v slurmctld >/dev/null; then
        [ "$(id -u)" = 0 ] || { echo "skipped: Slurm is not installed and this is not root"; exit 2; }
        (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge) \
            >"$TMP/apt.log" 2>&1 || { echo "skipped: cannot install slurm-wlm and munge"; tail -3 "$TMP/apt.log"; exit 2; }
    fi
    [ "$(id -u)" = 0 ] || { echo "skipped: starting Slurm needs root"; exit 2; }
    HOST=$(hostname -s)
    mkdir -p /etc/slurm /var/log/slurm /run/munge /etc/munge "$TMP/ctld" "$TMP/d"
    [ -f /etc/munge/munge.key ] || head -c 1024 /dev/urandom >/etc/munge/munge.key
    chown -R munge:munge /etc/munge /run/munge /var/lib/munge /var/log/munge 2>/dev/null
    chmod 400 /etc/munge/munge.key
    if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
        su -s /bin/sh munge -c /usr/sbin/munged && STARTED+=(/run/munge/munged.pid)
    fi
    cat >/etc/slurm/slurm.conf <<CONF
ClusterName=calbench
SlurmctldHost=$HOST
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$TMP/ctld
SlurmdSpoolDir=$TMP/d
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
NodeName=$HOST CPUs=$(nproc) RealMemory=4000 State=UNKNOWN
PartitionName=calbench Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
CONF
    rm -f /etc/slurm/cgroup.conf
    /usr/sbin/slurmctld && STARTED+=(/run/slurmctld.pid)
    /usr/sbin/slurmd && STARTED+=(/run/slurmd.pid)
    for _ in $(seq 30); do up && break; sleep 1; done
    up || { echo "FAIL: a one-node Slurm did not come up"; tail -3 /var/log/slurm/*.log; exit 1; }
fi
git clone -q "$ROOT" "$TMP/work" || exit 1
mkdir -p "$TMP/work/target/release" && cp "$BIN" "$TMP/work/target/release/calbench"
(cd "$TMP/work" && CPUS=1 bash examples/slurm/submit.sh scenarios/ci-guard.toml 4) || exit 1
for _ in $(seq 600); do
    [ -f "$TMP/work/results/ci-guard/summary.json" ] && [ -z "$(squeue -h)" ] && break
    sleep 1
done
[ -f "$TMP/work/results/ci-guard/summary.json" ] || { echo "FAIL: the array and merge did not finish"; squeue; exit 1; }
"$BIN" run "$ROOT/scenarios/ci-guard.toml" --out "$TMP/unsharded" >/dev/null 2>&1 || exit 1
for f in summary.json trials.csv; do
    cmp -s "$TMP/work/results/ci-guard/$f" "$TMP/unsharded/$f" || { echo "FAIL: $f differs"; exit 1; }
done
echo "Slurm: 4 shards and the merge give the bytes of the unsharded run"
