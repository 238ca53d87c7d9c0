# CASA: rebuild every table, statistic and figure from the raw logs.
#
#   snakemake --cores all                  # everything
#   snakemake --cores all --configfile config/ci.yaml
#   snakemake --config allow_invalid=true  # exclude bad log files instead of stopping
#   snakemake --report report.html         # one self-contained report
#
# Every run reads profiles/default (Snakemake finds it next to the Snakefile): keep
# building the other datasets past a bad one, rerun what a killed run left incomplete.
# `--workflow-profile profiles/slurm` runs the same DAG on a Slurm cluster.
#
# Datasets are the folders of data/raw/, found when the workflow is parsed: a
# folder of casa-trial/1 logs dropped there is built on the next run.
from snakemake.utils import min_version

min_version("9.0")


configfile: "config/config.yaml"


# Every rule runs `exec casa ...`: the casa process is the job itself, a child of
# Snakemake with no shell in between. Given Snakemake's pid in CASA_PARENT_PID, it ends
# when Snakemake dies, even by SIGKILL (casa_core/cli/_lifetime.py): no orphan runs on.
shell.prefix("set -euo pipefail; export CASA_PARENT_PID=$PPID; ")


include: "workflow/rules/common.smk"
include: "workflow/rules/datasets.smk"
include: "workflow/rules/replay.smk"
include: "workflow/rules/stats.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/study.smk"
include: "workflow/rules/report.smk"
# The claims under each modelling variant; with the simulated study, part of the default
# target (`snakemake --cores all robustness` builds it alone).
include: "workflow/rules/robustness.smk"
# `snakemake --cores all power`: the simulated power of H1-H3 against participants.
include: "workflow/rules/power.smk"


# A failed run ends on why: each failed job's own message, from its log (common.smk).
onerror:
    print_failures(log)


# The report's landing page: results, figures, statistics, tables, then the workflow.
report: "workflow/report/workflow.rst"


# `snakemake --report` reports what was built of it (common.smk: built_only).
rule all:
    default_target: True
    input:
        built_only(all_outputs()),
        built_only(report_pages()),
        built_only(rules.robustness.input if SIMULATE and WHOLE_BUILD else []),
