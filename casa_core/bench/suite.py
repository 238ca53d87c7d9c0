"""``casa bench``: every benchmark of the package.

How long one assistance step takes and how it grows with the intents
(:func:`assistance_benchmarks`), and how many simulated seconds a whole CASA trial
runs per second in a simulation kept open and what multiple of its pybullet work it
costs (:mod:`casa_core.bench.trial`); :func:`run_benchmarks` runs them all.

One *assistance step* is what the assistant does at an inference step (twice per
second): :meth:`Assistant.update` with the state reached (prefix costs, optimal
costs-to-go, beta_hat, belief, arbitration, replanning u* when the most likely
intent changes) plus one :meth:`Assistant.act` (the blended action). It is timed at
a late step of a trial (``late_step`` = 24, t = 12 s of the 15 s horizon), after
the assistant has been fed the trial so far, because that is where a real trial
spends its time and where incremental bookkeeping pays or fails to.

The trial is the Unknown Goal task's intended trajectory (the reference shown to
participants), sampled every 0.5 s and moved by a random sub-millimetre offset, so
that intents which cache plans by state (planned and neural intents) plan for real
at the timed step, warm started from the previous step as in a trial. The assistant
is fed the steps before the timed one once; each repetition times the step on a
deep copy of it. The sets of goal intents are timed together, in rounds
(:func:`time_assistance_steps`): timed one after the other, a busy spell of the machine
during one of them made 3 goal intents look slower than 4, which differ by one intent.

Times are CPU time of the measuring thread (``time.thread_time_ns``), not wall
time: the targets are for one core, and on a machine shared with other jobs wall
time would also count the time the thread waited for a core. A whole trial is timed
in CPU time of the process, pybullet included.
"""

from __future__ import annotations

import copy
import time
from collections.abc import Callable, Sequence

import numpy as np

from casa_core.assist.assistant import Assistant
from casa_core.assist.intents import GoalIntent
from casa_core.assist.tasks import intended_trajectory
from casa_core.bench.protocol import TARGETS, participant_benchmark, target_met
from casa_core.bench.trial import TRIAL_SECONDS, trial_physics_cpu_s, trial_realtime_factor
from casa_core.defaults import HORIZON
from casa_core.scene import REQUIRED_GOALS, Scene

#: Numbers of goal intents of the scaling measurement.
SCALING_SIZES = (2, 4, 8, 16, 32, 64)
#: Box (m) from which extra goals of the scaling measurement are drawn.
WORKSPACE = (np.array([0.25, -0.4, 0.1]), np.array([0.6, 0.3, 0.4]))


def bench_trajectory(scene: Scene, dt: float = 0.5) -> np.ndarray:
    """States ``(n, 4)`` every ``dt`` s of the Unknown Goal reference, held at its end."""
    reference = intended_trajectory("unknown_goal", scene, dt=dt)[:, 1:]
    n_needed = int(round(HORIZON / dt)) + 1
    if len(reference) < n_needed:
        reference = np.vstack([reference, np.repeat(reference[-1:], n_needed - len(reference), 0)])
    return reference


def goal_intents(scene: Scene, n: int, rng: np.random.Generator) -> list[GoalIntent]:
    """``n`` goal intents: green, purple, red, then goals drawn uniformly in :data:`WORKSPACE`."""
    named = [GoalIntent(name, scene.goals[name]) for name in REQUIRED_GOALS][:n]
    extra = rng.uniform(*WORKSPACE, size=(max(n - len(named), 0), 3))
    return named + [GoalIntent(f"goal{i}", goal) for i, goal in enumerate(extra)]


def _fed_assistant(intents, states, late_step, user_action) -> Assistant:
    """An assistant fed the states before ``late_step``, the robot assisting as in a trial."""
    fed = Assistant(intents, arbitration="confidence")
    fed.reset(states[0])
    for state in states[1:late_step]:
        fed.update(state, user_input=True)
        # The robot's share of the motion, which the next step removes from the evidence.
        fed.act(state, user_action)
    return fed


