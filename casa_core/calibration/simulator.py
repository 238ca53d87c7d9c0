"""The simulator of `casa calibrate`: a dataset's design run by simulated operators in pybullet.

A candidate population (the operator parameters' medians; their spreads and ``max_keys``
stay the study's) is turned into one simulated participant per person of the design, who
runs that person's trials in the same scene, each a closed-loop trial with pybullet
(:func:`casa_core.study.closed_loop.run_trial`). Every draw comes from
``numpy.random.default_rng([seed, draw, person, trial])``, so a simulation does not depend
on which process runs it.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from casa_core.assist.presets import Preset
from casa_core.assist.tasks import intended_trajectory
from casa_core.calibration.design import Design
from casa_core.calibration.summaries import SUMMARIES, cell_means, trial_summaries
from casa_core.scene import Scene
from casa_core.study.closed_loop import run_trial
from casa_core.study.participants import draw_participants, make_participant
from casa_core.study.settings import LOGNORMAL_PARAMETERS, Lognormal, Population

#: The free parameters of the fit: the medians of the population's lognormal parameters.
PARAMETERS = LOGNORMAL_PARAMETERS


def with_medians(population: Population, medians) -> Population:
    """``population`` with its lognormal medians replaced, in the order of :data:`PARAMETERS`."""
    changed = {
        name: Lognormal(float(value), getattr(population, name).sigma)
        for name, value in zip(PARAMETERS, medians, strict=True)
    }
    return replace(population, **changed)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Simulator:
    """Runs a design with the operators of a candidate population.

    Parameters
    ----------
    scene : Scene
    design : Design
    base : Population
        The spreads and ``max_keys`` of every candidate population.
    operator : str
        The operator model (``simulation.operator``).
    inference : Preset
        How the assistant infers in the assisted trials.
    seed : int
    """

    scene: Scene
    design: Design
    base: Population
    operator: str
    inference: Preset
    seed: int

    def trials(self, medians, draw: int, sim=None) -> pd.DataFrame:
        """One simulated dataset: each planned trial's summaries, in the design's order."""
        from casa_core.robot.sim import ArmSimulation

        population = with_medians(self.base, medians)
        own = sim is None
        sim = sim or ArmSimulation(self.scene)
        rows = []
        try:
            for person, participant in enumerate(self.design.participants):
                rng = np.random.default_rng([self.seed, draw, person])
                params = draw_participants(1, population, rng)[0]
                for number, planned in enumerate(self.design.of(participant)):
                    reference = intended_trajectory(planned.task, self.scene)
                    source = make_participant(
                        params,
                        reference,
                        rng=np.random.default_rng([self.seed, draw, person, number + 1]),
                        tick=self.scene.teleop.dt,
                        operator=self.operator,
                        speed=self.scene.teleop.speed,
                        rot_speed=self.scene.teleop.rot_speed,
                    )
                    result = run_trial(
                        self.scene,
                        planned.task,
                        planned.method,
                        source,
                        participant=participant,
                        phase=planned.phase,
                        max_duration=planned.max_duration,
                        sim=sim,
                        inference=self.inference,
                    )
                    summary = trial_summaries(result.frame, reference, dt=self.scene.teleop.dt)
                    rows.append({"task": planned.task, "method": planned.method, **summary})
        finally:
            if own:
                sim.close()
        return pd.DataFrame(rows, columns=["task", "method", *SUMMARIES])

    def summary(self, medians, draw: int, sim=None) -> np.ndarray:
        """The design's cell means (:func:`~casa_core.calibration.summaries.cell_means`)."""
        return cell_means(self.trials(medians, draw, sim), self.design.cells)


_WORKER: dict = {}


def _install(simulator: Simulator) -> None:
    # A forked worker inherits the simulator; a scene does not pickle.
    _WORKER["simulator"] = simulator


def _run_chunk(jobs, simulator: Simulator | None = None) -> list[np.ndarray]:
    from casa_core.robot.sim import ArmSimulation

    simulator = simulator or _WORKER["simulator"]
    with ArmSimulation(simulator.scene) as sim:
        return [simulator.summary(medians, draw, sim) for draw, medians in jobs]


def simulate_many(
    simulator: Simulator, medians: np.ndarray, draws, *, cores: int = 1, progress=None
) -> np.ndarray:
    """The summaries of many candidate populations, one row each, in the order given.

    ``medians`` has one row per simulation; ``draws`` numbers them (their seeds). The
    work is split into chunks over ``cores`` processes; ``progress(n)`` is called as
    each chunk of ``n`` simulations finishes.
    """
    jobs = list(zip([int(d) for d in draws], np.asarray(medians, dtype=float), strict=True))
    if not jobs:
        return np.empty((0, len(simulator.design.cells) * len(SUMMARIES)))
    cores = max(1, min(int(cores), len(jobs), os.cpu_count() or 1))
    size = max(1, min(8, -(-len(jobs) // (4 * cores))))
    chunks = [jobs[i : i + size] for i in range(0, len(jobs), size)]
    results: list[list[np.ndarray]] = [[] for _ in chunks]
    if cores == 1:
        for i, chunk in enumerate(chunks):
            results[i] = _run_chunk(chunk, simulator)
            if progress:
                progress(len(chunk))
    else:
        context = multiprocessing.get_context("fork")
        with ProcessPoolExecutor(cores, context, _install, (simulator,)) as pool:
            futures = {pool.submit(_run_chunk, chunk): i for i, chunk in enumerate(chunks)}
            for future in as_completed(futures):
                results[futures[future]] = future.result()
                if progress:
                    progress(len(chunks[futures[future]]))
    return np.array([row for chunk in results for row in chunk])
