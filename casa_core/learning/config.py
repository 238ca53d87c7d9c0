"""Settings of deep maximum-entropy IRL (where they depart from the original implementation
and how to restore its choices: docs/departures.md, "Learning a new intent")."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from casa_core.assist.intents import COST_FORMS
from casa_core.defaults import COST_PER_METRE, DT
from casa_core.model._checks import require_positive
from casa_core.planning import PlannerConfig

#: The learned cost's bound: a goal's ``distance_sum`` cost of one state 0.5 m from it
#: (COST_PER_METRE rounded to a whole cost per metre, as training was tuned with it).
COST_SCALE = round(COST_PER_METRE) * DT * 0.5


@dataclass(frozen=True)
class IRLConfig:
    """Settings of deep maximum-entropy IRL.

    Attributes
    ----------
    hidden : int
        Units per hidden layer (2 layers). Default 64; the original has 128. The
        hidden x hidden layer dominates planning's cost, and with 64 units learning
        takes about half the time. On 30 simulated participants outside the study
        the 64-unit network met the learning targets as often as the 128-unit one, and
        fewer of its trials after learning failed or timed out (4 of 60, against 5).
        With 96 units 2 of the study's 11 pours missed the target (docs/departures.md,
        "Learning a new intent").
    negative_slope : float
        Slope of the leaky ReLU for negative inputs.
    cost_scale : float
        During training the per-state cost is ``cost_scale * sigmoid(network
        output)``, in [0, cost_scale]. Default :data:`COST_SCALE`, 56.75 =
        227 * 0.5 s * 0.5 m: what a goal intent's ``distance_sum`` cost charges per
        state at 0.5 m from its goal, with the cost per metre
        (:data:`~casa_core.defaults.COST_PER_METRE`, 227.27) rounded to a whole number,
        the scale at which training was tuned.
    calibration : {"path_length", "distance_sum"} or None
        After training, the cost is multiplied by the factor that makes its
        optimal cost from the demonstrations' mean start equal to that of a
        :class:`~casa_core.assist.intents.GoalIntent` of this cost form whose goal is
        where that optimal trajectory ends: learned and goal intents then charge
        the same for the same task done optimally, so their suboptimalities,
        confidences and beliefs compare. Default ``"path_length"``, the goal
        intents' default; None keeps the trained scale.
    length_scale : float
        Metres per unit of the position features.
    lr, weight_decay : float
        Adam's settings. The original's are 1e-3 and 1e-3; our default lr is
        3e-3 with 3 Adam steps per iteration, which within 30 iterations learns
        an optimum ending within 5 cm of the demonstrations (and tilted past 60
        degrees for pouring) where 1e-3 with one step does not (set ``lr=1e-3,
        steps_per_iteration=1, logit_penalty=0`` for the original's).
    max_iterations : int
        Most IRL iterations (one plan of D^phi each). Default 30 (the original about
        50): on the 11 simulated participants every learned goal and pour meets the
        learning targets within 30 as within 50, and their trials after learning all
        succeed, none timed out, as with 50 (docs/departures.md, "Learning a new intent").
    steps_per_iteration : int
        Adam steps on the cost per plan of D^phi (the gradient estimate is
        reused; planning is the expensive part).
    logit_penalty : float
        Weight of the mean squared network output (before the sigmoid) over the
        demonstrated and sampled states, added to the loss (divided by
        ``cost_scale``). The loss C(D*) - C(D^phi) alone is unbounded below and
        pushes the sigmoid into saturation, where the gradient vanishes and
        learning stalls; the penalty keeps the output in its responsive range.
    min_iterations : int
        Iterations run before convergence is tested.
    explore_iterations : int
        D^phi is warm started from the previous iteration's (cheap, but it would
        never leave its basin); each iteration also plans this many steps from a
        cold start and keeps, per demonstration, the cheaper of the two, so that
        a spurious low-cost region elsewhere is found and raised.
    tol_gap : float
        Converged when the cost gap between demonstrations and D^phi, per state
        and relative to ``cost_scale``, is below this ...
    tol_end : float
        ... and the ends of D^phi moved less than this (m) in the last iteration ...
    tol_match : float
        ... and the ends of D^phi match the demonstrations' ends: their
        :func:`~casa_core.learning.maxent.end_match` is below this (without rot, a
        tilt is never waited for); the feature matching MaxEnt IRL converges to.
    verify_candidates : int
        How many of the best-matching iterations are checked, at the end, by
        planning their cost as assistance will (cold, from the demonstrations'
        mean start); the one whose own optimum ends closest is returned.
    assist_warm_iterations : int
        Warm-started iterations of the learned intent's planner per assistance
        step (its ``warm_iterations``). Default 10: an assistance step has about
        2 ms, one iteration cost about 0.15 ms with a 128-unit network
        (:mod:`casa_core.learning.numpy_cost`), and with 10 instead of 15 the trials
        after learning of simulated participants differ by less than participants do
        (docs/departures.md, "Learning a new intent").
    planner : PlannerConfig
        The trajectory optimizer used for D^phi and (with
        ``assist_warm_iterations``) by the learned intent.
    """

    hidden: int = 64
    negative_slope: float = 0.01
    cost_scale: float = COST_SCALE
    calibration: str | None = "path_length"
    length_scale: float = 0.1
    lr: float = 3e-3
    weight_decay: float = 1e-3
    max_iterations: int = 30
    steps_per_iteration: int = 3
    logit_penalty: float = 0.01
    min_iterations: int = 15
    explore_iterations: int = 100
    assist_warm_iterations: int = 10
    verify_candidates: int = 5
    tol_gap: float = 0.005
    tol_end: float = 0.005
    tol_match: float = 0.03
    planner: PlannerConfig = PlannerConfig()

    def __post_init__(self):
        counts = ("max_iterations", "steps_per_iteration", "explore_iterations")
        for name in (*counts, "assist_warm_iterations", "verify_candidates", "min_iterations"):
            value, low = getattr(self, name), 0 if name == "min_iterations" else 1
            if not (isinstance(value, int) and not isinstance(value, bool) and value >= low):
                raise ValueError(f"IRLConfig.{name} must be an integer >= {low}, got {value!r}")
        if self.min_iterations > self.max_iterations:
            raise ValueError(
                f"IRLConfig.min_iterations ({self.min_iterations}) must be at most "
                f"max_iterations ({self.max_iterations})"
            )
        require_positive("IRLConfig", hidden=self.hidden, cost_scale=self.cost_scale)
        require_positive("IRLConfig", length_scale=self.length_scale, lr=self.lr)
        require_positive("IRLConfig", tol_gap=self.tol_gap, tol_end=self.tol_end)
        require_positive("IRLConfig", tol_match=self.tol_match)
        for name in ("negative_slope", "weight_decay", "logit_penalty"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"IRLConfig.{name} must be a finite number >= 0, got {value!r}")
        if int(self.hidden) != self.hidden:
            raise ValueError(f"IRLConfig.hidden must be an integer, got {self.hidden!r}")
        if self.calibration is not None and self.calibration not in COST_FORMS:
            raise ValueError(
                f"IRLConfig.calibration must be one of {COST_FORMS} or None, "
                f"got {self.calibration!r}"
            )

    def assist_planner(self) -> PlannerConfig:
        """The planner settings of a learned intent during assistance (short warm starts).

        Examples
        --------
        >>> IRLConfig(assist_warm_iterations=7).assist_planner().warm_iterations
        7
        """
        return replace(self.planner, warm_iterations=self.assist_warm_iterations)
