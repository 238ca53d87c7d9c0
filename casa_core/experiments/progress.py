"""Progress of the long targets (power, robustness) from the jobs' Snakemake benchmarks.

Each job of these targets writes a Snakemake benchmark file (``benchmark:``, a TSV
whose ``s`` is the job's wall time) under ``benchmarks/<target>/<unit>/``, a unit being
one power replicate (``<variant>/r<replicate>``) or one robustness variant. From the
files present, :func:`read_progress` counts the units and jobs done, the time per unit
and the time left at the pace so far. Only the benchmarks of the unit's jobs count, so
that files left by jobs of another workflow version are not taken for its own. A
benchmark older than its unit's config (``data/interim/<target>/<unit>/config.yaml``,
rewritten when what the unit's jobs read changes) is from an earlier configuration and
not counted; one left by a forced rerun (``--forcerun``) counts until its job runs
again. Measured times stay in these files and in the progress log; no table of results
contains them.

Examples
--------
>>> import tempfile
>>> root = Path(tempfile.mkdtemp())
>>> (root / "v" / "r1").mkdir(parents=True)
>>> for job in ("a", "b"):
...     _ = (root / "v" / "r1" / f"{job}.tsv").write_text("s\\th:m:s\\n30.0\\t0:00:30\\n")
>>> done = read_progress(root, {"v/r1": ("a", "b"), "v/r2": ("a", "b")})
>>> done.units_done, done.jobs_done, done.seconds_per_unit
(1, 2, 60.0)
"""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from datetime import timedelta
from pathlib import Path

from casa_core.experiments.power import power_variants
from casa_core.experiments.robustness import variant_names

#: Where the jobs' benchmark files go, one folder per target (workflow/rules/*.smk).
BENCHMARKS = Path("benchmarks")
#: Where each unit's config is written: INTERIM / target / unit / "config.yaml".
INTERIM = Path("data/interim")
#: The targets that report progress and the word for their units.
UNIT_WORDS = {"power": "replicates", "robustness": "variants"}
#: The benchmarks of a power replicate's jobs (workflow/rules/power.smk): its participants'
#: protocols, one job, its tables and its detections.
REPLICATE_JOBS = ("participants", "process", "detect")
#: The benchmarks of a robustness variant's jobs (workflow/rules/robustness.smk): its
#: participants' protocols, one job, its tables, statistics, case study and claims.
VARIANT_JOBS = ("participants", "process", "stats", "case_study", "claims")


@dataclass(frozen=True)
class Progress:
    """Units and jobs done of their totals, job seconds per unit, wall time, time left."""

    units_done: int
    units_total: int
    jobs_done: int
    jobs_total: int
    seconds_per_unit: float
    elapsed: float
    remaining: float

    def line(self, target: str) -> str:
        """One line for people: done / total, time per unit, the time left.

        Examples
        --------
        >>> print(Progress(1, 4, 10, 40, 120.0, 60.0, 180.0).line("power"))
        ... # doctest: +NORMALIZE_WHITESPACE
        power: 1/4 replicates done (10/40 jobs); 120 s of job time per replicate;
        0:01:00 elapsed, about 0:03:00 left
        """
        word = UNIT_WORDS.get(target, "units")
        per = "unknown" if math.isnan(self.seconds_per_unit) else f"{self.seconds_per_unit:.0f} s"
        left = "unknown" if math.isnan(self.remaining) else _clock(self.remaining)
        return (
            f"{target}: {self.units_done}/{self.units_total} {word} done "
            f"({self.jobs_done}/{self.jobs_total} jobs); {per} of job time per "
            f"{word.removesuffix('s')}; {_clock(self.elapsed)} elapsed, about {left} left"
        )


def _clock(seconds: float) -> str:
    return str(timedelta(seconds=round(seconds)))


