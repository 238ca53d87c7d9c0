# Config validation, the study's vocabulary, dataset discovery and the list of outputs.
# No rules here.
import functools
import os
import re
import shlex
import sys
from pathlib import Path

from casa_core import config as casa_config
from casa_core.experiments import power as casa_power
from casa_core.experiments import robustness as casa_variants
from casa_core import vocabulary
from casa_core.io.population import population_label
from casa_core.io.atomic import atomic_write_text
from casa_core.io.workflow_log import failure_summary
from casa_core.io.contract import INTENT_SUFFIX
from casa_core.scene import DEFAULT_SCENE


def config_layers():
    """The config files in the order Snakemake merges them: the Snakefile's, then --configfile's."""
    settings = workflow.config_settings
    given = list(settings.configfiles)
    own = [] if settings.replace_workflow_config else workflow.configfiles[len(given) :]
    shown = []
    for path in map(str, [*own, *given]):
        relative = os.path.relpath(path)
        shown.append(path if relative.startswith("..") else relative)
    return shown


# Validated once, here (casa_core/config.schema.yaml: every key, its type, range and
# default); each problem names the file, the dotted key and the rule it breaks.
config.clear()
config.update(casa_config.load_config(*config_layers(), overrides=workflow.config_settings.config))
# A config without a scene (the schema's default, null) means the package's own, as for casa.
config["scene"] = config["scene"] or os.path.relpath(DEFAULT_SCENE)
# A population fitted by `casa calibrate` (docs/calibration.md): read here, so that a bad
# file stops the run before any job, naming its key; the simulating rules take it as input.
OPERATOR_POPULATION = [p for p in [config["simulation"]["operator_population"]] if p]
population_label(config["simulation"])


def effective_config_file(path=Path("data/interim/config.yaml"), settings=None):
    """The validated config, --config overrides and schema defaults included, for the package.

    The package commands read a config file; this one is what the workflow itself
    sees, so that `--config KEY=VALUE` reaches them too, less the keys that only choose
    the targets (casa_core.config.TARGET_KEYS: datasets, simulate). It is rewritten only
    when its content changes, so that an unchanged config reruns nothing and keeps its
    mtime (the one `casa progress` compares benchmarks with). `settings`: another whole
    config to write instead (a robustness variant's).
    """
    settings = config if settings is None else settings
    jobs_read = {k: v for k, v in settings.items() if k not in casa_config.TARGET_KEYS}
    text = casa_config.config_text(jobs_read)
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        atomic_write_text(path, text)
    return str(path)


CONFIG_FILE = effective_config_file()

# The simulated study is the dataset data/raw/simulated, and the case study's tables
# and figures (workflow/rules/study.smk) and the robustness target join the default
# target; `--config simulate=false` builds only the datasets already in data/raw.
SIMULATE = config["simulate"]
CASE_STUDY = config["simulate"]

RAW = Path("data/raw")
PROCESSED = Path("data/processed")
FIGURES = Path("figures")
# The jobs' Snakemake benchmark files (their times), read by `casa progress`.
BENCHMARKS = Path("benchmarks")
# Dataset names become folder and file names: keep them portable.
DATASET_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")
# Outputs of the dataset-independent rules live here; no dataset may take the name.
RESERVED = ("case_study", "robustness", "power")
# The tasks whose intents the simulated participants teach (workflow/rules/study.smk).
UNKNOWN_TASKS = vocabulary.UNKNOWN_TASKS
# Datasets that rules of this workflow write into data/raw (the simulated study).
SIMULATED_NAME = "simulated"
GENERATED = (SIMULATED_NAME,) if SIMULATE else ()


# Dataset folders whose names are refused: a key (a portable name) and the reason. Each
# is a target that fails (workflow/rules/datasets.smk), so that the other datasets build
# and the run still stops on it.
REFUSED = {}
REFUSED_LOGS = Path("logs/refused")


def discover_datasets():
    """The folders of data/raw (hidden ones skipped), plus the datasets rules generate.

    Without `simulate`, data/raw/simulated is not a dataset: the simulated study's logs
    and outputs are left as they are, not rebuilt as an ordinary dataset's.
    """
    found = set(GENERATED)
    if RAW.is_dir():
        found |= {p.name for p in RAW.iterdir() if p.is_dir() and not p.name.startswith(".")}
    if not SIMULATE and SIMULATED_NAME in found:
        found.discard(SIMULATED_NAME)
        print(
            f"data/raw/{SIMULATED_NAME}: the simulated study, left as it is with its outputs "
            "(simulate=false)",
            file=sys.stderr,
        )
    refused = sorted(n for n in found if not DATASET_NAME.fullmatch(n) or n in RESERVED)
    for name in refused:
        key = portable_name(name)
        key = f"{key}_{len(REFUSED)}" if key in REFUSED else key
        REFUSED[key] = (
            f"data/raw/{name}: a dataset folder name must match {DATASET_NAME.pattern} and "
            f"not be one of {', '.join(RESERVED)}; rename it, e.g. to data/raw/"
            f"{portable_name(name)}, and run again (the other datasets are built)"
        )
        fate = "not built" if config["datasets"] else "the run fails on it"
        print(f"{REFUSED[key]}; {fate}", file=sys.stderr)
    return sorted(set(found) - set(refused))


