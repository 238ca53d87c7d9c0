"""A throwaway single-node Slurm cluster on this host, from Debian's packages.

munged, slurmctld and slurmd run in the foreground as children of the test, so that
they are stopped by their process ids. Their key, sockets, state and logs live in one
temporary folder; only ``/etc/slurm/slurm.conf`` is outside it, because a job step
reads the configuration from there (``SLURM_CONF`` does not reach it). That file
carries a marker line; a run killed before its teardown leaves it behind, and the next
run stops what the file names and replaces it.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path

SLURM_CONF = Path("/etc/slurm/slurm.conf")
MARKER = "# casa test cluster (tests/single_node_slurm.py)"
DAEMONS = ("munged", "slurmctld", "slurmd")
#: Commands the cluster and its use need, all from Debian's munge, slurmctld, slurmd.
COMMANDS = (*DAEMONS, "sbatch", "squeue", "scancel", "sinfo")
PARTITION = "main"  # the partition profiles/slurm names


def why_not() -> str | None:
    """Why no cluster can be started here, or None."""
    if not hasattr(os, "geteuid") or os.geteuid() != 0:
        return "starting munged, slurmctld and slurmd needs root"
    missing = [c for c in COMMANDS if shutil.which(c) is None]
    if missing:
        return (
            f"{', '.join(missing)} not installed (Debian: apt-get install munge slurmctld "
            "slurmd; .ci/run installs them)"
        )
    if SLURM_CONF.exists() and MARKER not in SLURM_CONF.read_text(errors="replace"):
        return f"{SLURM_CONF} belongs to another Slurm installation; the test keeps it"
    return None


def _node_line() -> str:
    """This host's node line, as slurmd itself measures it (CPUs, sockets, memory)."""
    out = subprocess.run(["slurmd", "-C"], capture_output=True, text=True, check=True).stdout
    return out.splitlines()[0] + " NodeAddr=127.0.0.1 State=UNKNOWN"


def _config(root: Path, node: str) -> str:
    name = node.split()[0].removeprefix("NodeName=")
    return "\n".join(
        [
            MARKER,
            f"# pids: {' '.join(f'{root}/{d}.child-pid' for d in reversed(DAEMONS))}",
            "ClusterName=casatest",
            f"SlurmctldHost={name}(127.0.0.1)",
            "SlurmUser=root",
            "AuthType=auth/munge",
            "CredType=cred/munge",
            f"AuthInfo=socket={root}/munge.socket",
            # No cgroups: processes are tracked and tasks launched without them.
            "ProctrackType=proctrack/linuxproc",
            "TaskPlugin=task/none",
            "MpiDefault=none",
            "JobAcctGatherType=jobacct_gather/none",
            "AccountingStorageType=accounting_storage/none",
            # Without accounting, finished jobs are seen in squeue for MinJobAge seconds
            # and in the job-completion log.
            "JobCompType=jobcomp/filetxt",
            f"JobCompLoc={root}/jobcomp.txt",
            "MinJobAge=3600",
            "MailProg=/bin/true",
            "SelectType=select/cons_tres",
            "SelectTypeParameters=CR_Core",
            "ReturnToService=2",
            f"StateSaveLocation={root}/state",
            f"SlurmdSpoolDir={root}/spool",
            f"SlurmctldPidFile={root}/slurmctld.pid",
            f"SlurmdPidFile={root}/slurmd.pid",
            f"SlurmctldLogFile={root}/slurmctld.log",
            f"SlurmdLogFile={root}/slurmd.log",
            node,
            f"PartitionName={PARTITION} Nodes={name} Default=YES MaxTime=INFINITE State=UP",
            "",
        ]
    )


def _stop(pid: int, *, name: str | None = None) -> None:
    """SIGTERM ``pid`` (if ``name`` is given, only when the process is that daemon)."""
    try:
        if name is not None and Path(f"/proc/{pid}/comm").read_text().strip() != name:
            return
        os.kill(pid, signal.SIGTERM)
    except (OSError, ValueError):
        return
    for _ in range(100):
        if not Path(f"/proc/{pid}").exists() or "Z" in _state(pid):
            return
        time.sleep(0.1)
    try:
        os.kill(pid, signal.SIGKILL)
    except OSError:
        pass