def _job_seconds(path: Path) -> float:
    """The ``s`` column of a Snakemake benchmark file (its mean over repeats)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    if len(lines) < 2:
        return math.nan
    column = lines[0].split("\t").index("s")
    values = [float(line.split("\t")[column]) for line in lines[1:] if line.strip()]
    return sum(values) / len(values) if values else math.nan


def read_progress(
    root: Path | str,
    units: Mapping[str, Collection[str]],
    *,
    configs: Mapping[str, Path] | None = None,
) -> Progress:
    """The progress of a target whose unit ``u`` has the jobs ``units[u]`` under ``root / u``.

    A job is done when its benchmark file ``root / u / <job>.tsv`` exists (Snakemake
    writes it when the job ends) and is not older than the unit's config in ``configs``
    (if given and present); a unit when all its jobs are. Other files in the folder are
    not counted. The time left is the remaining jobs at the mean job time so far, divided
    by the parallelism so far (job time done over the wall time from the first job's
    start to the last one's end).
    """
    root = Path(root)
    configs = configs or {}
    done_units, jobs_done, job_time, unit_times = 0, 0, 0.0, []
    starts, ends = [], []
    for unit, jobs in units.items():
        files = [root / unit / f"{job}.tsv" for job in jobs]
        config = Path(configs[unit]) if unit in configs else None
        since = config.stat().st_mtime if config is not None and config.is_file() else -math.inf
        seconds = []
        for path in files:
            if not path.is_file():
                continue
            value, end = _job_seconds(path), path.stat().st_mtime
            if math.isnan(value) or end < since:
                continue
            seconds.append(value)
            starts.append(end - value)
            ends.append(end)
        jobs_done += len(seconds)
        job_time += sum(seconds)
        if len(seconds) == len(jobs):
            done_units += 1
            unit_times.append(sum(seconds))
    jobs_total = sum(len(jobs) for jobs in units.values())
    elapsed = max(ends) - min(starts) if ends else 0.0
    per_job = job_time / jobs_done if jobs_done else math.nan
    parallel = job_time / elapsed if elapsed > 0 else math.nan
    remaining = (jobs_total - jobs_done) * per_job / parallel if jobs_done else math.nan
    per_unit = sum(unit_times) / len(unit_times) if unit_times else math.nan
    return Progress(
        done_units, len(units), jobs_done, jobs_total, per_unit, elapsed, max(remaining, 0.0)
    )


def target_units(config: Mapping, target: str) -> dict[str, tuple[str, ...]]:
    """The units of ``target`` (``power`` or ``robustness``) and their jobs' benchmarks.

    Examples
    --------
    >>> from casa_core.config import DEFAULT_CONFIG, load_config
    >>> units = target_units(load_config(DEFAULT_CONFIG), "power")
    >>> len(units), units["default/r1"]
    (200, ('participants', 'process', 'detect'))
    >>> target_units(load_config(DEFAULT_CONFIG), "robustness")["paper"]
    ('participants', 'process', 'stats', 'case_study', 'claims')
    """
    if target == "power":
        replicates = range(1, config["power"]["replicates"] + 1)
        return {f"{v}/r{r}": REPLICATE_JOBS for v in power_variants(config) for r in replicates}
    if target == "robustness":
        return {name: VARIANT_JOBS for name in variant_names(config)}
    raise ValueError(f"progress: no target {target!r} (targets: {', '.join(UNIT_WORDS)})")


def unit_configs(
    target: str, units: Mapping[str, object], workflow: Path | str = "."
) -> dict[str, Path]:
    """Each unit's config file, as the workflow in folder ``workflow`` writes it (:data:`INTERIM`).

    Examples
    --------
    >>> unit_configs("power", {"default/r1": 5})
    {'default/r1': PosixPath('data/interim/power/default/r1/config.yaml')}
    >>> unit_configs("robustness", {"paper": 15}, "/work/casa")["paper"].as_posix()
    '/work/casa/data/interim/robustness/paper/config.yaml'
    """
    return {unit: Path(workflow) / INTERIM / target / unit / "config.yaml" for unit in units}
