"""Presets of inference: the paper's equations, the original implementation's numerics, ours.

The paper leaves choices open that change what confidence means: the cost of a goal,
the scale of the suboptimality, what counts as evidence. A :class:`Preset` fixes them
all; the assistant and the goal intents are built from it (:meth:`Preset.assistant_options`,
:meth:`Preset.goal_options`). ``docs/departures.md`` sets the presets side by side.

``casa`` (the default)
    The original's goal cost and numerics, with the evidence being the user's own
    commanded motion, and an inference step in which the user held no key adding no
    evidence: a user who gives no input is never taken over.
``original``
    What the authors' implementation computes: the arm's executed motion is the
    evidence, every step counts, the suboptimality is divided by 1.8; without its
    defects (exact ``t k / 2``, suboptimality clamped at 0, the posterior computed in
    log space).
``paper``
    The paper's equations and goal cost as written: the sum over the trajectory's
    states of the distance to the goal, the suboptimality unscaled, the trajectory
    the arm went through as the evidence.

Every preset uses the MAP estimate with lambda = 4, k = 7, T = 15 s and dt = 0.5 s, and
counts at most ``T / dt`` steps of evidence (the horizon's worth), so that a trial
running past T does not keep growing its confidences with time alone.

Examples
--------
>>> casa = preset("casa")
>>> casa.evidence, casa.idle_is_evidence
('commanded', False)
>>> sorted(preset("original").assistant_options())
['evidence', 'idle_is_evidence', 'lam', 'subopt_scale']
>>> preset("paper").goal_options()
{'cost': 'distance_sum', 'scale': 2.0}
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

from casa_core.assist.intents import COST_FORMS
from casa_core.defaults import COST_PER_METRE, DT, LAM, SUBOPT_SCALE
from casa_core.vocabulary import DEFECTS_PRESET, EVIDENCE


@dataclass(frozen=True)
class Preset:
    """The choices of inference that the paper leaves open.

    Attributes
    ----------
    name : str
    goal_cost : {"path_length", "distance_sum"}
        Cost form of a goal intent (:class:`~casa_core.assist.intents.GoalIntent`).
    goal_scale : float
        Its ``scale``: cost per metre of path, or per metre-second of distance.
    subopt_scale : float
        Factor on the suboptimality before use.
    lam : float
        Rate of the exponential prior on beta.
    evidence : {"commanded", "executed"}
        What the trajectory of inference is (:class:`~casa_core.assist.assistant.Assistant`).
    idle_is_evidence : bool
        Whether an inference step in which the user held no key counts as evidence.
    """

    name: str
    goal_cost: str
    goal_scale: float
    subopt_scale: float
    lam: float
    evidence: str
    idle_is_evidence: bool

    def __post_init__(self):
        if self.goal_cost not in COST_FORMS:
            raise ValueError(f"goal_cost must be one of {COST_FORMS}, got {self.goal_cost!r}")
        if self.evidence not in EVIDENCE:
            raise ValueError(f"evidence must be one of {EVIDENCE}, got {self.evidence!r}")

    def assistant_options(self) -> dict:
        """Keyword arguments of :class:`~casa_core.assist.assistant.Assistant`."""
        keys = ("subopt_scale", "lam", "evidence", "idle_is_evidence")
        return {key: value for key, value in asdict(self).items() if key in keys}

    def goal_options(self) -> dict:
        """Keyword arguments of :class:`~casa_core.assist.intents.GoalIntent`."""
        return {"cost": self.goal_cost, "scale": self.goal_scale}

    def with_evidence(self, evidence: str | None) -> Preset:
        """The preset with another evidence (``None``: unchanged)."""
        return self if evidence is None else replace(self, evidence=evidence)


_CASA = Preset(
    "casa",
    goal_cost="path_length",
    goal_scale=COST_PER_METRE,
    subopt_scale=SUBOPT_SCALE,
    lam=LAM,
    evidence="commanded",
    idle_is_evidence=False,
)
PRESETS = {
    "casa": _CASA,
    # The original's inference: casa's costs, on the executed motion, idle steps included.
    "original": replace(_CASA, name="original", evidence="executed", idle_is_evidence=True),
    "paper": Preset(
        "paper",
        goal_cost="distance_sum",
        # distance_sum charges scale * dt per metre at each state: 1 / dt makes it the
        # paper's plain sum of distances over the states.
        goal_scale=1.0 / DT,
        subopt_scale=1.0,
        lam=LAM,
        evidence="executed",
        idle_is_evidence=True,
    ),
}
#: The preset used when none is named.
DEFAULT_PRESET = "casa"
#: The settings of a replay that redoes the original's numerics with their defects
#: (casa_core.io.original.numerics): the ``original`` preset's, named apart. Not in
#: :data:`PRESETS`: the assistant never runs it.
DEFECTS = replace(PRESETS["original"], name=DEFECTS_PRESET)


def preset(name: str = DEFAULT_PRESET, *, evidence: str | None = None) -> Preset:
    """The preset called ``name``, with its evidence replaced if ``evidence`` is given.

    Raises
    ------
    ValueError
        Naming the unknown preset and the known ones.
    """
    if name not in PRESETS:
        raise ValueError(f"unknown inference preset {name!r}; expected one of {', '.join(PRESETS)}")
    return PRESETS[name].with_evidence(evidence)
