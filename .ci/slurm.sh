#!/usr/bin/env bash
# A sweep on a real SLURM: installs slurm-wlm, munge and GNU parallel from Debian,
# starts munged, slurmctld and slurmd on this machine (one node, 2 CPUs, a generated
# slurm.conf, completion records in a jobcomp/filetxt file), submits the array job that
# `host-demo sweep --emit slurm` writes for host/sweeps/small.toml (8 points),
# waits for it, and checks that `collect` finds every point and that the point folders
# equal a local `sweep` run byte for byte (summary.json apart from its execution fields:
# wall_time_s, steps_per_second, machine, resumed_from). Then a task stopped by SIGTERM
# (what the time limit sends with the emitted --signal) is resubmitted with the line
# `collect` prints and ends equal to a clean run, though the base scene was edited
# after emitting. Where SLURM cannot start, it says so loudly and runs the GNU parallel
# command (and the stop by a plain kill -TERM) instead. Every wait is bounded.
#
#   bash .ci/slurm.sh [HOST_DEMO]     (root, or sudo; HOST_DEMO: the built binary)
#
# Takes about 15 s on 2 cores once the packages are installed (apt: about a minute).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
bin=$(realpath "${1:-target/release/host-demo}")
sweep=host/sweeps/small.toml
t_start=$SECONDS
say() { printf '\n==> [slurm] %s\n' "$*"; }
loud() { printf '\n!!!!!!!!!! %s !!!!!!!!!!\n' "$*"; }

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
need=()
for tool in slurmctld:slurm-wlm munged:munge parallel:parallel; do
    command -v "${tool%%:*}" >/dev/null 2>&1 || need+=("${tool#*:}")
