"""The targets that run many studies: robustness variants, power replicates, their progress.

The modules, each with one job:

- :mod:`~casa_core.experiments.robustness`: Modelling variants of the simulated study: the
  config's ``robustness`` block.
- :mod:`~casa_core.experiments.power`: The power analysis' replicate studies: their seeds,
  configs and the jobs they take.
- :mod:`~casa_core.experiments.progress`: Progress of the long targets (power, robustness)
  from the jobs' Snakemake benchmarks.
"""

from casa_core.experiments.power import (
    POWER_STREAM,
    power_sizes,
    power_variant_config,
    power_variants,
    replicate_config,
    replicate_seed,
    replicate_seeds,
)
from casa_core.experiments.progress import (
    BENCHMARKS,
    INTERIM,
    REPLICATE_JOBS,
    UNIT_WORDS,
    VARIANT_JOBS,
    Progress,
    read_progress,
    target_units,
    unit_configs,
)
from casa_core.experiments.robustness import (
    OVERLAY_KEYS,
    RUNNING_BLOCKS,
    settings_text,
    setup_text,
    variant_config,
    variant_names,
)

__all__ = [
    "BENCHMARKS",
    "INTERIM",
    "OVERLAY_KEYS",
    "POWER_STREAM",
    "Progress",
    "REPLICATE_JOBS",
    "RUNNING_BLOCKS",
    "UNIT_WORDS",
    "VARIANT_JOBS",
    "power_sizes",
    "power_variant_config",
    "power_variants",
    "read_progress",
    "replicate_config",
    "replicate_seed",
    "replicate_seeds",
    "settings_text",
    "setup_text",
    "target_units",
    "unit_configs",
    "variant_config",
    "variant_names",
]
