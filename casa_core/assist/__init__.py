"""Assistance: intents as costs, the assistant's step, the presets, the intended paths.

The modules, each with one job:

- :mod:`~casa_core.assist.intents`: Intents as cost functions (paper, Sec. II-A).
- :mod:`~casa_core.assist.assistant`: One assistance step: inference, confidence,
  arbitration and policy blending.
- :mod:`~casa_core.assist.presets`: Presets of inference: the paper's equations, the
  original implementation's numerics, ours.
- :mod:`~casa_core.assist.tasks`: The study's tasks and the trajectory each one intends.
- :mod:`~casa_core.assist.trial`: The assistant of one trial in a scene: how often it infers
  and how it is built.
"""

from casa_core.assist.assistant import (
    ARBITRATIONS,
    Assistant,
    Inference,
)
from casa_core.assist.intents import (
    COST_FORMS,
    GoalIntent,
    Intent,
    length,
)
from casa_core.assist.presets import (
    DEFAULT_PRESET,
    PRESETS,
    Preset,
    preset,
)
from casa_core.assist.tasks import (
    PRACTICE_GOAL,
    intended_trajectory,
    task_waypoints,
)

__all__ = [
    "ARBITRATIONS",
    "Assistant",
    "COST_FORMS",
    "DEFAULT_PRESET",
    "GoalIntent",
    "Inference",
    "Intent",
    "PRACTICE_GOAL",
    "PRESETS",
    "Preset",
    "intended_trajectory",
    "length",
    "preset",
    "task_waypoints",
]