def portable_name(name):
    """A dataset name like `name` that DATASET_NAME allows and RESERVED does not hold."""
    portable = re.sub(r"[^A-Za-z0-9_-]+", "_", name).strip("_-") or "dataset"
    return f"{portable}_data" if portable in RESERVED else portable


def chosen_datasets():
    """The datasets of the default target: config `datasets`, else every one."""
    unknown = [name for name in config["datasets"] if name not in DATASETS]
    refused = [name for name in unknown if (RAW / name).is_dir() and name not in GENERATED]
    if refused:
        name = refused[0]
        raise ValueError(
            f"datasets: data/raw/{name} is a folder whose name a dataset cannot take (it "
            f"must match {DATASET_NAME.pattern} and not be one of {', '.join(RESERVED)}); "
            f"rename it, e.g. to data/raw/{portable_name(name)}, and choose "
            f"datasets=[{portable_name(name)}]"
        )
    if unknown:
        raise ValueError(
            f"datasets: {', '.join(unknown)} is not a dataset (found: "
            f"{', '.join(DATASETS) or 'none'}); name folders of data/raw"
            + ("" if SIMULATE else f", or set simulate=true for {SIMULATED_NAME}")
        )
    return list(config["datasets"]) or DATASETS


DATASETS = discover_datasets()
# The default target: the chosen datasets, and only when none is chosen the case study
# and the robustness target too.
TARGET_DATASETS = chosen_datasets()
WHOLE_BUILD = not config["datasets"]


wildcard_constraints:
    ds="|".join(re.escape(d) for d in DATASETS) or "(?!)",
    refused="|".join(re.escape(key) for key in REFUSED) or "(?!)",


def raw_files(wildcards):
    """Every non-hidden file of a dataset and its learned intents (also in hidden folders:
    .session/library/), so that a changed or added log or intent reruns it."""
    if wildcards.ds in GENERATED:
        return [RAW / wildcards.ds / ".complete"]
    files = []
    for path in sorted((RAW / wildcards.ds).rglob("*")):
        parts = path.relative_to(RAW).parts
        hidden = any(part.startswith(".") for part in parts)
        if path.is_file() and (not hidden or path.name.endswith(INTENT_SUFFIX)):
            files.append(str(path))
    return files


def dataset_scene(wildcards):
    """A dataset's own scene.yaml (an imported dataset carries its layout), else config's."""
    own = RAW / wildcards.ds / "scene.yaml"
    return str(own) if own.is_file() else config["scene"]


def setup_option(wildcards=None):
    """`--setup` of a figure: the setup a dataset's data come from (a generated dataset's,
    the config's; another's, its own scene), or the config's for the case study."""
    if wildcards is None or wildcards.ds in GENERATED:
        text = casa_variants.setup_text(config)
    else:
        text = casa_variants.setup_text({"scene": dataset_scene(wildcards)})
    return f"--setup {shlex.quote(text)}" if text else ""


def has_surveys(ds):
    """Whether a dataset has Likert answers; generated datasets always do."""
    return ds in GENERATED or any((RAW / ds).rglob("surveys.csv"))


def likert_option(wildcards, input):
    """Pass the Likert table to the statistics only when the dataset has surveys."""
    return f"--likert {input.likert}" if has_surveys(wildcards.ds) else ""


def allow_invalid_flag(wildcards=None):
    return "--allow-invalid" if config["allow_invalid"] else ""


def print_failures(snakemake_logs):
    """Print, last, what each failed job said (casa_core.io.workflow_log), from Snakemake's logs."""
    logs = [snakemake_logs] if isinstance(snakemake_logs, str) else snakemake_logs or []
    paths = [path for path in map(Path, logs) if path.is_file()]
    text = "\n".join(path.read_text(encoding="utf-8", errors="replace") for path in paths)
    summary = failure_summary(text, allow_invalid=config["allow_invalid"])
    if summary:
        print(summary, file=sys.stderr, flush=True)


