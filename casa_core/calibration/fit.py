"""Neural posterior estimation of the operator population (sbi's NPE), and its predictions.

The free parameters are the logarithms of the population's medians
(:func:`~casa_core.calibration.simulator.fitted_parameters`). Their prior is uniform in log
space, fixed before any fit was run: over a factor :data:`PRIOR_FACTOR` either side of the
study's own medians (``simulation.population``), wide enough to hold every value the
operator literature cites (docs/departures.md, "Simulated operators"), narrow enough to
keep the operator in the regime where it finishes a trial; and for intermittent control
over the ranges of :data:`~casa_core.study.operator_params.INTERMITTENT_PRIORS`, taken
from its literature. NPE (sbi) learns the posterior from simulations
drawn from the prior, once for all observations (it is amortised), which is what makes
the parameter-recovery check over many synthetic datasets affordable: one training set
serves them all.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from casa_core.study.operator_params import INTERMITTENT_PRIORS
from casa_core.study.settings import Population

#: The prior of each median spans median / PRIOR_FACTOR to median * PRIOR_FACTOR.
PRIOR_FACTOR = 3.0
#: sbi's density estimator: a neural spline flow. On the recovery check's simulations
#: (docs/calibration.md) sbi's default, a masked autoregressive flow, and a mixture
#: density network gave 90% intervals covering 72-84% of true values; the spline flow 85-91%.
DENSITY_ESTIMATOR = "nsf"
#: Posterior draws per kept sample (:func:`sample_posterior`).
OVERSAMPLE = 10
#: Added to every summary before its logarithm is taken (:func:`features`).
FEATURE_FLOOR = 0.01


def prior_bounds(base: Population, parameters: Sequence[str]) -> np.ndarray:
    """``[low, high]`` of each log-median, one row per name of ``parameters``.

    Examples
    --------
    >>> from casa_core.config import DEFAULT_CONFIG, load_config
    >>> base = Population.from_config(load_config(DEFAULT_CONFIG)["simulation"]["population"])
    >>> bounds = np.exp(prior_bounds(base, ["reaction_time", "pause"]))
    >>> bounds.round(4).tolist()  # s
    [[0.1167, 1.05], [0.1, 3.0]]
    """
    rows: list[list[float]] = []
    for name in parameters:
        if name in INTERMITTENT_PRIORS:
            rows.append(np.log(INTERMITTENT_PRIORS[name]).tolist())
        else:
            centre = np.log(getattr(base, name).median)
            rows.append([centre - np.log(PRIOR_FACTOR), centre + np.log(PRIOR_FACTOR)])
    return np.array(rows, dtype=float)


def draw_prior(bounds: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` log-medians drawn uniformly within ``bounds``, one row each."""
    low, high = bounds[:, 0], bounds[:, 1]
    return low + (high - low) * rng.random((n, len(bounds)))


def features(x: np.ndarray) -> np.ndarray:
    """What the network reads: the logarithm of each summary plus :data:`FEATURE_FLOOR`.

    Every summary is positive and right-skewed (a timed-out trial's duration, a lost arm's
    error); the logarithm keeps a few such simulations from dominating the z-scoring.
    """
    return np.log(np.asarray(x, dtype=float) + FEATURE_FLOOR)


def _torch_prior(bounds: np.ndarray):
    import torch
    from sbi.utils import BoxUniform

    return BoxUniform(
        low=torch.tensor(bounds[:, 0], dtype=torch.float32),
        high=torch.tensor(bounds[:, 1], dtype=torch.float32),
    )


def usable(x: np.ndarray) -> np.ndarray:
    """Which rows of summaries are all finite (a simulation can give none, e.g. no trial)."""
    return np.all(np.isfinite(x), axis=1)


def train_posterior(theta: np.ndarray, x: np.ndarray, bounds: np.ndarray, *, seed: int):
    """sbi's NPE posterior, trained on the simulations ``(theta, x)`` with finite ``x``.

    Raises
    ------
    ValueError
        With fewer than 10 finite simulations: too few to train on.
    """
    import torch
    from sbi.inference import NPE

    keep = usable(x)
    if keep.sum() < 10:
        raise ValueError(f"{int(keep.sum())} simulations with finite summaries; at least 10 needed")
    torch.manual_seed(seed)
    prior = _torch_prior(bounds)
    trainer = NPE(prior=prior, density_estimator=DENSITY_ESTIMATOR, show_progress_bars=False)
    trainer.append_simulations(
        torch.tensor(theta[keep], dtype=torch.float32),
        torch.tensor(features(x[keep]), dtype=torch.float32),
    )
    estimator = trainer.train()
    return trainer.build_posterior(estimator)


def sample_posterior(
    posterior, x_observed: np.ndarray, n: int, *, seed: int, bounds: np.ndarray
) -> np.ndarray:
    """``n`` log-medians from the posterior given the observed summaries, one row each.

    The network's density is sampled :data:`OVERSAMPLE` times over and the draws inside
    the prior kept, in order (sbi's own rejection sampler can run for ever when almost no
    mass is inside).

    Raises
    ------
    ValueError
        When fewer than ``n`` of the draws are inside the prior: the network has not
        learned these summaries (too few simulations for their number).
    """
    import torch

    torch.manual_seed(seed)
    observed = torch.tensor(features(x_observed), dtype=torch.float32)
    drawn = posterior.sample(
        (OVERSAMPLE * n,), x=observed, show_progress_bars=False, reject_outside_prior=False
    )
    drawn = drawn.detach().numpy().astype(float)
    inside = drawn[np.all((drawn >= bounds[:, 0]) & (drawn <= bounds[:, 1]), axis=1)]
    if len(inside) < n:
        raise ValueError(
            f"only {len(inside) / len(drawn):.1%} of the posterior's draws lie inside the "
            f"prior for {len(drawn[0])} parameters and {len(x_observed)} summaries: the "
            "network has not learned them; run more simulations (--simulations)"
        )
    return inside[:n]


def central_interval(samples: np.ndarray, level: float = 0.9) -> np.ndarray:
    """``[low, high]`` of each column: the central ``level`` interval of the samples."""
    tail = (1 - level) / 2
    return np.column_stack(
        [np.quantile(samples, tail, axis=0), np.quantile(samples, 1 - tail, axis=0)]
    )


def coverage(intervals: Sequence[np.ndarray], truths: np.ndarray) -> np.ndarray:
    """The share of datasets whose interval holds the true value, per parameter."""
    inside = [
        (box[:, 0] <= truth) & (truth <= box[:, 1])
        for box, truth in zip(intervals, truths, strict=True)
    ]
    return np.mean(inside, axis=0)


def shrinkage(samples: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """1 - posterior variance / prior variance, per parameter: 0 learns nothing, 1 everything."""
    prior_variance = (bounds[:, 1] - bounds[:, 0]) ** 2 / 12
    return 1 - np.var(samples, axis=0) / prior_variance
