"""One assistance step: inference, confidence, arbitration and policy blending.

The :class:`Assistant` is fed the arm's state as the trajectory unfolds. At each
inference step (twice per second in the original, every ``period``) it updates, per
intent, the prefix cost incrementally, the optimal cost-to-go and the
suboptimality, then beta_hat, the belief over intents, the most likely intent
theta*, the user's control authority alpha, and whether the intent set looks
misspecified.

Two rules say what counts as evidence. With no evidence yet (``t = 0``) nothing is
inferred: the user has full control under every arbitration. At most ``T / period``
steps count (the horizon's worth): past T, confidence no longer grows with time
alone, so the verdict on the same behaviour does not depend on how long the trial
runs. Whether a step in which the user held no key counts is the option
``idle_is_evidence``; the presets (:mod:`casa_core.assist.presets`) choose it.

At every control tick :meth:`Assistant.act` blends the user's action with the robot's
action u*, which tracks the cached optimal trajectory to theta* (replanned when theta*
changes). The cost of a step is O(number of intents), independent of the steps so far.
"""

from __future__ import annotations

import numpy as np

from casa_core.assist._inference import Inference
from casa_core.defaults import (
    DT,
    EPSILON,
    HORIZON,
    LAM,
    PBA_DISTANCE,
    ROT_SPEED,
    SPEED,
    SUBOPT_SCALE,
    TICK,
    K,
)
from casa_core.fixed_order import length
from casa_core.model import _cores as cores
from casa_core.model._checks import require_positive
from casa_core.model.arbitration import blend
from casa_core.vocabulary import EVIDENCE

ARBITRATIONS = ("confidence", "distance", "belief", "none")


