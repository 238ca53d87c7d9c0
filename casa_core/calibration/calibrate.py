"""`casa calibrate`: the operator population fitted to people's trials, and how well it fits.

:func:`calibrate` simulates the people's design with candidate populations drawn from the
prior (:mod:`casa_core.calibration.fit`), trains sbi's NPE on them, reads the posterior at
the people's summaries, and simulates the design again with posterior draws: the
posterior predictive table puts the people's summaries beside the simulated ones. The
population it returns has the posterior medians of the medians and the study's spreads.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from casa_core.calibration import fit
from casa_core.calibration.design import People
from casa_core.calibration.simulator import Simulator, simulate_many, with_medians
from casa_core.calibration.summaries import cell_means, summary_labels
from casa_core.study.settings import LOGNORMAL_PARAMETERS, Population
from casa_core.vocabulary import METHODS

#: Posterior samples kept in the population file.
POSTERIOR_SAMPLES = 1000
#: Draw numbers of the posterior predictive simulations start here, apart from the prior's.
PREDICTIVE_DRAWS = 1_000_000
#: The posterior predictive interval of the table.
LEVEL = 0.9
PREDICTIVE_COLUMNS = (
    "task",
    "method",
    "summary",
    "fitted",
    "people",
    "people_trials",
    "simulated_median",
    "simulated_low",
    "simulated_high",
    "inside",
)


@dataclass(frozen=True)
class Calibration:
    """What :func:`calibrate` found (attributes named as in the population file)."""

    dataset: str
    parameters: tuple[str, ...]
    bounds: np.ndarray
    samples: np.ndarray
    population: Population
    predictive: pd.DataFrame
    fit_methods: tuple[str, ...]
    simulations: int
    usable_simulations: int


def fitted_mask(cells: Sequence[tuple[str, str]], methods: Sequence[str]) -> np.ndarray:
    """Which entries of the cell means belong to cells of the given methods."""
    return np.array([method in methods for _, method, _ in summary_labels(cells)])


def calibrate(
    people: People,
    simulator: Simulator,
    *,
    simulations: int,
    predictive: int,
    seed: int,
    cores: int = 1,
    fit_methods: Sequence[str] = METHODS,
    progress: Callable[[int], None] | None = None,
    prior_simulations: tuple[np.ndarray, np.ndarray] | None = None,
) -> Calibration:
    """Fit the operator population to ``people`` (module docstring).

    Parameters
    ----------
    people : People
        The dataset's human trials (:func:`~casa_core.calibration.design.read_people`).
    simulator : Simulator
        Runs ``people.design``; its ``base`` gives the prior's centre and the spreads.
    simulations : int
        Simulations from the prior to train on.
    predictive : int
        Posterior predictive simulations.
    seed : int
        Seed of the prior draws, the training and the posterior samples.
    cores : int
        Processes the simulations run in.
    fit_methods : sequence of str
        The methods whose cells are fitted; the other cells are only predicted (the
        hold-out check fits ``("NA",)``).
    progress : callable, optional
        Called with the number of simulations each finished chunk held.
    prior_simulations : (theta, x), optional
        Simulations of the design from the prior, log-medians and cell means, to train on
        instead of running ``simulations`` new ones (the checks share one set).
    """
    cells = people.design.cells
    mask = fitted_mask(cells, fit_methods)
    if not mask.any():
        raise ValueError(
            f"no trial of the methods {', '.join(fit_methods)} in dataset {people.dataset!r}"
        )
    bounds = fit.prior_bounds(simulator.base, simulator.parameters)
    if prior_simulations is None:
        theta = fit.draw_prior(bounds, simulations, np.random.default_rng([seed, 0]))
        x = simulate_many(
            simulator, np.exp(theta), range(simulations), cores=cores, progress=progress
        )
    else:
        theta, x = prior_simulations
    observed = cell_means(people.summaries, cells)
    posterior = fit.train_posterior(theta, x[:, mask], bounds, seed=seed)
    try:
        samples = fit.sample_posterior(
            posterior, observed[mask], POSTERIOR_SAMPLES, seed=seed + 1, bounds=bounds
        )
    except ValueError as error:
        beyond = unreached(observed, x, summary_labels(cells), mask)
        if beyond:
            error = ValueError(f"{error}. No simulated operator reaches: {'; '.join(beyond)}")
        raise error from None
    population = with_medians(
        simulator.base, np.exp(np.median(samples, axis=0)), simulator.parameters
    )
    draws = samples[np.linspace(0, len(samples) - 1, predictive).astype(int)]
    predicted = simulate_many(
        simulator,
        np.exp(draws),
        range(PREDICTIVE_DRAWS, PREDICTIVE_DRAWS + predictive),
        cores=cores,
        progress=progress,
    )
    table = predictive_table(people, predicted, mask)
    return Calibration(
        people.dataset,
        simulator.parameters,
        bounds,
        samples,
        population,
        table,
        tuple(fit_methods),
        len(theta),
        int(fit.usable(x[:, mask]).sum()),
    )


def unreached(
    observed: np.ndarray, x: np.ndarray, labels: Sequence[tuple[str, str, str]], mask: np.ndarray
) -> list[str]:
    """The fitted summaries whose people's value lies outside every simulation's from the prior.

    Examples
    --------
    >>> x = np.array([[1.0, 5.0], [2.0, 6.0]])
    >>> unreached(np.array([1.5, 9.0]), x, [("a", "NA", "hold"), ("a", "NA", "gap")],
    ...           np.array([True, True]))
    ['a NA gap: people 9, operators 5-6']
    """
    out = []
    for j in np.flatnonzero(mask).tolist():
        column = x[:, j][np.isfinite(x[:, j])]
        if len(column) and not column.min() <= observed[j] <= column.max():
            out.append(beside(*labels[j], observed[j], column.min(), column.max()))
    return out


def beside(
    task: str, method: str, summary: str, people: float, low: float, high: float, *, whose=""
) -> str:
    """One summary of the people beside the operators' range, as messages name it.

    >>> beside("a", "NA", "gap", 9.0, 5.0, 6.0, whose="fitted ")
    'a NA gap: people 9, fitted operators 5-6'
    """
    return f"{task} {method} {summary}: people {people:.3g}, {whose}operators {low:.3g}-{high:.3g}"


def predictive_table(people: People, predicted: np.ndarray, mask: np.ndarray) -> pd.DataFrame:
    """People's cell means beside the simulated ones' median and central interval."""
    cells = people.design.cells
    observed = cell_means(people.summaries, cells)
    counts = people.summaries.groupby(["task", "method"]).size()
    tail = (1 - LEVEL) / 2
    rows = []
    for j, (task, method, name) in enumerate(summary_labels(cells)):
        column = predicted[:, j][np.isfinite(predicted[:, j])]
        low, mid, high = np.quantile(column, [tail, 0.5, 1 - tail]) if len(column) else [np.nan] * 3
        rows.append(
            (
                task,
                method,
                name,
                bool(mask[j]),
                observed[j],
                int(counts[(task, method)]),
                mid,
                low,
                high,
                bool(low <= observed[j] <= high),
            )
        )
    return pd.DataFrame(rows, columns=list(PREDICTIVE_COLUMNS))


def population_document(result: Calibration, *, operator: str, seed: int) -> dict:
    """The population file's document (:mod:`casa_core.io.population`) of a calibration.

    Its population holds the six lognormal parameters and the intermittent control that
    was fitted, none that was not (a lookahead fit's config may set some: the config keeps
    them).
    """
    from casa_core.io.population import FORMAT, VERSION

    population = result.population
    block: dict = {
        name: {"median": getattr(population, name).median, "sigma": getattr(population, name).sigma}
        for name in dict.fromkeys((*LOGNORMAL_PARAMETERS, *result.parameters))
    }
    block["max_keys"] = {
        "values": list(population.max_keys.values),
        "p": list(population.max_keys.p),
    }
    return {
        "format": FORMAT,
        "version": VERSION,
        "dataset": result.dataset,
        "operator": operator,
        "fit_methods": list(result.fit_methods),
        "seed": int(seed),
        "simulations": result.simulations,
        "usable_simulations": result.usable_simulations,
        "population": block,
        "posterior": {
            "parameters": list(result.parameters),
            "prior_log_bounds": result.bounds.tolist(),
            "log_median_samples": np.round(result.samples, 6).tolist(),
        },
    }
