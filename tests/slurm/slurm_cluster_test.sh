#!/bin/bash
# deploy/slurm/ on a real single-node Slurm cluster (Debian's slurmctld, slurmd and munge, started
# here without systemd): 2 views x 4 regions rendered as a job array after a preparation job, then
# assembled by a dependent job; each assembled frame must be byte for byte what `photond render`
# writes for the whole view. Run as root (`make test-slurm`). Usage: slurm_cluster_test.sh PHOTOND
set -euo pipefail
[ "$(id -u)" = 0 ] || exec sudo -E bash "$0" "$@"  # munged's run directory, /etc/hosts
photond=$(realpath "${1:?usage: $0 path/to/photond}")
repo=$(cd "$(dirname "$0")/../.." && pwd)
sc=$(mktemp -d /tmp/photond_slurm_test.XXXXXX)
host=$(hostname -s)
started_munge=0

stop_cluster() {
    scancel --user=root 2>/dev/null || true
    for daemon in slurmd slurmctld; do
        if [ -f "$sc/run/$daemon.pid" ]; then
            pid=$(cat "$sc/run/$daemon.pid")
            kill -TERM "$pid" 2>/dev/null || true
            for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
        fi
    done
    if [ "$started_munge" = 1 ] && [ -f /run/munge/munged.pid ]; then
        pid=$(cat /run/munge/munged.pid)
        kill -TERM "$pid" 2>/dev/null || true
        for _ in $(seq 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    fi
}
trap 'status=$?; stop_cluster; if [ $status -ne 0 ]; then tail -n 20 "$sc"/log/*.log "$sc"/out/logs/*.txt 2>/dev/null; fi; rm -rf "$sc"; exit $status' EXIT

# The cluster: munge, then slurmctld and slurmd with a configuration of our own, no systemd.
mkdir -p "$sc"/{etc,state/ctld,state/d,log,run,out}
getent hosts "$host" >/dev/null || echo "127.0.0.1 $host" >>/etc/hosts
install -d -o munge -g munge -m 0755 /run/munge
if [ ! -f /etc/munge/munge.key ]; then
    mungekey --create --keyfile=/etc/munge/munge.key
    chown munge:munge /etc/munge/munge.key
    chmod 0400 /etc/munge/munge.key
fi
if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    runuser -u munge -- /usr/sbin/munged
    started_munge=1
    for _ in $(seq 100); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.1; done
fi
memory_mb=$(($(awk '/MemTotal/ { print int($2 / 1024) }' /proc/meminfo) - 1024))
cat >"$sc/etc/slurm.conf" <<CONF
ClusterName=photond-test
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0,sched_min_interval=0
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MailProg=/bin/true
StateSaveLocation=$sc/state/ctld
SlurmdSpoolDir=$sc/state/d
SlurmctldPidFile=$sc/run/slurmctld.pid
SlurmdPidFile=$sc/run/slurmd.pid
SlurmctldLogFile=$sc/log/slurmctld.log
SlurmdLogFile=$sc/log/slurmd.log
NodeName=$host NodeAddr=127.0.0.1 CPUs=$(nproc) RealMemory=$memory_mb State=UNKNOWN
PartitionName=render Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$sc/etc/slurm.conf"
slurmctld
slurmd
for _ in $(seq 300); do [ "$(sinfo -h -n "$host" -o %t 2>/dev/null)" = idle ] && break; sleep 0.1; done
[ "$(sinfo -h -n "$host" -o %t)" = idle ] || { echo "the Slurm node did not become idle" >&2; exit 1; }

# Two views of one scene.
cat >"$sc/front.json" <<'JOB'
{"scene": {"builtin": "cornell-box-diffuse"}, "preset": "preview", "image": {"width": 96, "height": 64, "tile_size": 16}}
JOB
cat >"$sc/side.json" <<'JOB'
{"scene": {"builtin": "cornell-box-diffuse"}, "preset": "preview", "image": {"width": 96, "height": 64, "tile_size": 16},
 "camera": {"look_from": [1.5, 3.0, 9.0], "look_at": [0.0, 2.0, 0.0], "vfov_deg": 45}}
JOB
"$repo/deploy/slurm/submit_frames.sh" --photond "$photond" --cache-dir "$sc/cache" --out "$sc/out" \
    --regions 2 2 --wait "$sc/front.json" "$sc/side.json"

for view in front side; do
    "$photond" render --job "$sc/$view.json" -o "$sc/$view-single.exr" --quiet
    cmp "$sc/out/$view.exr" "$sc/$view-single.exr" ||
        { echo "the assembled $view differs from the single-node render" >&2; exit 1; }
done
# The regions took the views' photon maps and irradiance caches from the preparation job.
for part in "$sc"/out/parts/*.json; do
    python3 -c 'import json, sys
s = json.load(open(sys.argv[1]))
assert s["photons"]["cache"] == "hit" and s["irradiance_cache"]["cache"] == "hit", sys.argv[1]' "$part"
done
echo "slurm: 2 views x 4 regions assembled byte-identical to photond render; every region took the prepared caches"