class Assistant:
    """Confidence-aware shared autonomy over a set of intents.

    Parameters
    ----------
    intents : sequence of Intent
        The known intents Theta; names must be unique.
    arbitration : {"confidence", "distance", "belief", "none"}
        "confidence" is CASA (alpha = min(1, 1/beta_hat*)); "distance" is the
        policy-blending baseline PBA (beta fixed at 1, alpha = min(1, d/D));
        "belief" arbitrates on P(theta*|xi) (with a single intent, whose belief is 1
        by construction, the user keeps full control: see
        :func:`casa_core.model.arbitration.alpha_belief`); "none" is direct teleoperation (NA).
    k : int, default K
        The action's dimensionality in the likelihood's Laplace approximation: 7, the
        JACO's joint velocities, as in the paper, although the action this assistant
        blends is the 4-D state velocity (docs/departures.md, "Planning").
    lam : float, default LAM
        Exponential prior rate on beta (MAP estimate; the original used 4).
    epsilon : float, default EPSILON
        Misspecification threshold on beta_hat (1.0 as in related work), > 0.
    pba_distance : float, default PBA_DISTANCE
        D of distance arbitration, metres (0.55 in the original).
    subopt_scale : float, default SUBOPT_SCALE
        Factor applied to suboptimality before use (the original divides by 1.8).
    horizon : float, default HORIZON
        T, the episode horizon in seconds (15 in the original).
    period : float, default DT
        The inference period: seconds between inference steps and between the states
        of the planned trajectories (0.5); not the control tick (``tick``).
    speed, rot_speed : float, default SPEED, ROT_SPEED
        Limits of the robot action u*: m/s for the position, rad/s for rot.
    evidence : {"commanded", "executed"}
        What the trajectory xi_{0->t} of inference is. The paper's model is one
        of the *user's* input (beta says how consistent with the intent that
        input is expected to be). ``"executed"`` (the original
        implementation's): the states the arm went through, the robot's own
        motion included, so that once the robot assists an intent its motion
        confirms that intent. ``"commanded"`` (default): what the user's input
        alone did, i.e. each inference step the state the arm would have
        reached from the last one without the robot's share (1 - alpha)(u* -
        T(a)) of the blended action; the suboptimality is then summed step by
        step, ``c(x_j -> x^H_{j+1}) + C*(x^H_{j+1}) - C*(x_{j+1})`` added to
        the prefix cost, so that the robot's own motion is never evidence for
        the intent it assists. Both are the same while alpha = 1.
    tick : float, default TICK
        Seconds each :meth:`act` is applied for (the 20 Hz control tick); with
        ``evidence="commanded"`` it turns the robot's share into displacement.
    idle_is_evidence : bool, default False
        Whether an inference step in which the user's action was zero at every
        :meth:`act` counts as evidence. False: such a step leaves the evidence and
        the suboptimalities as they were (the arm may still move, assisted), so that
        standing still, which costs nothing under the path-length cost and so looks
        optimal for every goal, never makes the robot confident. True: every step
        counts, as in the original implementation.

    Raises
    ------
    ValueError
        On an unknown ``arbitration`` or ``evidence``, no or duplicate intent names,
        or a parameter out of range (naming it).

    Examples
    --------
    >>> from casa_core.assist.intents import GoalIntent
    >>> intents = [GoalIntent("green", [0.3, 0.4, 0.0]), GoalIntent("red", [-0.4, 0.1, 0.2])]
    >>> assistant = Assistant(intents, arbitration="confidence")
    >>> assistant.reset([0.0, 0.0, 0.0, 0.0])
    >>> step = assistant.update([0.015, 0.02, 0.0, 0.0], user_input=True)  # 2.5 cm to green
    >>> step.intent, step.alpha
    ('green', 1.0)
    >>> assistant.act([0.015, 0.02, 0.0, 0.0], np.zeros(4)).shape
    (4,)
    """

    def __init__(
        self,
        intents,
        *,
        arbitration: str = "confidence",
        k: int = K,
        lam: float = LAM,
        epsilon: float = EPSILON,
        pba_distance: float = PBA_DISTANCE,
        subopt_scale: float = SUBOPT_SCALE,
        horizon: float = HORIZON,
        period: float = DT,
        speed: float = SPEED,
        rot_speed: float = ROT_SPEED,
        evidence: str = "commanded",
        tick: float = TICK,
        idle_is_evidence: bool = False,
    ):
        if arbitration not in ARBITRATIONS:
            raise ValueError(f"arbitration must be one of {ARBITRATIONS}, got {arbitration!r}")
        if evidence not in EVIDENCE:
            raise ValueError(f"evidence must be one of {EVIDENCE}, got {evidence!r}")
        self.intents = list(intents)
        names = [intent.name for intent in self.intents]
        if not names:
            raise ValueError("the assistant needs at least one intent")
        if len(set(names)) != len(names):
            raise ValueError(f"intent names must be unique, got {names}")
        require_positive("Assistant", k=k, pba_distance=pba_distance, subopt_scale=subopt_scale)
        require_positive("Assistant", horizon=horizon, period=period, tick=tick)
        require_positive("Assistant", speed=speed, rot_speed=rot_speed)
        # beta_hat >= 0: an epsilon <= 0 (or NaN) would never detect misspecification.
        require_positive("Assistant", epsilon=epsilon)
        if int(k) != k:
            raise ValueError(f"k of Assistant must be an integer, got {k!r}")
        try:
            lam_ok = bool(np.isfinite(lam) and lam >= 0)
        except TypeError:  # not a number at all
            lam_ok = False
        if not lam_ok:
            raise ValueError(f"lam of Assistant must be a number >= 0, got {lam!r}")
        self.arbitration, self.evidence = arbitration, evidence
        self.k, self.lam, self.epsilon = k, lam, epsilon
        self.pba_distance, self.subopt_scale = pba_distance, subopt_scale
        self.horizon, self.period, self.tick = horizon, period, tick
        self.speed, self.rot_speed = speed, rot_speed
        self.idle_is_evidence = bool(idle_is_evidence)
        self.max_evidence = int(round(horizon / period))
        self.names = names
        self._start_trial(None)  # the trial's state, set by reset()

    def _require_reset(self, method: str) -> np.ndarray:
        """The last state observed; RuntimeError before :meth:`reset`."""
        if self._last_state is None:
            raise RuntimeError(f"call reset(start_state) before {method}")
        return self._last_state

    def reset(self, state) -> None:
        """Start a trial at ``state``: no evidence, costs measured from here."""
        state = np.asarray(state, dtype=float)
        if state.ndim != 1 or not np.isfinite(state).all():
            raise ValueError(f"start state must be finite (one vector), got {state!r}")
        self._start_trial(state)

    def _start_trial(self, state: np.ndarray | None) -> None:
        """The trial's state at ``state``, or before any trial (``state`` None)."""
        n = len(self.intents)
        if state is not None:
            for intent in self.intents:  # intents shared by several trials start afresh
                intent.start_trial()
        self._steps = 0
        self._evidence = 0  # inference steps that counted as evidence
        self._user_input = False  # any nonzero user action since the last step
        self._subopt = np.zeros(n)  # unscaled, at the last step
        self._last_state: np.ndarray | None = state
        self._prefix = np.zeros(n)
        self._optimal = (
            np.zeros(n)
            if state is None
            else np.array([i.cost_to_go(state, self.horizon) for i in self.intents])
        )
        # The cached optimal trajectory to theta*, one state per step, from inference step
        # _plan_origin on.
        self._plan: np.ndarray | None = None
        self._plan_intent: int | None = None
        self._plan_origin = 0
        # The robot's share of the motion since the last step.
        self._robot_motion: np.ndarray | None = None if state is None else np.zeros_like(state)
        self.latest: Inference | None = None

    def update(self, state, *, user_input: bool | None = None) -> Inference:
        """Observe the state reached one inference step (``period``) after the last one.

        ``user_input`` says whether the user gave input during the step; by default,
        whether :meth:`act` was given a nonzero user action since the last step. A
        caller feeding a trajectory of the user's own (an analysis, a test) passes True.
        """
        last = self._require_reset("update")
        state = np.asarray(state, dtype=float)
        if state.shape != last.shape or not np.isfinite(state).all():
            raise ValueError(f"state must be finite, of shape {last.shape}: {state!r}")
        self._steps += 1
        time_left = max(self.horizon - self._steps * self.period, 0.0)
        gave_input = self._user_input if user_input is None else bool(user_input)
        self._user_input = False
        self._observe(state, time_left, counts=self.idle_is_evidence or gave_input)
        evidence_steps = min(self._evidence, self.max_evidence)
        # The equations' unchecked cores: costs are finite and k, lam were checked once.
        subopt = self.subopt_scale * self._subopt
        betas = cores.beta_hat(subopt, evidence_steps, self.k, self.lam)
        inference_beta = np.ones_like(betas) if self.arbitration == "distance" else betas
        likelihood = cores.log_likelihood(subopt, inference_beta, evidence_steps, self.k)
        belief = cores.posterior(likelihood)
        star = int(np.argmax(belief))
        alphas = self._arbitrate(state, star, betas, belief, evidence_steps)
        self._replan(state, star, time_left)
        self.latest = Inference(
            time=self._steps * self.period,
            beta=dict(zip(self.names, betas.tolist(), strict=True)),
            belief=dict(zip(self.names, belief.tolist(), strict=True)),
            suboptimality=dict(zip(self.names, np.atleast_1d(subopt).tolist(), strict=True)),
            intent=self.names[star],
            alpha=1.0 if self.arbitration == "none" else alphas[self.arbitration],
            alpha_by_arbitration=alphas,
            misspecified=bool(evidence_steps > 0 and (betas < self.epsilon).all()),
            evidence_steps=evidence_steps,
        )
        return self.latest

    def _observe(self, state: np.ndarray, time_left: float, *, counts: bool) -> None:
        """The evidence of one step: the prefix costs to the state the user's input reached
        (the robot's share removed under commanded evidence), the costs-to-go, and the
        suboptimalities where the step ``counts`` as evidence."""
        observed = state
        motion = self._robot_motion
        if self.evidence == "commanded" and motion is not None and motion.any():
            observed = state - motion
        for j, intent in enumerate(self.intents):
            self._prefix[j] += intent.step_cost(self._last_state, observed)
        self._last_state = state
        self._robot_motion = np.zeros_like(state)
        if observed is state:
            to_go = self._costs_to_go([state], time_left)[:, 0]
        else:
            # The user's step ended at `observed`; the next one starts from `state`
            # (last, so that the planners warm start from its plan next time).
            at_observed, to_go = self._costs_to_go([observed, state], time_left).T
            self._prefix += at_observed - to_go
        if counts:
            self._evidence += 1
            self._subopt = cores.suboptimality(self._prefix, to_go, self._optimal)
        else:
            # Not evidence: the suboptimality stays, and the prefix is rebased on it.
            self._prefix = self._subopt + self._optimal - to_go

    def _arbitrate(self, state, star: int, betas, belief, evidence_steps: int) -> dict:
        """alpha under each arbitration for the most likely intent ``star``; 1 for every
        one before any evidence (nothing inferred yet: no arbitration assists)."""
        # The distance is read even then: a planned intent's plans it makes are warm starts.
        distance = self.intents[star].distance(state)
        if evidence_steps == 0:
            return dict.fromkeys(("confidence", "distance", "belief"), 1.0)
        return {
            "confidence": float(cores.alpha_confidence(float(betas[star]))),
            "distance": float(cores.alpha_distance(distance, self.pba_distance)),
            "belief": float(cores.alpha_belief(float(belief[star]), len(self.intents))),
        }

    def _replan(self, state: np.ndarray, star: int, time_left: float) -> None:
        """The robot's plan toward the most likely intent, made again when that intent
        changes (u* follows it: :meth:`robot_action`)."""
        if star != self._plan_intent:
            self._plan = self.intents[star].optimal_trajectory(state, time_left)
            self._plan_intent = star
            self._plan_origin = self._steps

    def _costs_to_go(self, states, time_left: float) -> np.ndarray:
        """Costs-to-go ``(n_intents, n_states)``; each intent plans its states at once."""
        if len(states) == 1:  # the common case, without the batching machinery
            to_go = np.array([[i.cost_to_go(states[0], time_left)] for i in self.intents])
        else:
            to_go = np.array([i.costs_to_go(states, time_left) for i in self.intents])
        if not np.isfinite(to_go).all():
            bad = [n for n, c in zip(self.names, to_go, strict=True) if not np.isfinite(c).all()]
            raise ValueError(f"intent(s) {bad} returned a non-finite cost-to-go")
        return to_go

    def robot_action(self, state, elapsed_in_step: float = 0.0) -> np.ndarray:
        """u*: velocity toward the cached plan's next state, within the speed limits."""
        self._require_reset("robot_action")
        state = np.asarray(state, dtype=float)
        if self._plan is None:
            return np.zeros_like(state)
        index = min(self._steps - self._plan_origin + 1, len(self._plan) - 1)
        target = self._plan[index]
        remaining = max(self.period - elapsed_in_step, self.period / 10)
        velocity = (target - state) / remaining
        norm = length(velocity[:3])
        if norm > self.speed:
            velocity[:3] *= self.speed / norm
        velocity[3] = min(max(velocity[3], -self.rot_speed), self.rot_speed)  # np.clip's order
        return velocity

    def act(
        self,
        state,
        user_action,
        elapsed_in_step: float = 0.0,
        *,
        alpha: float | None = None,
        record: bool = True,
    ) -> np.ndarray:
        """The blended action alpha T(a) + (1 - alpha) u*, applied even with no key held.

        Before the first inference step the user has full control. ``alpha``, if
        given, is the authority actually applied this tick instead of the latest
        inference's: replaying a log (:mod:`casa_core.analysis.replay`) gives the logged one,
        so that the robot's share removed from the evidence is the share it had. With
        ``record=False`` the blend is only computed, not applied: nothing is kept for the
        evidence (a live node answering a command between two ticks, :mod:`casa_core.ros2`).
        """
        self._require_reset("act")
        user_action = np.asarray(user_action, dtype=float)
        if self.latest is None:
            if record:
                self.record(user_action)
            return user_action.copy()
        robot = self.robot_action(state, elapsed_in_step)
        alpha = self.latest.alpha if alpha is None else float(alpha)
        if record:
            self.record(user_action, robot, alpha=alpha)
        return blend(alpha, user_action, robot)

    @property
    def alpha(self) -> float:
        """The user's authority this tick: the latest inference's alpha, 1 before the first."""
        return 1.0 if self.latest is None else self.latest.alpha

    @property
    def beta(self) -> dict[str, float]:
        """beta_hat per intent: the latest inference's; 0 before the first (no evidence)."""
        return dict.fromkeys(self.names, 0.0) if self.latest is None else self.latest.beta

    @property
    def belief(self) -> dict[str, float]:
        """The belief per intent: the latest inference's; uniform before the first."""
        if self.latest is None:
            return dict.fromkeys(self.names, 1.0 / len(self.names))
        return self.latest.belief

    def record(self, user_action, robot_action=None, *, alpha: float = 1.0) -> None:
        """Keep, for the next inference step, what one tick applied: the user's action T(a)
        and, where the robot had a share (``alpha < 1``), the robot's action, each the
        state velocity ``[vx, vy, vz, vrot]`` of the command the arm was driven by.

        :meth:`act` records its own blend; a caller that blends in another space (joint
        velocities, :class:`casa_core.study.drive.OriginalDrive`) records the state
        velocities of the commands it blended, so that the robot's share removed from the
        evidence is the one the arm was moved by.
        """
        self._require_reset("record")
        user_action = np.asarray(user_action, dtype=float)
        if user_action.any():
            self._user_input = True
        if robot_action is not None and self.evidence == "commanded" and alpha < 1.0:
            robot = np.asarray(robot_action, dtype=float)
            self._robot_motion += (1.0 - alpha) * (robot - user_action) * self.tick