def _state(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return "X"


def clear_leftovers() -> None:
    """Stop the daemons a killed earlier run left, by the pids its config names."""
    if not SLURM_CONF.exists():
        return
    text = SLURM_CONF.read_text(errors="replace")
    if MARKER not in text:
        return
    files = [line.split()[2:] for line in text.splitlines() if line.startswith("# pids: ")]
    for pid_file in map(Path, files[0] if files else []):
        try:
            _stop(int(pid_file.read_text()), name=pid_file.name.split(".")[0])
        except (OSError, ValueError):
            pass
    for pid_file in map(Path, files[0] if files else []):
        shutil.rmtree(pid_file.parent, ignore_errors=True)
    SLURM_CONF.unlink()


class Cluster:
    """munged, slurmctld and slurmd on this host; ``stop()`` ends exactly those three."""

    def __init__(self) -> None:
        clear_leftovers()
        self.root = Path(tempfile.mkdtemp(prefix="casa-slurm-"))
        self.root.chmod(0o755)  # munged wants its socket's folder readable by all
        self.jobcomp = self.root / "jobcomp.txt"
        self._procs: list[subprocess.Popen] = []
        self._created_etc = not SLURM_CONF.parent.exists()

    def start(self, *, timeout: float = 60.0) -> Cluster:
        root = self.root
        for sub in ("state", "spool"):
            (root / sub).mkdir()
        key = root / "munge.key"
        key.write_bytes(os.urandom(128))
        key.chmod(0o600)
        SLURM_CONF.parent.mkdir(parents=True, exist_ok=True)
        SLURM_CONF.write_text(_config(root, _node_line()))
        self._spawn(
            "munged",
            ["munged", "--foreground", "--force", f"--key-file={key}"]
            + [f"--socket={root}/munge.socket", f"--pid-file={root}/munged.pid"]
            + [f"--seed-file={root}/munged.seed", f"--log-file={root}/munged.log"],
        )
        self._wait(lambda: (root / "munge.socket").exists(), timeout, "munged's socket")
        self._spawn("slurmctld", ["slurmctld", "-D", "-i"])
        self._spawn("slurmd", ["slurmd", "-D"])
        self._wait(self._idle, timeout, f"node idle in partition {PARTITION}")
        return self

    def _spawn(self, name: str, argv: list[str]) -> None:
        with open(self.root / f"{name}.out", "wb") as out:
            proc = subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT)
        self._procs.append(proc)
        (self.root / f"{name}.child-pid").write_text(f"{proc.pid}\n")

    def _idle(self) -> bool:
        out = subprocess.run(
            ["sinfo", "--noheader", "--partition", PARTITION, "--format", "%T"],
            capture_output=True,
            text=True,
        )
        return out.stdout.strip() == "idle"

    def _wait(self, ready, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while not ready():
            dead = [p.args[0] for p in self._procs if p.poll() is not None]
            if dead or time.monotonic() > deadline:
                raise RuntimeError(f"no {what} ({', '.join(dead) or 'timeout'}):\n{self.logs()}")
            time.sleep(0.5)

    def logs(self) -> str:
        """The daemons' own output, last lines of each."""
        parts = []
        for name in ("munged.out", "slurmctld.out", "slurmd.out", "slurmctld.log", "slurmd.log"):
            path = self.root / name
            if path.exists():
                tail = path.read_text(errors="replace").splitlines()[-15:]
                parts.append(f"--- {name}\n" + "\n".join(tail))
        return "\n".join(parts)

    def jobs(self) -> list[dict[str, str]]:
        """Every job slurmctld still knows (MinJobAge): id, name, comment, state, workdir."""
        fields = ("id", "name", "comment", "state", "workdir")
        out = subprocess.run(
            ["squeue", "--states=all", "--noheader", "--format=%i|%j|%k|%T|%Z"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        return [dict(zip(fields, line.split("|"), strict=True)) for line in out.splitlines()]

    def stop(self) -> None:
        """Cancel what is left, end the three daemons by pid, remove the config."""
        if any(p.poll() is None for p in self._procs):
            subprocess.run(["scancel", "--user=root"], capture_output=True, timeout=30)
        for proc in reversed(self._procs):  # slurmd, slurmctld, then munged
            _stop(proc.pid)
            proc.wait(timeout=30)
        if SLURM_CONF.exists() and MARKER in SLURM_CONF.read_text(errors="replace"):
            SLURM_CONF.unlink()
        if self._created_etc:
            shutil.rmtree(SLURM_CONF.parent, ignore_errors=True)
        shutil.rmtree(self.root, ignore_errors=True)