def time_assistance_steps(
    intent_sets: Sequence[Sequence],
    trajectory: np.ndarray,
    rng: np.random.Generator,
    *,
    late_step: int = 24,
    repeats: int = 30,
    warmup: int = 3,
    rounds: int = 10,
) -> list[dict]:
    """Median CPU time (microseconds) of the assistance step ``late_step``, per intent set.

    The sets are timed in ``rounds`` rounds, each set in turn within a round, so that a
    busy spell of a shared machine (which can slow a step by more than one intent costs)
    slows every set alike instead of whichever was being timed then. Within a round a set
    is timed ``warmup`` times untimed and then repeatedly, as a trial repeats the step.

    Parameters
    ----------
    intent_sets : sequence of sequences of intents
        The intents of each assistant.
    trajectory : numpy.ndarray, shape (n, 4)
        States every inference step, the start first; ``n > late_step``.
    rng : numpy.random.Generator
        Draws each set's sub-millimetre offset of the trajectory.
    late_step : int
        The timed inference step (the steps before it are fed untimed).
    repeats : int
        Timed repetitions per set, over all rounds; the median is returned.
    warmup : int
        Untimed repetitions of a set at the start of each round (its first calls after
        another set's run cold).
    rounds : int
        Rounds the repetitions are split into (at most ``repeats``).

    Returns
    -------
    list of dict
        Per set: ``step_us`` (the median) and ``assisting``: whether the robot had a
        share of the motion before the timed step (alpha < 1); then each intent's
        cost-to-go is computed at two states, the state reached and the user's part of it,
        instead of one.
    """
    if len(trajectory) <= late_step:
        raise ValueError(f"trajectory has {len(trajectory)} states, needs > {late_step}")
    user_action = np.array([0.0, 0.05, -0.05, 0.0])
    fed, states = [], []
    for intents in intent_sets:
        moved = trajectory + rng.uniform(-5e-4, 5e-4, size=(1, 4))
        fed.append(_fed_assistant(list(intents), moved, late_step, user_action))
        states.append(moved[late_step])
    rounds = max(1, min(rounds, repeats))
    per_round = [len(block) for block in np.array_split(np.arange(repeats), rounds)]
    times: list[list[float]] = [[] for _ in fed]
    for timed in per_round:
        for index, (assistant_fed, state) in enumerate(zip(fed, states, strict=True)):
            for repeat in range(warmup + timed):
                # A copy of the fed assistant (caches and warm starts included) takes it.
                assistant = copy.deepcopy(assistant_fed)
                start = time.thread_time_ns()
                assistant.update(state, user_input=True)
                assistant.act(state, user_action)
                if repeat >= warmup:
                    times[index].append((time.thread_time_ns() - start) / 1e3)
    return [
        {"step_us": float(np.median(t)), "assisting": a.latest is not None and a.latest.alpha < 1.0}
        for t, a in zip(times, fed, strict=True)
    ]


def time_assistance_step(
    make_intents: Callable[[], Sequence],
    trajectory: np.ndarray,
    rng: np.random.Generator,
    *,
    late_step: int = 24,
    repeats: int = 30,
    warmup: int = 3,
) -> float:
    """Median CPU time (microseconds) of the assistance step ``late_step`` of a trial.

    One intent set of :func:`time_assistance_steps`; ``make_intents`` returns it (called
    once).
    """
    (row,) = time_assistance_steps(
        [make_intents()],
        trajectory,
        rng,
        late_step=late_step,
        repeats=repeats,
        warmup=warmup,
        rounds=1,
    )
    return row["step_us"]


def linear_fit_r2(sizes, times) -> tuple[float, float, float]:
    """Least-squares line ``time = a + b n``: returns ``(a, b, R^2)``."""
    sizes, times = np.asarray(sizes, dtype=float), np.asarray(times, dtype=float)
    b, a = np.polyfit(sizes, times, 1)
    residual = times - (a + b * sizes)
    r2 = 1.0 - residual @ residual / np.sum((times - times.mean()) ** 2)
    return float(a), float(b), float(r2)


