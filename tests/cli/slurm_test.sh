#!/usr/bin/env bash
# Stands up a real single-node Slurm (slurmctld + slurmd + munge on loopback, private ports,
# everything under a temporary directory), submits scripts/slurm/regbench-array.sbatch with its
# defaults for a small benchmark (4 array tasks + the afterok merge job), waits, and checks that
# the merged result equals a single-process run at `run --timeout 120`, the script's default
# and reproduce's (timing fields aside). Stops every daemon it started.
# Usage: slurm_test.sh REGBENCH SOURCE_DIR. Exit 77 (CTest: skipped) with the reason printed
# when the Slurm/munge packages are absent or the test is not run as root (slurmd needs root).
set -uo pipefail
bin="$1"
src="$2"
skip() { echo "SKIPPED: $*"; exit 77; }
fail() {
  echo "FAIL: $*" >&2
  for f in "$B"/log/*.log "$B"/out/*.log; do [ -f "$f" ] && { echo "== $f" >&2; tail -20 "$f" >&2; }; done
  exit 1
}

for cmd in slurmctld slurmd munged mungekey sbatch scontrol sinfo; do
  command -v "$cmd" >/dev/null 2>&1 ||
    skip "'$cmd' not found: install slurmctld slurmd slurm-client munge (scripts/install_deps.sh)"
done
[ "$(id -u)" -eq 0 ] || skip "slurmd must run as root to start jobs; run the test as root"

B="$(mktemp -d /tmp/regbench_slurm_XXXXXX)"
chmod 755 "$B"  # munged requires execute permission for all on every directory of its socket
H="$(hostname -s)"
cleanup() {
  if [ -f "$B/state/slurmctld.pid" ]; then
    SLURM_CONF="$B/etc/slurm.conf" timeout 10 scontrol shutdown >/dev/null 2>&1
    sleep 1
  fi
  for pidfile in "$B/state/slurmctld.pid" "$B/spool/slurmd.$H.pid" "$B/munge/munged.pid"; do
    [ -f "$pidfile" ] && kill "$(cat "$pidfile")" 2>/dev/null
  done
  sleep 0.5
  rm -rf "$B"
}
trap cleanup EXIT

# Two free TCP ports, so the test never collides with a Slurm already on 6817/6818.
free_port() {
  for _ in $(seq 1 100); do
    local p=$((20000 + RANDOM % 20000))
    (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null || { echo "$p"; return; }
  done
  fail "no free port"
}
ctld_port="$(free_port)"
slurmd_port="$(free_port)"
[ "$ctld_port" != "$slurmd_port" ] || slurmd_port=$((ctld_port + 1))

mkdir -p "$B"/{munge,etc,state,"spool/slurmd.$H",log,out}
chmod 755 "$B/munge"
mungekey -c -k "$B/munge/munge.key" >/dev/null 2>&1 || fail "mungekey"
munged --key-file="$B/munge/munge.key" --socket="$B/munge/munge.socket" \
  --pid-file="$B/munge/munged.pid" --log-file="$B/log/munged.log" \
  --seed-file="$B/munge/munged.seed" || fail "munged did not start"

node_line="$(slurmd -C | head -1)"
mem_mb="$(free -m | awk '/^Mem:/ {print int($2 * 0.9)}')"
node_line="$(echo "$node_line" | sed "s/RealMemory=[0-9]*/RealMemory=$mem_mb/")"
cat >"$B/etc/slurm.conf" <<CONF
ClusterName=regbenchci
SlurmctldHost=$H(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$B/munge/munge.socket
StateSaveLocation=$B/state
SlurmdSpoolDir=$B/spool/slurmd.%n
SlurmctldPidFile=$B/state/slurmctld.pid
SlurmdPidFile=$B/spool/slurmd.%n.pid
SlurmctldLogFile=$B/log/slurmctld.log
SlurmdLogFile=$B/log/slurmd.log
MailProg=/bin/true
MpiDefault=none
SwitchType=switch/none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
ReturnToService=2
MinJobAge=300
$node_line NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=$H Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$B/etc/slurm.conf"
slurmctld -f "$SLURM_CONF" || fail "slurmctld did not start"
slurmd -f "$SLURM_CONF" || fail "slurmd did not start"
for _ in $(seq 1 100); do
  sinfo -h -o %t 2>/dev/null | grep -qE '^idle' && break
  sleep 0.2
done
sinfo -h -o %t 2>/dev/null | grep -qE '^idle' || fail "node never became idle: $(sinfo 2>&1)"

cd "$B/out"
"$bin" generate --protocol partial --dataset procedural --split test --pairs 8 --seed 1 \
  --out "$B/out/pairs.h5" >/dev/null 2>&1 || fail "generate"
ids="$(PAIRS="$B/out/pairs.h5" METHODS=identity,icp OUT="$B/out/res" SHARDS=4 REGBENCH="$bin" \
  bash "$src/scripts/slurm/regbench-array.sbatch")" || fail "submission failed: $ids"
merge_id="$(echo "$ids" | awk '/^merge/ {print $2}')"
[ -n "$merge_id" ] || fail "no merge job id in: $ids"
state=""
for _ in $(seq 1 600); do
  state="$(scontrol show job "$merge_id" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')"
  case "$state" in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL) break ;; esac
  sleep 0.5
done
[ "$state" = COMPLETED ] || fail "merge job $merge_id ended in state '$state'"

"$bin" run --pairs "$B/out/pairs.h5" --methods identity,icp --out "$B/out/single.jsonl" -q \
  --timeout 120 2>/dev/null || fail "single-process run"
strip() { sed -E 's/"(cpu_)?seconds":[^,]*,//g; s/"machine":\{[^}]*\},?//g' "$1"; }
diff <(strip "$B/out/single.jsonl") <(strip "$B/out/res/merged.jsonl") >/dev/null ||
  fail "merged result differs from the single-process run"
[ "$(wc -l <"$B/out/res/merged.jsonl")" -eq 16 ] || fail "merged result is not 16 rows"
echo "ok: 4 Slurm array tasks + afterok merge = single-process run (16 rows)"
