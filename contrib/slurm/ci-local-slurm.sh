#!/usr/bin/env bash
# A pgt cluster render through a real, single-node Slurm on this machine (the test
# tests/cluster/slurm.rs runs it; it is also a worked example of contrib/slurm/submit.sh).
#
#   PGT=/path/to/pgt contrib/slurm/ci-local-slurm.sh WORK SCENE N [pgt render options...]
#
# Starts munged, slurmctld and slurmd on localhost with a configuration of its own under
# WORK/slurm (own ports, own munge socket: it touches no system-wide Slurm or munge), submits the
# N-part array job and the dependent merge job with submit.sh, waits for them, and writes
# WORK/merged.exr. The daemons are stopped by the process ids started here on every exit, and
# their ids are left in WORK/daemon-pids so a caller can check that none survived.
#
# Exit status: 0 the merge job completed; 77 Slurm cannot be started here (the reason is the last
# line on stderr: missing packages, not root, a daemon that does not come up); 1 anything else
# (a job failed, a timeout). Needs the Debian packages slurmd slurmctld slurm-client munge
# (`apt-get install --no-install-recommends`) and root (the daemons switch users).
set -uo pipefail

skip() { echo "cannot start Slurm here: $*" >&2; exit 77; }
fail() { echo "ci-local-slurm: $*" >&2; exit 1; }

[ $# -ge 3 ] || { echo "usage: PGT=pgt $0 WORK SCENE N [pgt render options...]" >&2; exit 2; }
work=$(mkdir -p "$1" && cd "$1" && pwd) || fail "cannot create $1"
scene=$(realpath "$2") || fail "no scene $2"
parts=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)

for tool in munged slurmctld slurmd sbatch scontrol squeue setpriv; do
    command -v "$tool" >/dev/null || skip "'$tool' is not installed (apt-get install --no-install-recommends slurmd slurmctld slurm-client munge)"
done
[ "$(id -u)" = 0 ] || skip "needs root (munged and slurmctld run as the users munge and slurm)"
id munge >/dev/null 2>&1 && id slurm >/dev/null 2>&1 || skip "the users munge and slurm do not exist"

state="$work/slurm"
rm -rf "$state"
mkdir -p "$state/munge" "$state/ctld" "$state/spool" "$state/log"
chmod 755 "$work" "$state"
chown munge:munge "$state/munge"
chmod 755 "$state/munge" # the socket in it must be reachable by slurm and root
chown slurm:slurm "$state/ctld" "$state/log"
: >"$work/daemon-pids"

pids=()
stop_daemons() {
    local pid
    # Let the job steps of slurmd end first, so none is orphaned mid-exit.
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do
            pgrep -P "$pid" slurmstepd >/dev/null 2>&1 || break
            sleep 0.1
        done
    done
    for pid in "${pids[@]}"; do kill -TERM "$pid" 2>/dev/null; done
    for pid in "${pids[@]}"; do
        # An exited daemon stays a zombie until waited for: look at its state, not at kill -0.
        for _ in $(seq 100); do
            [ -e "/proc/$pid/stat" ] || break
            [ "$(awk '{print $3}' "/proc/$pid/stat" 2>/dev/null)" = Z ] && break
            sleep 0.1
        done
        kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    pids=()
}
trap stop_daemons EXIT
trap 'exit 1' INT TERM
start() { # start NAME COMMAND...: runs it in the background, records its pid
    local name=$1
    shift
    "$@" >"$state/log/$name.out" 2>&1 &
    pids+=("$!")
    echo "$!" >>"$work/daemon-pids"
}
show_logs() {
    local f
    for f in "$state"/log/*; do echo "--- $f" >&2; tail -n 20 "$f" >&2; done
}

# Free TCP ports for slurmctld and slurmd, so that nothing else on the machine is disturbed.
read -r ctld_port d_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*[x.getsockname()[1] for x in s])' 2>/dev/null || echo "16817 16818")

host=$(hostname -s)
# The node's sockets, cores and threads as slurmd sees them.
node=$(slurmd -C 2>/dev/null | head -n 1 | sed -e "s/^NodeName=[^ ]*//" -e "s/UpTime=.*//")
[ -n "$node" ] || skip "slurmd -C printed nothing"
dd if=/dev/urandom of="$state/munge/munge.key" bs=1024 count=1 status=none
chown munge:munge "$state/munge/munge.key"
chmod 400 "$state/munge/munge.key"
socket="$state/munge/munge.socket"
export SLURM_CONF="$state/slurm.conf"
cat >"$SLURM_CONF" <<CONF
ClusterName=pgtci
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$d_port
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$socket
SlurmUser=slurm
SlurmdUser=root
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/ctld/slurmctld.pid
SlurmdPidFile=$state/spool/slurmd.pid
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
MailProg=/bin/true
NodeName=$host NodeAddr=127.0.0.1 $node State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF

start munged setpriv --reuid=munge --regid=munge --init-groups \
    munged -F --force --socket="$socket" --key-file="$state/munge/munge.key" \
    --pid-file="$state/munge/munged.pid" --seed-file="$state/munge/seed" \
    --log-file="$state/log/munged.log"
for _ in $(seq 50); do [ -S "$socket" ] && break; sleep 0.1; done
[ -S "$socket" ] || { show_logs; skip "munged did not start"; }
start slurmctld slurmctld -D -f "$SLURM_CONF"
start slurmd slurmd -D -f "$SLURM_CONF"
idle=""
deadline=$((SECONDS + 30))
while [ "$SECONDS" -lt "$deadline" ]; do
    idle=$(timeout 5 sinfo -h -n "$host" -o %T 2>/dev/null)
    [ "$idle" = idle ] && break
    sleep 0.2
done
[ "$idle" = idle ] || { show_logs; skip "the node did not become idle within 30 s (state '$idle')"; }
echo "Slurm is up (node $host: $node)" >&2

cd "$work" || fail "cannot enter $work"
ids=$(PGT="${PGT:-pgt}" "$here/submit.sh" "$scene" "$parts" "$work/merged.exr" "$@") || {
    show_logs
    fail "submitting failed"
}
echo "$ids" >&2
array=$(sed -E 's/^render array job ([0-9]+).*/\1/' <<<"$ids")
merge=$(sed -E 's/.*merge job ([0-9]+).*/\1/' <<<"$ids")
deadline=$((SECONDS + ${PGT_SLURM_TIMEOUT:-300}))
while [ "$SECONDS" -lt "$deadline" ]; do
    queued=$(timeout 5 squeue -h -j "$array,$merge" 2>&1) && [ -z "$queued" ] && break
    sleep 0.2
done
states=$(scontrol show job -o "$array" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | sort | uniq -c)
merge_state=$(scontrol show job -o "$merge" 2>/dev/null | grep -o 'JobState=[A-Z_]*')
echo "array job $array: $(echo $states); merge job $merge: $merge_state" >&2
if [ "$merge_state" != JobState=COMPLETED ]; then
    for f in "$work"/pgt-*.log; do [ -e "$f" ] && { echo "--- $f" >&2; cat "$f" >&2; }; done
    show_logs
    fail "the merge job did not complete ($merge_state)"
fi
cat "$work"/pgt-merge-*.log >&2
exit 0
