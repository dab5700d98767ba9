"""A single-node Slurm cluster in a temporary folder, for tests (docs/farm.md "Testing").

munged with a generated key, then slurmctld and slurmd with a generated slurm.conf (proctrack/linuxproc, task/none,
select/cons_tres, one node with this machine's CPUs, one partition), on free ports; stopped by PID.
Needs root (slurmd runs jobs as their users) and Debian's slurm-wlm and munge.
"""
import os
import shutil
import signal
import socket
import subprocess
import time


class SlurmUnavailable(Exception):
    pass


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class SlurmCluster:
    def __init__(self, root):
        self.root = os.path.abspath(root)
        self.procs = []
        self.env = dict(os.environ)

    def start(self, timeout=60):
        for tool in ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "scancel"):
            if not shutil.which(tool) and not os.path.exists("/usr/sbin/" + tool):
                raise SlurmUnavailable(tool + " is not installed (Debian packages slurm-wlm and munge)")
        if os.geteuid() != 0:
            raise SlurmUnavailable("the single-node cluster needs root (slurmd starts jobs as their users)")
        r = self.root
        for d in ("munge", "state", "spool", "log"):
            os.makedirs(os.path.join(r, d), exist_ok=True)
        os.chmod(os.path.join(r, "munge"), 0o700)
        key = os.path.join(r, "munge", "munge.key")
        with open(key, "wb") as f:
            f.write(os.urandom(1024))
        os.chmod(key, 0o400)
        self.socket = os.path.join(r, "munge", "munge.socket")
        self._spawn(["/usr/sbin/munged", "--foreground", "--force", "--key-file", key, "--socket", self.socket,
                     "--pid-file", os.path.join(r, "munge", "munged.pid"), "--log-file", os.path.join(r, "log", "munged.log"),
                     "--seed-file", os.path.join(r, "munge", "munged.seed")], "munged")
        self._wait(lambda: os.path.exists(self.socket), timeout, "munged's socket")
        host = socket.gethostname()
        cpus = os.cpu_count() or 1
        conf = os.path.join(r, "slurm.conf")
        with open(conf, "w") as f:
            f.write(f"""ClusterName=specula-test
SlurmctldHost={host}
SlurmUser=root
SlurmdUser=root
SlurmctldPort={_free_port()}
SlurmdPort={_free_port()}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={self.socket}
StateSaveLocation={r}/state
SlurmdSpoolDir={r}/spool
SlurmctldPidFile={r}/slurmctld.pid
SlurmdPidFile={r}/slurmd.pid
SlurmctldLogFile={r}/log/slurmctld.log
SlurmdLogFile={r}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
KillWait=5
Waittime=0
MaxArraySize=10001
NodeName={host} CPUs={cpus} State=UNKNOWN
PartitionName=test Nodes={host} Default=YES MaxTime=INFINITE State=UP OverSubscribe=NO
""")
        self.env["SLURM_CONF"] = conf
        self._spawn(["/usr/sbin/slurmctld", "-D", "-i", "-f", conf], "slurmctld")
        self._spawn(["/usr/sbin/slurmd", "-D", "-f", conf, "-N", host], "slurmd")

        def ready():
            out = subprocess.run(["sinfo", "-h", "-o", "%T"], env=self.env, capture_output=True, text=True)
            return out.returncode == 0 and out.stdout.strip() in ("idle", "mixed", "allocated")
        try:
            self._wait(ready, timeout, "the node to come up (sinfo idle)")
        except SlurmUnavailable:
            raise SlurmUnavailable("Slurm did not come up:\n" + self.logs())
        return self

    def _spawn(self, argv, name):
        log = open(os.path.join(self.root, "log", name + ".out"), "w")
        p = subprocess.Popen(argv, env=self.env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        self.procs.append((name, p))

    def _wait(self, cond, timeout, what):
        end = time.time() + timeout
        while time.time() < end:
            for name, p in self.procs:
                if p.poll() is not None:
                    raise SlurmUnavailable(f"{name} exited with {p.returncode} while waiting for {what}:\n" + self.logs())
            if cond():
                return
            time.sleep(0.2)
        raise SlurmUnavailable("timed out waiting for " + what)

    def logs(self):
        text = ""
        for name in ("munged.out", "slurmctld.log", "slurmd.log", "slurmctld.out", "slurmd.out"):
            path = os.path.join(self.root, "log", name)
            if os.path.exists(path):
                with open(path, errors="replace") as f:
                    text += f"--- {name}\n" + "".join(f.readlines()[-15:])
        return text

    def run(self, *argv, check=True):
        out = subprocess.run(list(argv), env=self.env, capture_output=True, text=True)
        if check and out.returncode != 0:
            raise RuntimeError(f"{' '.join(argv)} failed ({out.returncode}): {out.stdout}{out.stderr}")
        return out

    def stop(self):
        # Daemons by PID (their own sessions), slurmd first; then any job step left.
        for name, p in reversed(self.procs):
            if p.poll() is None:
                try:
                    os.killpg(p.pid, signal.SIGTERM)
                except ProcessLookupError:
                    pass
        for name, p in reversed(self.procs):
            try:
                p.wait(timeout=15)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
        self.procs = []