done
if [ ${#need[@]} -gt 0 ]; then
    say "apt-get install ${need[*]}"
    timeout 120 $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive timeout 600 $sudo apt-get install -y -qq "${need[@]}" >/dev/null
fi

work=$(mktemp -d /tmp/hydrorattle-slurm.XXXXXX)
chmod 755 "$work"
started=()   # pids of the daemons this script started, stopped on exit
cleanup() {
    local p
    for p in "${started[@]}"; do $sudo kill "$p" 2>/dev/null || true; done
    # Wait for them to end (slurmctld saves its state on the way out) before removing
    # their folder.
    for p in "${started[@]}"; do
        timeout 10 bash -c "while kill -0 $p 2>/dev/null; do sleep 0.1; done" || true
    done
    if [ "${keep_work:-}" != 1 ]; then rm -rf "$work"; fi
}
trap cleanup EXIT

# --- SLURM on localhost ---------------------------------------------------------------

host=$(hostname -s)
export SLURM_CONF="$work/slurm.conf"
cat >"$SLURM_CONF" <<EOF
ClusterName=ci
SlurmctldHost=$host(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$work/jobcomp.txt
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmdParameters=config_overrides
ReturnToService=2
MpiDefault=none
MaxArraySize=1001
NodeName=$host NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=30 State=UP
EOF
mkdir -p "$work/state" "$work/spool"

start_slurm() {
    say "munged, slurmctld and slurmd (config $SLURM_CONF)"
    local t0=$SECONDS
    # munge: the Debian package made a key; munged runs as its own user.
    [ -s /etc/munge/munge.key ] || $sudo mungekey --create --force
    $sudo mkdir -p /run/munge "$work/munge"
    $sudo chown munge:munge /run/munge "$work/munge"
    $sudo chmod 755 /run/munge
    # A controller or node daemon left running (by another run) would answer in place
    # of ours: refuse it rather than stop what this script did not start.
    if pgrep -x slurmctld >/dev/null || pgrep -x slurmd >/dev/null; then
        echo "a slurmctld or slurmd is already running on this machine (pids $(pgrep -d ' ' -x 'slurmctld|slurmd'))"
        return 1
    fi
    if munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
        echo "    munged already running"
    else
        $sudo runuser -u munge -- /usr/sbin/munged --pid-file="$work/munge/munged.pid" \
            || $sudo runuser -u munge -- /usr/sbin/munged --force --pid-file="$work/munge/munged.pid" \
            || return 1
        started+=("$(cat "$work/munge/munged.pid")")
    fi
    timeout 10 bash -c 'until munge -n </dev/null | unmunge >/dev/null 2>&1; do sleep 0.2; done' \
        || { echo "munge does not answer"; return 1; }
    $sudo env SLURM_CONF="$SLURM_CONF" /usr/sbin/slurmctld -c || return 1
    timeout 10 bash -c "until [ -s '$work/slurmctld.pid' ]; do sleep 0.1; done" || return 1
    started+=("$(cat "$work/slurmctld.pid")")
    $sudo env SLURM_CONF="$SLURM_CONF" /usr/sbin/slurmd -N "$host" || return 1
    timeout 10 bash -c "until [ -s '$work/slurmd.pid' ]; do sleep 0.1; done" || return 1
    started+=("$(cat "$work/slurmd.pid")")
    if ! timeout 30 bash -c 'until sinfo -h -o %t 2>/dev/null | grep -qE "^(idle|mix|alloc)"; do sleep 0.5; done'; then
        echo "the node did not come up:"; sinfo 2>&1 || true
        tail -n 20 "$work/slurmctld.log" "$work/slurmd.log" 2>/dev/null || true
        return 1
    fi
    sinfo
    echo "    SLURM up in $(( SECONDS - t0 )) s"
}

local_dir="$work/local"
say "local run: $bin sweep $sweep --out $local_dir"
timeout 300 "$bin" sweep "$sweep" --out "$local_dir" --jobs 2 | tail -n 1

engine_dir="$work/engine"
engine=slurm
# SLURM_CI_SKIP=1 tries the GNU parallel path on a machine where SLURM would start.
if [ -z "${SLURM_CI_SKIP:-}" ] && start_slurm; then
    say "submit the emitted array job"
    timeout 60 "$bin" sweep "$sweep" --out "$engine_dir" --emit slurm --partition ci \
        --time 00:05:00 --cpus 1 --throttle 2
    cat "$engine_dir/slurm.sh"
    t0=$SECONDS
    if ! jobid=$(timeout 30 sbatch --parsable "$engine_dir/slurm.sh"); then
        loud "sbatch refused the array job"
        keep_work=1
        tail -n 20 "$work/slurmctld.log" 2>/dev/null || true
        exit 1
    fi
    echo "    submitted array job $jobid"
    # Polled every half second (sbatch --wait polls slower): done when the queue no
    # longer holds any of its tasks.
    if ! timeout 600 bash -c "while [ -n \"\$(squeue -h -j $jobid 2>/dev/null)\" ]; do sleep 0.5; done"; then
        loud "the SLURM array job did not end within 600 s"
        keep_work=1
        scontrol show job "$jobid" 2>/dev/null || true
        tail -n 30 "$work/slurmctld.log" "$work/slurmd.log" "$engine_dir"/slurm/*.out 2>/dev/null || true
        exit 1
    fi
    echo "    array job done in $(( SECONDS - t0 )) s"
    say "completion records (jobcomp/filetxt)"
    # The records land a moment after the job ends.
    timeout 10 bash -c "until [ \$(grep -c JobState=COMPLETED '$work/jobcomp.txt' 2>/dev/null || echo 0) -ge 8 ]; do sleep 0.2; done" || true
    cat "$work/jobcomp.txt"
    scontrol show job "$jobid" 2>/dev/null | head -n 3 || true
    completed=$(grep -c "JobState=COMPLETED" "$work/jobcomp.txt" || true)
    if [ "$completed" -lt 8 ]; then
        loud "expected 8 completed array tasks in the completion records, found $completed"
        exit 1
    fi
    tail -n 2 "$engine_dir"/slurm/*.out
else
    engine=parallel
    loud "SLURM COULD NOT START ON THIS MACHINE: running the sweep with GNU parallel instead"
    tail -n 20 "$work/slurmctld.log" "$work/slurmd.log" 2>/dev/null || true
    timeout 60 "$bin" sweep "$sweep" --out "$engine_dir" --emit parallel --cpus 2
    timeout 600 bash "$engine_dir/parallel.sh"
    cat "$engine_dir/parallel.log"
fi

# --- Checks ---------------------------------------------------------------------------

say "collect: every point found"
timeout 60 "$bin" collect "$engine_dir"
timeout 60 "$bin" collect "$local_dir" >/dev/null

say "point folders ($engine) against the local run, byte for byte"
python3 - "$local_dir" "$engine_dir" <<'EOF'
import json, os, sys
a, b = sys.argv[1:3]
run_fields = {"wall_time_s", "steps_per_second", "machine", "resumed_from"}
ids = sorted(os.listdir(os.path.join(a, "points")))
assert ids == sorted(os.listdir(os.path.join(b, "points"))), "different points"
files = 0
for i in ids:
    pa, pb = os.path.join(a, "points", i), os.path.join(b, "points", i)
    names = sorted(os.listdir(pa))
    assert names == sorted(os.listdir(pb)), f"{i}: different files"
    for n in names:
        x, y = (open(os.path.join(p, n), "rb").read() for p in (pa, pb))
        if n == "summary.json":
            x, y = ({k: v for k, v in json.loads(t).items() if k not in run_fields} for t in (x, y))
        assert x == y, f"{i}/{n} differs"
        files += 1
strip = lambda p: [l.rsplit(",", 2)[0] for l in open(os.path.join(p, "collected.csv"))]
assert strip(a) == strip(b), "collected.csv differs"
print(f"    {len(ids)} points, {files} files equal; collected.csv equal apart from wall times")
EOF
cmp "$local_dir/sweep.json" "$engine_dir/sweep.json"

# --- A task stopped by SIGTERM resumes on resubmission -----------------------------
# What SLURM does at a time limit with the emitted `--signal=B:TERM@60`: SIGTERM to the
# batch shell, which `exec` made host-demo. `scancel --batch --signal=TERM` sends the
# same signal now (a real time limit is a minute at least). The task checkpoints its
# point and exits 143; `collect` names the task and prints the `sbatch --array` line,
# which is run as printed; the points then equal a clean local run.
long="$work/long.toml"
cp host/scenes/figure1a.toml "$work/long-base.toml"
cat >"$long" <<EOT
[sweep]
base = "long-base.toml"
"integrator.duration" = [1500.0]
"helix.dhat" = [1.05, 1.5]
EOT
say "a stopped task: clean local run of $long"
timeout 300 "$bin" sweep "$long" --out "$work/long-local" --jobs 2 --checkpoint-every 50 | tail -n 1
stopped_dir="$work/long-stopped"
timeout 60 "$bin" sweep "$long" --out "$stopped_dir" --emit slurm --tasks 1 --time 00:05:00 \
    --checkpoint-every 50 --partition ci >/dev/null
# The base edited after emitting: the job runs the frozen scenes all the same.
sed -i 's/viscosity = 1.0/viscosity = 9.0/' "$work/long-base.toml"
grep -q "viscosity = 9.0" "$work/long-base.toml"
wait_checkpoint() {
    timeout 120 bash -c "until ls '$stopped_dir'/points/*/checkpoint.json >/dev/null 2>&1; do sleep 0.1; done"
}
if [ "$engine" = slurm ]; then
    jobid=$(timeout 30 sbatch --parsable "$stopped_dir/slurm.sh")
    wait_checkpoint || { loud "no checkpoint from job $jobid"; keep_work=1; exit 1; }
    timeout 30 scancel --batch --signal=TERM "$jobid"
    timeout 120 bash -c "while [ -n \"\$(squeue -h -j $jobid 2>/dev/null)\" ]; do sleep 0.5; done"
    cat "$stopped_dir"/slurm/*.out
    grep -q "stopped by signal 15" "$stopped_dir"/slurm/*.out || { loud "the task was not stopped by SIGTERM"; exit 1; }
else
    "$bin" sweep --frozen --out "$stopped_dir" --jobs 1 --checkpoint-every 50 &
    pid=$!
    wait_checkpoint || { loud "no checkpoint"; exit 1; }
    kill -TERM "$pid"
    status=0; wait "$pid" || status=$?
    [ "$status" = 143 ] || { loud "expected exit status 143 after SIGTERM, got $status"; exit 1; }
fi
if listed=$(timeout 60 "$bin" collect "$stopped_dir"); then
    loud "collect found every point done after SIGTERM"; exit 1
fi
echo "$listed"
rerun=$(echo "$listed" | grep -o 'sbatch --array=.*') || { loud "collect printed no sbatch line"; exit 1; }
echo "    collect says: $rerun"
if [ "$engine" = slurm ]; then
    jobid=$(timeout 30 ${rerun/sbatch /sbatch --parsable })
    timeout 300 bash -c "while [ -n \"\$(squeue -h -j $jobid 2>/dev/null)\" ]; do sleep 0.5; done"
else
    timeout 300 "$bin" sweep --frozen --out "$stopped_dir" --jobs 2 --checkpoint-every 50 | tail -n 1
fi
timeout 60 "$bin" collect "$stopped_dir"
python3 - "$work/long-local" "$stopped_dir" <<'EOF2'
import json, os, sys
a, b = sys.argv[1:3]
run_fields = {"wall_time_s", "steps_per_second", "machine", "resumed_from"}
resumed = 0
for i in sorted(os.listdir(os.path.join(a, "points"))):
    for n in ["trajectory.xyz", "trajectory.gsd", "observables.csv", "scene.toml", "summary.json"]:
        x, y = (open(os.path.join(p, "points", i, n), "rb").read() for p in (a, b))
        if n == "summary.json":
            x, y = (json.loads(t) for t in (x, y))
            resumed += y.get("resumed_from") is not None
            x, y = ({k: v for k, v in d.items() if k not in run_fields} for d in (x, y))
        assert x == y, f"{i}/{n} differs from the clean run"
assert resumed >= 1, "no point was resumed from its checkpoint"
print(f"    stopped, resumed ({resumed} from a checkpoint) and equal to the clean run")
EOF2
say "sweep on $engine passed in $(( SECONDS - t_start )) s"
