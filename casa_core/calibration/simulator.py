"""The simulator of `casa calibrate`: a dataset's design run by simulated operators in pybullet.

A candidate population (the medians of the operator parameters :func:`fitted_parameters`
names; their spreads and ``max_keys`` stay the study's) is turned into one simulated
participant per person of the design, who runs that person's trials in the same scene,
each a closed-loop trial with pybullet
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
from casa_core.study.closed_loop import simulated_trial
from casa_core.study.operator_params import INTERMITTENT_SIGMA
from casa_core.study.participants import draw_participants
from casa_core.study.settings import LOGNORMAL_PARAMETERS, Lognormal, Population
from casa_core.vocabulary import INTERMITTENT_PARAMETERS


def fitted_parameters(operator: str) -> tuple[str, ...]:
    """The free parameters of a fit of ``operator``: the medians of these parameters.

    The predictive operator's intermittent control is fitted with the rest; the lookahead
    operator has none.

    Examples
    --------
    >>> fitted_parameters("predictive")[-3:], len(fitted_parameters("lookahead"))
    (('bout', 'pause', 'planning'), 6)
    """
    if operator == "predictive":
        return (*LOGNORMAL_PARAMETERS, *INTERMITTENT_PARAMETERS)
    return LOGNORMAL_PARAMETERS


def with_medians(population: Population, medians, parameters: tuple[str, ...]) -> Population:
    """``population`` with the medians of ``parameters`` replaced, in that order.

    Each keeps its spread; an intermittent parameter the population does not set gets
    :data:`~casa_core.study.operator_params.INTERMITTENT_SIGMA`.
    """
    changed = {}
    for name, value in zip(parameters, medians, strict=True):
        spec = getattr(population, name)
        changed[name] = Lognormal(float(value), INTERMITTENT_SIGMA if spec is None else spec.sigma)
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

    @property
    def parameters(self) -> tuple[str, ...]:
        """The fit's free parameters (:func:`fitted_parameters` of the operator)."""
        return fitted_parameters(self.operator)

    def trials(self, medians, draw: int, sim=None) -> pd.DataFrame:
        """One simulated dataset: each planned trial's summaries, in the design's order."""
        from casa_core.robot.sim import ArmSimulation

        population = with_medians(self.base, medians, self.parameters)
        own = sim is None
        sim = sim or ArmSimulation(self.scene)
        rows = []
        try:
            for person, participant in enumerate(self.design.participants):
                rng = np.random.default_rng([self.seed, draw, person])
                params = draw_participants(1, population, rng)[0]
                for number, planned in enumerate(self.design.of(participant)):
                    reference = intended_trajectory(planned.task, self.scene)
                    result = simulated_trial(
                        self.scene,
                        planned,
                        reference,
                        params,
                        np.random.default_rng([self.seed, draw, person, number + 1]),
                        participant=participant,
                        operator=self.operator,
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