def dataset_outputs(ds):
    tables = ["trials", "steps", "likert", "stats", "wide", "validation"]
    outputs = [str(PROCESSED / ds / f"{name}.csv") for name in tables]
    outputs.append(str(PROCESSED / ds / "stats.md"))
    # Each claim of the paper with its criterion and verdict (workflow/rules/report.smk).
    outputs.append(str(PROCESSED / ds / "results.md"))
    figures = ["objective"] + (["likert"] if has_surveys(ds) else [])
    outputs += [str(FIGURES / ds / f"{f}.{ext}") for f in figures for ext in ("pdf", "png")]
    # Each assisted trial replayed (workflow/rules/replay.smk).
    outputs += [str(PROCESSED / ds / "replay"), str(FIGURES / ds / "replay")]
    return outputs


def all_outputs():
    outputs = [out for ds in TARGET_DATASETS for out in dataset_outputs(ds)]
    # A refused dataset folder fails the default target, whose other jobs still run.
    outputs += [str(REFUSED_LOGS / f"{key}.refused") for key in REFUSED if WHOLE_BUILD]
    outputs.append(str(FIGURES / "scene.png"))
    if CASE_STUDY and WHOLE_BUILD:
        outputs += [str(PROCESSED / "case_study" / f) for f in ("steps.csv", "arbitration.csv")]
        outputs += [
            str(FIGURES / f"{f}.{e}") for f in ("case_study", "arbitration") for e in ("pdf", "png")
        ]
    return outputs


# The HTML report's pages (workflow/rules/report.smk).
REPORT = Path("data/report")
# The tables of every dataset; the simulated study also has learning.csv.
REPORT_TABLES = ("trials", "validation")


# `snakemake --report`: Snakemake stops on a report item of the DAG that does not exist,
# so that the report of a run that built one dataset would fail on the others'. It
# reports what was built instead (built_only). Snakemake tells the Snakefile nothing of
# the report, hence its command line; --report-after-run builds first, so everything.
REPORTING = any(arg == "--report" or arg.startswith("--report=") for arg in sys.argv) and (
    "--report-after-run" not in sys.argv
)


def built_only(paths):
    """The default target's `paths`; for a report (REPORTING), those that exist."""
    return [path for path in map(str, paths) if Path(path).exists()] if REPORTING else paths


def report_pages():
    pages = [str(PROCESSED / ds / "summary.md") for ds in TARGET_DATASETS]
    names = ("results", "summary", "stats", *REPORT_TABLES)
    pages += [str(REPORT / ds / f"{name}.html") for ds in TARGET_DATASETS for name in names]
    if SIMULATE and SIMULATED_NAME in TARGET_DATASETS:
        pages.append(str(REPORT / "simulated" / "learning.html"))
    return pages


def results_input(wildcards):
    """The tables results.md judges; the simulated study's also the case study's.

    The case study runs along the config's scene, the simulated study's, so its claims
    (C3, and C1, C2, C4 on the expert) are judged there; another dataset's results.md
    says it cannot test C3.
    """
    folder = PROCESSED / wildcards.ds
    names = ("trials", "steps", "stats", "likert", "validation")
    tables = {name: folder / f"{name}.csv" for name in names}
    if CASE_STUDY and wildcards.ds in GENERATED:
        tables["arbitration"] = PROCESSED / "case_study" / "arbitration.csv"
        tables["case_steps"] = PROCESSED / "case_study" / "steps.csv"
    return tables


def case_study_options(wildcards, input):
    """The case study's tables as options of `casa report results`, when they are inputs."""
    names = {"arbitration": "--arbitration", "case_steps": "--case-steps"}
    paths = {flag: getattr(input, name, None) for name, flag in names.items()}
    return " ".join(f"{flag} {path}" for flag, path in paths.items() if path)


def operator_option(wildcards):
    """The setup and operator model of a generated dataset, named in its results.md."""
    if wildcards.ds not in GENERATED:
        return ""
    option = f"--operator {config['simulation']['operator']}"
    option += f" --setup {shlex.quote(casa_variants.setup_text(config))}"
    if OPERATOR_POPULATION:
        option += f" --population {shlex.quote(population_label(config['simulation']))}"
    return option


def stats_input(wildcards):
    """The tables of the statistics; statistics left beside missing tables are removed.

    Snakemake keeps an output whose inputs were deleted (a failed processing step
    deletes its tables), so such statistics would describe tables that are gone;
    removed here, they are rebuilt with the tables. A dry run only says so.
    """
    folder = PROCESSED / wildcards.ds
    tables = {name: folder / f"{name}.csv" for name in ("trials", "likert", "validation")}
    if not all(path.exists() for path in tables.values()):
        for stale in (folder / "stats.csv", folder / "stats.md"):
            if stale.exists() and workflow.dryrun:
                print(f"{stale}: its tables are missing; a run rebuilds it", file=sys.stderr)
            elif stale.exists():
                stale.unlink()
    return tables


