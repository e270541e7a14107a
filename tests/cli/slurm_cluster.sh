# Sourced by the Slurm tests (slurm_test.sh, slurm_reproduce_test.sh): stands up a real
# single-node Slurm (slurmctld + slurmd + munge on loopback, private ports, everything under a
# temporary directory $B) and stops every daemon it started when the test exits. Exits 77
# (CTest: skipped) with the reason printed when the Slurm/munge packages are absent or the test
# is not run as root (slurmd needs root). Defines skip, fail (prints the logs under $B/log and
# $B/out) and wait_job ID (prints the job's final state).
skip() { echo "SKIPPED: $*"; exit 77; }
fail() {
  echo "FAIL: $*" >&2
  for f in "$B"/log/*.log "$B"/out/*.log "$B"/out/*/slurm-logs/*.log; do
    [ -f "$f" ] && { echo "== $f" >&2; tail -20 "$f" >&2; }
  done
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

# The final state of job $1 (COMPLETED, FAILED, CANCELLED, ...), waiting at most $2 seconds
# (default 300); "" when it has not ended by then.
wait_job() {
  local state="" n=$((${2:-300} * 2))
  for _ in $(seq 1 "$n"); do
    state="$(scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')"
    case "$state" in COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY)
      echo "$state"; return ;;
    esac
    sleep 0.5
  done
  echo ""
}
