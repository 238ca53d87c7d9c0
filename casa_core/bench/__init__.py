"""Every benchmark (``casa bench``) and its targets.

The modules, each with one job:

- :mod:`~casa_core.bench.suite`: ``casa bench``: every benchmark of the package.
- :mod:`~casa_core.bench.protocol`: ``casa bench``: one simulated participant's whole
  protocol, and its learning, timed.
- :mod:`~casa_core.bench.trial`: ``casa bench``: a whole simulated CASA trial, timed, and
  its pybullet work alone.
- :mod:`~casa_core.bench.stages`: ``casa bench``: where a trial's and a protocol's CPU
  time goes.
"""

from casa_core.bench.protocol import (
    TARGETS,
    participant_benchmark,
    target_met,
)
from casa_core.bench.stages import PROTOCOL_STAGES, StageClock
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
    untrained_neural_intent,
)
from casa_core.bench.trial import TRIAL_SECONDS, trial_physics_cpu_s, trial_realtime_factor

__all__ = [
    "PROTOCOL_STAGES",
    "SCALING_SIZES",
    "StageClock",
    "TRIAL_SECONDS",
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
    "trial_physics_cpu_s",
    "trial_realtime_factor",
    "untrained_neural_intent",
]