# The robustness target's modelling variants (workflow/rules/robustness.smk;
# casa_core/experiments/robustness.py): each variant's whole config, written as the study's is.
VARIANTS = casa_variants.variant_names(config)
ROBUST_INTERIM = Path("data/interim/robustness")
ROBUST = PROCESSED / "robustness"
ROBUST_PARTICIPANTS = list(range(1, config["robustness"]["participants"] + 1))


def participant_path(folder, *parts):
    """For params: ``folder / parts``, ``folder``'s wildcards filled in and {p} left for
    casa simulate protocol to fill in with each participant's number, quoted."""
    return lambda wildcards: shlex.quote(str(Path(str(folder).format(**wildcards)) / Path(*parts)))


def participant_paths(folder, *templates):
    """For params: :func:`participant_path` of each template, space-separated."""
    return lambda wildcards: " ".join(
        participant_path(folder, template)(wildcards) for template in templates
    )


VARIANT_SETTINGS = {name: casa_variants.variant_config(config, name) for name in VARIANTS}
VARIANT_CONFIGS = {
    name: effective_config_file(ROBUST_INTERIM / name / "config.yaml", settings)
    for name, settings in VARIANT_SETTINGS.items()
}


# The power target's variants (workflow/rules/power.smk) may be others of robustness.variants.
POWER_VARIANTS = casa_power.power_variants(config)


wildcard_constraints:
    variant="|".join(re.escape(v) for v in dict.fromkeys(VARIANTS + POWER_VARIANTS)) or "(?!)",


def variant_config_input(wildcards):
    """The config of a robustness variant's job."""
    return VARIANT_CONFIGS[wildcards.variant]


def variant_scene_input(wildcards):
    """The scene file of a robustness variant (its overlay may name another setup)."""
    return VARIANT_SETTINGS[wildcards.variant]["scene"]


def margin_options(wildcards=None):
    """The config's non-inferiority margins (statistics) as casa stats options."""
    from casa_core.stats.margins import Margins

    return " ".join(Margins.from_config(config["statistics"]).options())


# The power target (workflow/rules/power.smk; casa_core/experiments/power.py): replicate studies of
# each variant of power.variants, each with its own seed.
POWER_INTERIM = Path("data/interim/power")
POWER = PROCESSED / "power"
POWER_BENCHMARKS = BENCHMARKS / "power"
POWER_SIZES = casa_power.power_sizes(config)
POWER_PARTICIPANTS = list(range(1, max(POWER_SIZES) + 1))
POWER_REPLICATES = list(range(1, config["power"]["replicates"] + 1))
# Stops here if two replicates would share a seed (each seed is a hash of the study's).
casa_power.replicate_seeds(config["simulation"]["seed"], len(POWER_REPLICATES))
# A replicate's folder, benchmark folder (its jobs' times, for casa progress) and logs.
REPLICATE = POWER_INTERIM / "{variant}" / "r{r}"
REPLICATE_BENCHMARKS = POWER_BENCHMARKS / "{variant}" / "r{r}"
REPLICATE_LOGS = "logs/power/{variant}/r{r}"


# Each variant's config for the power target, computed once (replicates differ in seed).
POWER_VARIANT_CONFIGS = {
    name: casa_power.power_variant_config(config, name) for name in POWER_VARIANTS
}


@functools.cache
def replicate_config_file(variant, r):
    """Replicate r's config file, written the first time a job of it is planned."""
    settings = casa_power.replicate_config(POWER_VARIANT_CONFIGS[variant], int(r))
    return effective_config_file(POWER_INTERIM / variant / f"r{r}" / "config.yaml", settings)


def replicate_config_input(wildcards):
    return replicate_config_file(wildcards.variant, wildcards.r)


def power_scene_input(wildcards):
    """The scene file of a power variant."""
    return POWER_VARIANT_CONFIGS[wildcards.variant]["scene"]


wildcard_constraints:
    r=r"\d+",


# Which configuration built an output: results.md, the robustness table and the power
# figure name the config files layered and the sha256 of the effective config
# (casa_core.config.Provenance). The rule's `config` input is that file, so an output
# naming it is rebuilt when it changes.


def provenance_options(wildcards, input):
    """`--config-files` (config_layers()) and `--effective-config` (the rule's config input)."""
    files = " ".join(shlex.quote(path) for path in config_layers())
    return f"--config-files {files} --effective-config {shlex.quote(str(input.config))}"