def assistance_benchmarks(
    scene: Scene,
    make_neural_intent: Callable[[], object] | None,
    *,
    seed: int = 0,
    repeats: int = 200,
    neural_repeats: int = 20,
) -> dict:
    """``step_us_goal3``, ``step_us_neural1`` (None without a neural intent) and ``scaling``.

    The 3 goal intents and every size of ``scaling`` are timed together, in turn
    (:func:`time_assistance_steps`), so that they compare; each ``scaling`` row has
    ``n_intents``, ``step_us`` and ``assisting``.
    """
    rng = np.random.default_rng(seed)
    trajectory = bench_trajectory(scene)
    goals3 = goal_intents(scene, 3, rng)
    sets = [goals3] + [goal_intents(scene, n, rng) for n in SCALING_SIZES]
    timed = time_assistance_steps(sets, trajectory, rng, repeats=repeats)
    results = {"step_us_goal3": timed[0]["step_us"]}
    if make_neural_intent is None:
        results["step_us_neural1"] = None
    else:
        results["step_us_neural1"] = time_assistance_step(
            lambda: [*goals3, make_neural_intent()], trajectory, rng, repeats=neural_repeats
        )
    results["scaling"] = [
        {"n_intents": n, **row} for n, row in zip(SCALING_SIZES, timed[1:], strict=True)
    ]
    return results


def format_table(results: dict) -> str:
    """The results as a plain-text table, with the targets, and notes on how to read it.

    A scaling row whose ``assisting`` is false is marked ``*`` and left out of the linear
    fit: without the robot's share each intent computes one cost-to-go instead of two.
    """
    rows = results["scaling"]
    assisting = [row.get("assisting", True) for row in rows]
    fitted = [row for row, a in zip(rows, assisting, strict=True) if a]
    if len(fitted) < 3:
        fitted = rows
    _, slope, r2 = linear_fit_r2(
        [row["n_intents"] for row in fitted], [row["step_us"] for row in fitted]
    )
    lines = [
        "CPU time of one thread/process (see casa_core.bench.suite)",
        f"{'measure':<44}{'value':>14}  target",
        _row("assistance step, 3 goal intents (us)", results, "step_us_goal3"),
        _row("assistance step, + 1 neural intent (us)", results, "step_us_neural1"),
    ]
    for row, a in zip(rows, assisting, strict=True):
        label = f"  {row['n_intents']} goal intents (us)" + ("" if a else " *")
        lines.append(f"{label:<44}{row['step_us']:>14.1f}")
    lines.append(f"{'  linear fit: us per intent, R^2':<44}{slope:>9.1f}, {r2:.3f}  linear")
    if "trial_realtime_factor" in results:
        label = "15 s CASA trial, simulated s per CPU s"
        lines.append(_row(label, results, "trial_realtime_factor"))
    if "trial_realtime_factor_new_sim" in results:
        lines.append(
            f"{'  the same, a new simulation per trial':<44}"
            f"{results['trial_realtime_factor_new_sim']:>14.1f}"
        )
    if "trial_realtime_factor_wall" in results:
        lines.append(
            f"{'  the same per wall-clock second':<44}"
            f"{results['trial_realtime_factor_wall']:>14.1f}"
        )
    if "trial_cost_over_physics" in results:
        lines.append(_row("  trial CPU / its pybullet CPU", results, "trial_cost_over_physics"))
    if "participant_cpu_s" in results:
        lines.append(_row("one participant's protocol (CPU s)", results, "participant_cpu_s"))
        lines.append(_row("  learning one intent (CPU s)", results, "irl_s"))
    for stage, seconds in results.get("protocol_split_s", {}).items():
        lines.append(f"{'  protocol: ' + stage + ' (CPU s)':<44}{seconds:>14.2f}")
    return "\n".join(lines + _notes(results, assisting, slope))


def _row(label: str, results: dict, key: str) -> str:
    """One line of the table: the value, its target and whether it is met."""
    value = results.get(key)
    comparison, bound = TARGETS[key]
    shown = f"{value:>14.1f}" if value is not None else f"{'n/a':>14}"
    met = target_met(key, value)
    verdict = "" if met is None else ("  met" if met else "  MISSED")
    return f"{label:<44}{shown}  {comparison} {bound:g}{verdict}"


