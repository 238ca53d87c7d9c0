"""``casa bench``: a whole simulated CASA trial, timed, and its pybullet work alone.

The trial is the Unknown Goal task driven by :class:`~casa_core.study.key_sources.WaypointKeys`
(an expert that rests at the goal once there) for :data:`TRIAL_SECONDS`, in closed loop
with pybullet (:func:`casa_core.study.closed_loop.run_trial`). :func:`trial_realtime_factor`
times it whole; :func:`trial_physics_cpu_s` times the same trial's calls into pybullet
(:class:`~casa_core.bench.stages.StageClock`), so that ``casa bench`` reports the trial's
cost as a multiple of its physics, measured in the same run
(``trial_cost_over_physics``): a ratio that travels between machines where absolute
times do not.
"""

from __future__ import annotations

import time

import numpy as np

from casa_core.assist.tasks import task_waypoints
from casa_core.bench.stages import StageClock
from casa_core.robot.sim import ArmSimulation
from casa_core.scene import Scene
from casa_core.study.closed_loop import run_trial
from casa_core.study.key_sources import WaypointKeys

#: Simulated seconds of the benchmark trial: the paper's 15 s horizon.
TRIAL_SECONDS = 15.0


class _ExpertThenRest(WaypointKeys):
    """:class:`WaypointKeys` that rests at the last waypoint instead of finishing."""

    def keys(self, t: float, state) -> frozenset[str]:
        held = super().keys(t, state)
        self.done = False
        return held


def _bench_trial(scene: Scene, duration: float, sim) -> None:
    source = _ExpertThenRest(task_waypoints("unknown_goal", scene)[1:])
    run_trial(
        scene, "unknown_goal", "CASA", source, participant="bench", max_duration=duration, sim=sim
    )


def trial_realtime_factor(
    scene: Scene,
    *,
    duration: float = TRIAL_SECONDS,
    repeats: int = 3,
    reuse_simulation: bool = True,
) -> tuple[float, float]:
    """Simulated seconds per second of a whole CASA trial, pybullet included.

    The Unknown Goal task driven by :class:`WaypointKeys` for ``duration`` seconds
    (the expert rests at the goal once there). By default one simulation, created
    before the timing, runs every trial, as the simulated protocol, the session runner
    and replay run theirs (one simulation per stage, reset between trials); with
    ``reuse_simulation=False`` each trial creates and tears down its own simulation
    inside the timing (about 25 ms, mostly ``pybullet.connect`` and loading the arm).

    Returns
    -------
    (float, float)
        Medians over ``repeats`` trials of simulated seconds per CPU second of this
        process (what one core achieves, whatever else runs on the machine) and per
        wall-clock second.
    """
    shared = ArmSimulation(scene) if reuse_simulation else None
    per_cpu, per_wall = [], []
    try:
        for _ in range(repeats):
            cpu, wall = time.process_time(), time.perf_counter()
            _bench_trial(scene, duration, shared)
            per_cpu.append(duration / (time.process_time() - cpu))
            per_wall.append(duration / (time.perf_counter() - wall))
    finally:
        if shared is not None:
            shared.close()
    return float(np.median(per_cpu)), float(np.median(per_wall))


def trial_physics_cpu_s(
    scene: Scene, *, duration: float = TRIAL_SECONDS, repeats: int = 3
) -> float:
    """Median CPU seconds the trial of :func:`trial_realtime_factor` spends in pybullet.

    The same trial (the expert's keys are deterministic, so are its pybullet calls) run
    under :meth:`StageClock.pybullet <casa_core.bench.stages.StageClock.pybullet>`: the
    time inside every pybullet function it calls, with the clock's own overhead taken off.
    """
    seconds = []
    with ArmSimulation(scene) as sim:
        for _ in range(repeats):
            with StageClock.pybullet() as clock:
                _bench_trial(scene, duration, sim)
            seconds.append(clock.seconds["pybullet"])
    return float(np.median(seconds))
