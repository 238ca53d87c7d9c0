"""Trust in a calibration: parameter recovery and the hold-out of assisted trials.

:func:`parameter_recovery` simulates synthetic "people" with known medians drawn from the
prior, fits them back with one NPE trained on other simulations, and reports per parameter
how often the 90% posterior interval holds the true value (calibrated: close to 0.9) and
how much the posterior narrows the prior (shrinkage; near 0, the summaries do not identify
the parameter). :func:`holdout` fits synthetic people's NA trials only and predicts their
assisted ones.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from casa_core.calibration import fit
from casa_core.calibration.calibrate import LEVEL, Calibration, calibrate
from casa_core.calibration.design import People
from casa_core.calibration.simulator import Simulator, simulate_many

#: A parameter with a mean shrinkage below this is reported as not identified.
IDENTIFIED_SHRINKAGE = 0.2
RECOVERY_COLUMNS = ("parameter", "datasets", "coverage", "shrinkage", "identified")


def simulate_prior(
    simulator: Simulator, n: int, *, seed: int, cores: int = 1, progress=None
) -> tuple[np.ndarray, np.ndarray]:
    """``n`` simulations of the design from the prior: log-medians and cell means.

    The same draws as :func:`~casa_core.calibration.calibrate.calibrate` makes with ``seed``.
    """
    bounds = fit.prior_bounds(simulator.base, simulator.parameters)
    theta = fit.draw_prior(bounds, n, np.random.default_rng([seed, 0]))
    x = simulate_many(simulator, np.exp(theta), range(n), cores=cores, progress=progress)
    return theta, x


def parameter_recovery(
    simulator: Simulator,
    *,
    train: int,
    datasets: int,
    seed: int,
    cores: int = 1,
    samples: int = 500,
    progress=None,
    prior_simulations: tuple[np.ndarray, np.ndarray] | None = None,
) -> pd.DataFrame:
    """Coverage of the 90% intervals and shrinkage, per parameter, over ``datasets`` fits.

    The first ``train`` simulations from the prior train the network; the next
    ``datasets`` are the synthetic people. ``prior_simulations`` (log-medians and cell
    means, from :func:`simulate_prior`) gives them instead of new ones.
    """
    bounds = fit.prior_bounds(simulator.base, simulator.parameters)
    if prior_simulations is None:
        prior_simulations = simulate_prior(
            simulator, train + datasets, seed=seed, cores=cores, progress=progress
        )
    theta, x = prior_simulations
    posterior = fit.train_posterior(theta[:train], x[:train], bounds, seed=seed)
    intervals, shrunk, truths = [], [], []
    for k in range(train, train + datasets):
        if not fit.usable(x[k : k + 1])[0]:
            continue
        drawn = fit.sample_posterior(posterior, x[k], samples, seed=seed + k, bounds=bounds)
        intervals.append(fit.central_interval(drawn, LEVEL))
        shrunk.append(fit.shrinkage(drawn, bounds))
        truths.append(theta[k])
    covered = fit.coverage(intervals, np.array(truths))
    mean_shrinkage = np.mean(shrunk, axis=0)
    return pd.DataFrame(
        {
            "parameter": list(simulator.parameters),
            "datasets": len(truths),
            "coverage": covered,
            "shrinkage": mean_shrinkage,
            "identified": mean_shrinkage >= IDENTIFIED_SHRINKAGE,
        },
        columns=list(RECOVERY_COLUMNS),
    )


def holdout(
    simulator: Simulator,
    true_medians,
    *,
    train: int,
    predictive: int,
    seed: int,
    cores: int = 1,
    progress=None,
    prior_simulations: tuple[np.ndarray, np.ndarray] | None = None,
) -> Calibration:
    """Synthetic people with ``true_medians``, fitted on their NA trials only.

    The returned calibration's predictive table has the assisted cells with ``fitted``
    false: how well the NA fit predicts the people's trials with PBA and CASA.
    """
    rows = simulator.trials(np.asarray(true_medians, dtype=float), draw=2_000_000 + seed)
    people = People("synthetic", simulator.design, rows, ())
    return calibrate(
        people,
        simulator,
        simulations=train,
        predictive=predictive,
        seed=seed,
        cores=cores,
        fit_methods=("NA",),
        progress=progress,
        prior_simulations=prior_simulations,
    )
