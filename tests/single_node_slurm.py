"""A throwaway single-node Slurm cluster on this host, from Debian's packages.

munged, slurmctld and slurmd (and, where installed, MariaDB and slurmdbd for accounting)
run in the foreground as children of the test, so that they are stopped by their process
ids. Their keys, sockets, state, database and logs live in one temporary folder; only
the configuration is outside it, in ``/etc/slurm``, because a job step reads it from
there (``SLURM_CONF`` does not reach it). Those files carry a marker line; a run killed
before its teardown leaves them behind, and the next run stops what they name and
replaces them.
"""

from __future__ import annotations

import os
import secrets
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path

SLURM_CONF = Path("/etc/slurm/slurm.conf")
DBD_CONF = SLURM_CONF.with_name("slurmdbd.conf")
MARKER = "# casa test cluster (tests/single_node_slurm.py)"
#: In the order they start; they stop in the reverse order.
DAEMONS = ("munged", "mariadbd", "slurmdbd", "slurmctld", "slurmd")
#: What the cluster and its use need, from Debian's munge, slurmctld, slurmd.
COMMANDS = ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "scancel", "sinfo")
#: What accounting needs, from Debian's mariadb-server and slurmdbd.
ACCOUNTING = ("mariadbd", "mariadb-install-db", "mariadb", "slurmdbd", "sacctmgr", "sacct")
PARTITION = "main"  # the partition profiles/slurm names
CLUSTER = "casatest"


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
    for conf in (SLURM_CONF, DBD_CONF):
        if conf.exists() and MARKER not in conf.read_text(errors="replace"):
            return f"{conf} belongs to another Slurm installation; the test keeps it"
    return None


def accounting_why_not() -> str | None:
    """Why the cluster runs without accounting (sacct), or None."""
    missing = [c for c in ACCOUNTING if shutil.which(c) is None]
    if missing:
        return (
            f"{', '.join(missing)} not installed (Debian: apt-get install mariadb-server "
            "slurmdbd; .ci/run installs them)"
        )
    return None


def _node_line() -> str:
    """This host's node line, as slurmd itself measures it (CPUs, sockets, memory)."""
    out = subprocess.run(["slurmd", "-C"], capture_output=True, text=True, check=True).stdout
    return out.splitlines()[0] + " NodeAddr=127.0.0.1 State=UNKNOWN"


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _lines(root: Path, *settings: str) -> str:
    pids = " ".join(f"{root}/{d}.child-pid" for d in reversed(DAEMONS))
    return "\n".join([MARKER, f"# pids: {pids}", *settings, ""])


def _slurm_conf(root: Path, node: str, *, accounting: bool) -> str:
    name = node.split()[0].removeprefix("NodeName=")
    if accounting:
        storage = ["AccountingStorageType=accounting_storage/slurmdbd"]
        storage += ["AccountingStorageHost=localhost", "AccountingStoreFlags=job_comment"]
        # The munge socket for slurmdbd connections (AuthInfo does not reach them).
        storage += [f"AccountingStoragePass={root}/munge.socket"]
    else:
        storage = ["AccountingStorageType=accounting_storage/none"]
    return _lines(
        root,
        f"ClusterName={CLUSTER}",
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
        *storage,
        # Finished jobs stay in squeue for MinJobAge seconds, and in the completion log.
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
    )


def _stop(pid: int, *, name: str | None = None) -> None:
    """SIGTERM ``pid`` (if ``name`` is given, only when the process is that daemon)."""
    try:
        if name is not None and Path(f"/proc/{pid}/comm").read_text().strip() != name:
            return
        os.kill(pid, signal.SIGTERM)
    except (OSError, ValueError):
        return
    for _ in range(150):
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
    ours = [c for c in (SLURM_CONF, DBD_CONF) if c.exists() and MARKER in c.read_text()]
    named = [line for c in ours for line in c.read_text().splitlines() if "# pids: " in line]
    pid_files = [Path(f) for f in named[0].split()[2:]] if named else []  # slurmd first
    for pid_file in pid_files:
        try:
            _stop(int(pid_file.read_text()), name=pid_file.name.split(".")[0])
        except (OSError, ValueError):
            pass
    if pid_files:
        shutil.rmtree(pid_files[0].parent, ignore_errors=True)
    for conf in ours:
        conf.unlink()


