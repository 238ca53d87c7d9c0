"""Every benchmark (``casa bench``) and its targets.

The modules, each with one job:

- :mod:`~casa_core.bench.suite`: ``casa bench``: every benchmark of the package.
- :mod:`~casa_core.bench.protocol`: ``casa bench``: one simulated participant's whole
  protocol, and its learning, timed.
"""

from casa_core.bench.protocol import (
    TARGETS,
    participant_benchmark,
    target_met,
)
from casa_core.bench.suite import (
    SCALING_SIZES,
    WORKSPACE,
    assistance_benchmarks,
    bench_trajectory,
    format_table,
    goal_intents,
    linear_fit_r2,
    run_benchmarks,
    time_assistance_step,
    time_assistance_steps,
    trial_realtime_factor,
    untrained_neural_intent,
)

__all__ = [
    "SCALING_SIZES",
    "TARGETS",
    "WORKSPACE",
    "assistance_benchmarks",
    "bench_trajectory",
    "format_table",
    "goal_intents",
    "linear_fit_r2",
    "participant_benchmark",
    "run_benchmarks",
    "target_met",
    "time_assistance_step",
    "time_assistance_steps",
    "trial_realtime_factor",
    "untrained_neural_intent",
]