def _notes(results: dict, assisting: list[bool], slope: float) -> list[str]:
    """How to read the assistance rows: the timing order, unassisted rows, close neighbours."""
    notes = [
        "Notes:",
        "- The 3 goal intents and the goal-intent sizes are timed together, in rounds, each in",
        "  turn, so that a busy spell of the machine slows them alike.",
    ]
    if not all(assisting):
        notes += [
            "- * the robot does not assist at the timed step (alpha = 1), so each intent's",
            "  cost-to-go is computed at one state instead of two: the row lies below the line",
            "  and the linear fit leaves it out.",
        ]
    four = [row["step_us"] for row in results["scaling"] if row["n_intents"] == 4]
    if four and results["step_us_goal3"] >= four[0]:
        notes += [
            f"- 3 goal intents took no less than 4 ({results['step_us_goal3']:.1f} vs "
            f"{four[0]:.1f} us): one more intent adds about",
            f"  {slope:.0f} us (the fit), less than runs on a busy machine differ; run again.",
        ]
    return notes


def untrained_neural_intent(scene: Scene, *, seed: int = 0, planner=None):
    """A neural intent as IRL makes them (:mod:`casa_core.learning`), untrained: same cost.

    ``planner`` (a :class:`casa_core.planning.PlannerConfig`) defaults to the one
    learned intents assist with (short warm starts), as loaded from a library.
    """
    from casa_core.learning import IRLConfig, NeuralIntent, cost_network, feature_names
    from casa_core.study.learning_evidence import scene_objects

    config = IRLConfig()
    objects = scene_objects(scene)
    network = cost_network(
        len(feature_names(objects)),
        hidden=config.hidden,
        negative_slope=config.negative_slope,
        seed=seed,
    )
    return NeuralIntent(
        "neural",
        network,
        objects=objects,
        cost_scale=config.cost_scale,
        length_scale=config.length_scale,
        planner=config.assist_planner() if planner is None else planner,
    )


def run_benchmarks(
    scene: Scene, *, seed: int = 0, config: dict | None = None, participants=(0, 1, 2)
) -> dict:
    """Every benchmark: :func:`assistance_benchmarks`, :func:`trial_realtime_factor` and,
    with a workflow ``config``, :func:`~casa_core.bench.protocol.participant_benchmark`.

    Returns the dict :func:`format_table` prints: ``step_us_goal3``,
    ``step_us_neural1``, ``scaling``, ``trial_realtime_factor`` (per CPU second),
    ``trial_realtime_factor_wall``, ``trial_realtime_factor_new_sim``,
    ``trial_physics_realtime_factor`` (the trial's pybullet work alone, simulated s per
    CPU s) and ``trial_cost_over_physics`` (the trial's CPU over that work's); with a
    config ``participant_cpu_s``, ``irl_s`` (and their ``_all`` lists) and
    ``protocol_split_s``; and
    ``targets_met``: per key of :data:`~casa_core.bench.protocol.TARGETS`, whether
    its target is met (None if not measured).
    """
    results = assistance_benchmarks(
        scene, lambda: untrained_neural_intent(scene, seed=seed), seed=seed
    )
    factor_cpu, factor_wall = trial_realtime_factor(scene)
    physics = trial_physics_cpu_s(scene)
    results["trial_physics_realtime_factor"] = TRIAL_SECONDS / physics
    results["trial_cost_over_physics"] = (TRIAL_SECONDS / factor_cpu) / physics
    results["trial_realtime_factor"] = factor_cpu
    results["trial_realtime_factor_wall"] = factor_wall
    results["trial_realtime_factor_new_sim"] = trial_realtime_factor(scene, reuse_simulation=False)[
        0
    ]
    if config is not None:
        results.update(participant_benchmark(scene, config=config, participants=participants))
    results["targets_met"] = {key: target_met(key, results.get(key)) for key in TARGETS}
    return results