class Cluster:
    """The daemons on this host; ``stop()`` ends exactly those it started."""

    def __init__(self, *, accounting: bool) -> None:
        clear_leftovers()
        self.accounting = accounting
        self.root = Path(tempfile.mkdtemp(prefix="casa-slurm-"))
        self.root.chmod(0o755)  # munged wants its socket's folder readable by all
        self.jobcomp = self.root / "jobcomp.txt"
        self._procs: list[subprocess.Popen] = []
        self._created_etc = not SLURM_CONF.parent.exists()

    def start(self, *, timeout: float = 90.0) -> Cluster:
        root = self.root
        for sub in ("state", "spool"):
            (root / sub).mkdir()
        key = root / "munge.key"
        key.write_bytes(os.urandom(128))
        key.chmod(0o600)
        SLURM_CONF.parent.mkdir(parents=True, exist_ok=True)
        conf = _slurm_conf(root, _node_line(), accounting=self.accounting)
        SLURM_CONF.write_text(conf)
        self._spawn(
            "munged",
            ["munged", "--foreground", "--force", f"--key-file={key}"]
            + [f"--socket={root}/munge.socket", f"--pid-file={root}/munged.pid"]
            + [f"--seed-file={root}/munged.seed", f"--log-file={root}/munged.log"],
        )
        self._wait(lambda: (root / "munge.socket").exists(), timeout, "munged's socket")
        if self.accounting:
            self._start_accounting(timeout)
        self._spawn("slurmctld", ["slurmctld", "-D", "-i"])
        self._spawn("slurmd", ["slurmd", "-D"])
        self._wait(self._idle, timeout, f"node idle in partition {PARTITION}")
        return self

    def _start_accounting(self, timeout: float) -> None:
        """MariaDB on a loopback port of its own, slurmdbd on it, the cluster registered."""
        root, port, password = self.root, _free_port(), secrets.token_hex(16)
        db = [f"--datadir={root}/db", "--user=root"]
        subprocess.run(
            ["mariadb-install-db", "--no-defaults", *db, "--skip-test-db"]
            + ["--auth-root-authentication-method=socket"],
            capture_output=True,
            check=True,
        )
        self._spawn(
            "mariadbd",
            ["mariadbd", "--no-defaults", *db, f"--socket={root}/mysql.sock"]
            + ["--bind-address=127.0.0.1", f"--port={port}", f"--pid-file={root}/db.pid"],
        )
        sql = ["mariadb", "--no-defaults", f"--socket={root}/mysql.sock", "--user=root"]
        self._wait(
            lambda: subprocess.run([*sql, "-e", "SELECT 1"], capture_output=True).returncode == 0,
            timeout,
            "MariaDB",
        )
        grant = (
            f"CREATE USER 'slurm'@'127.0.0.1' IDENTIFIED BY '{password}';"
            "GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';"
        )
        subprocess.run([*sql, "-e", grant], capture_output=True, check=True)
        DBD_CONF.write_text(
            _lines(
                root,
                "AuthType=auth/munge",
                f"AuthInfo=socket={root}/munge.socket",
                "DbdHost=localhost",
                "SlurmUser=root",
                "StorageType=accounting_storage/mysql",
                "StorageHost=127.0.0.1",
                f"StoragePort={port}",
                "StorageUser=slurm",
                f"StoragePass={password}",
                "StorageLoc=slurm_acct_db",
                f"PidFile={root}/slurmdbd.pid",
                f"LogFile={root}/slurmdbd.log",
            )
        )
        DBD_CONF.chmod(0o600)  # slurmdbd refuses a readable password
        self._spawn("slurmdbd", ["slurmdbd", "-D"])
        add = ["sacctmgr", "--immediate", "add", "cluster", CLUSTER]
        self._wait(
            lambda: subprocess.run(add, capture_output=True, timeout=30).returncode == 0,
            timeout,
            "slurmdbd",
        )

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
        for path in sorted(self.root.glob("*.out")) + sorted(self.root.glob("*.log")):
            tail = path.read_text(errors="replace").splitlines()[-15:]
            parts.append(f"--- {path.name}\n" + "\n".join(tail))
        return "\n".join(parts)

    def jobs(self) -> list[dict[str, str]]:
        """Every job slurmctld still knows (MinJobAge): id, name, comment, state, workdir."""
        return _table(["squeue", "--states=all", "--noheader", "--format=%i|%j|%k|%T|%Z"])

    def accounted_jobs(self) -> list[dict[str, str]]:
        """Every job of the accounting database (sacct): the same fields."""
        return _table(
            ["sacct", "--allocations", "--noheader", "--parsable2", "--starttime=now-1days"]
            + ["--format=JobID,JobName,Comment,State,WorkDir"]
        )

    def stop(self) -> None:
        """Cancel what is left, end the daemons it started by pid, remove the config."""
        if any(p.poll() is None for p in self._procs):
            subprocess.run(["scancel", "--user=root"], capture_output=True, timeout=30)
        for proc in reversed(self._procs):
            _stop(proc.pid)
            proc.wait(timeout=30)
        for conf in (SLURM_CONF, DBD_CONF):
            if conf.exists() and MARKER in conf.read_text(errors="replace"):
                conf.unlink()
        if self._created_etc:
            shutil.rmtree(SLURM_CONF.parent, ignore_errors=True)
        shutil.rmtree(self.root, ignore_errors=True)


def _table(argv: list[str]) -> list[dict[str, str]]:
    fields = ("id", "name", "comment", "state", "workdir")
    out = subprocess.run(argv, capture_output=True, text=True, check=True).stdout
    return [dict(zip(fields, line.split("|"), strict=True)) for line in out.splitlines()]
