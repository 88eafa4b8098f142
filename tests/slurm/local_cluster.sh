# shellcheck shell=bash
# A private one-node Slurm cluster on localhost, for tests (sourced by bash, as root).
#
#   cluster_install    installs Slurm and MUNGE from Debian when missing; returns 77 when it can't
#   cluster_start DIR  starts munged, slurmctld and slurmd with everything under DIR
#                      (key, sockets, state, spool, logs, slurm.conf) and exports SLURM_CONF
#   cluster_stop       cancels the cluster's jobs and stops the three daemons it started
#   cluster_logs       prints the daemons' logs (for failures)
#
# Logs: the daemons run in the foreground and log to their stderr, kept in DIR/log/NAME.out.
# The cluster is isolated from any other on the machine: its own MUNGE key and socket, its own
# ports (two free ones picked at start), its own slurm.conf through SLURM_CONF. Daemons run in
# the foreground (-D/-F) as background jobs of the caller, so they are stopped by their pids.

cluster_dir=
cluster_pids=()

cluster_log() { echo "[local_cluster] $*"; }

# wait_daemon PID SECONDS DESCRIPTION COMMAND...: polls COMMAND every half second until it
# succeeds; gives up after SECONDS, or as soon as the daemon PID has exited (PID "": none).
wait_daemon() {
  local pid=$1 limit=$2 what=$3 start=$SECONDS
  shift 3
  until "$@" >/dev/null 2>&1; do
    if [ -n "$pid" ] && pid_gone "$pid"; then
      cluster_log "the daemon (pid $pid) exited while waiting for $what"
      return 1
    fi
    if [ $((SECONDS - start)) -ge "$limit" ]; then
      cluster_log "timed out after ${limit}s waiting for $what"
      return 1
    fi
    sleep 0.5
  done
}

# wait_for SECONDS DESCRIPTION COMMAND...: wait_daemon without a daemon to watch.
wait_for() { wait_daemon "" "$@"; }

cluster_install() {
  local missing=0 p
  for p in munged mungekey slurmctld slurmd slurmstepd sbatch squeue sinfo scontrol scancel; do
    command -v "$p" >/dev/null || missing=1
  done
  [ $missing = 1 ] || return 0
  if [ "$(id -u)" != 0 ]; then
    cluster_log "Slurm is not installed and installing it needs root"
    return 77
  fi
  local pkgs=(munge slurmctld slurmd slurm-client)
  cluster_log "installing ${pkgs[*]} from Debian"
  export DEBIAN_FRONTEND=noninteractive
  if ! apt-get install -y -q --no-install-recommends "${pkgs[@]}" >/tmp/gradus-slurm-apt.log 2>&1; then
    apt-get update -q >>/tmp/gradus-slurm-apt.log 2>&1
    if ! apt-get install -y -q --no-install-recommends "${pkgs[@]}" >>/tmp/gradus-slurm-apt.log 2>&1; then
      tail -n 20 /tmp/gradus-slurm-apt.log
      cluster_log "apt-get could not install ${pkgs[*]} (log: /tmp/gradus-slurm-apt.log)"
      return 77
    fi
  fi
}

port_free() { ! (exec 3<>"/dev/tcp/127.0.0.1/$1") 2>/dev/null; }

cluster_start() {
  cluster_dir=$1
  local d=$cluster_dir
  # munged insists that the socket's directory be reachable by everyone and the key private.
  mkdir -p "$d/munge-run" "$d/munge-key" "$d/state" "$d/spool" "$d/log"
  chmod 755 "$d" "$d/munge-run"
  chmod 700 "$d/munge-key"
  # munged requires every directory above its socket to be searchable by all.
  local up=$d
  while [ "$up" != / ]; do
    [ "$(stat -c %A "$up" | cut -c10)" != - ] ||
      { cluster_log "$up is not searchable by others (munged refuses a socket below it)"; return 1; }
    up=$(dirname "$up")
  done
  mungekey --create --keyfile="$d/munge-key/munge.key" || return 1
  chmod 400 "$d/munge-key/munge.key"
  munged --foreground --socket="$d/munge-run/munge.socket" --key-file="$d/munge-key/munge.key" \
    --log-file="$d/log/munged.log" --pid-file="$d/munge-run/munged.pid" \
    --seed-file="$d/munge-run/munged.seed" >>"$d/log/munged.out" 2>&1 &
  cluster_pids+=($!)
  wait_daemon $! 20 "munged's socket" test -S "$d/munge-run/munge.socket" || return 1
  munge -n --socket="$d/munge-run/munge.socket" | unmunge --socket="$d/munge-run/munge.socket" >/dev/null ||
    { cluster_log "munge/unmunge round trip failed"; return 1; }

  local port=0 _try
  for _try in $(seq 1 50); do
    port=$((20000 + RANDOM % 20000))
    port_free $port && port_free $((port + 1)) && break
    port=0
  done
  [ $port != 0 ] || { cluster_log "no two free ports found"; return 1; }
  # The node as slurmd sees the hardware (CPUs, sockets, cores, memory), named localhost.
  local node
  node=$(slurmd -C | sed -n '1s/^NodeName=[^ ]*/NodeName=localhost NodeAddr=127.0.0.1/p')
  [ -n "$node" ] || { cluster_log "slurmd -C printed no node line"; return 1; }
  cat >"$d/slurm.conf" <<EOF
# Written by tests/slurm/local_cluster.sh: one node, no accounting.
ClusterName=gradustest
SlurmctldHost=localhost
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$d/munge-run/munge.socket
StateSaveLocation=$d/state
SlurmdSpoolDir=$d/spool
SlurmctldPidFile=$d/slurmctld.pid
SlurmdPidFile=$d/slurmd.pid
SlurmctldDebug=info
SlurmdDebug=info
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
# Keep finished jobs' records long enough to read their state with scontrol.
MinJobAge=3600
$node State=UNKNOWN
PartitionName=test Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
  # Only this cluster: no settings inherited from an enclosing Slurm job or another cluster.
  local v
  for v in $(compgen -e | grep '^SLURM_'); do unset "$v"; done
  export SLURM_CONF=$d/slurm.conf

  slurmctld -D -i >>"$d/log/slurmctld.out" 2>&1 &
  cluster_pids+=($!)
  wait_daemon $! 30 "slurmctld to answer" scontrol ping || return 1
  slurmd -D -N localhost >>"$d/log/slurmd.out" 2>&1 &
  cluster_pids+=($!)
  wait_daemon $! 60 "the node to be idle" node_idle || { sinfo -N -l; return 1; }
  cluster_log "cluster up: $(sinfo -h -N -o '%N %T %c CPUs %m MB'), ports $port/$((port + 1))"
}

node_idle() { [ "$(sinfo -h -n localhost -o %T)" = idle ]; }

cluster_stop() {
  [ -n "$cluster_dir" ] || return 0
  if [ ${#cluster_pids[@]} -ge 2 ] && kill -0 "${cluster_pids[1]}" 2>/dev/null; then
    local jobs
    jobs=$(squeue -h -o %A 2>/dev/null | tr '\n' ' ')
    if [ -n "${jobs// /}" ]; then
      cluster_log "cancelling jobs: $jobs"
      # shellcheck disable=SC2086
      scancel $jobs 2>/dev/null
      wait_for 30 "the jobs to end" no_jobs || true
    fi
  fi
  # slurmd, then slurmctld, then munged (the reverse order of starting).
  local i pid
  for ((i = ${#cluster_pids[@]} - 1; i >= 0; i--)); do
    pid=${cluster_pids[$i]}
    kill -TERM "$pid" 2>/dev/null || continue
    wait_for 20 "pid $pid to exit" pid_gone "$pid" || kill -KILL "$pid" 2>/dev/null
    wait "$pid" 2>/dev/null
  done
  cluster_pids=()
}

no_jobs() { [ -z "$(squeue -h -o %A 2>/dev/null)" ]; }
# Gone, or a zombie waiting for the caller's `wait` (kill -0 still succeeds on one).
pid_gone() { [ ! -e "/proc/$1" ] || [ "$(sed 's/.*) //' "/proc/$1/stat" 2>/dev/null | cut -c1)" = Z ]; }

cluster_logs() {
  local f
  for f in "$cluster_dir"/log/*.out; do
    [ -s "$f" ] || continue
    echo "----- $f (last 40 lines)"
    tail -n 40 "$f"
  done
}
