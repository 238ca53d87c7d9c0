"""The paper's equations, numpy only: confidence, the intent posterior, arbitration.

The modules, each with one job:

- :mod:`~casa_core.model.confidence`: Situational confidence: suboptimality and the estimate
  beta_hat (paper, Sec. II-C).
- :mod:`~casa_core.model.inference`: Intent inference: the Boltzmann likelihood under
  Laplace's method and the posterior.
- :mod:`~casa_core.model.arbitration`: Arbitration (the human's control authority alpha) and
  policy blending.
"""

from casa_core.model.arbitration import (
    alpha_belief,
    alpha_confidence,
    alpha_distance,
    blend,
)
from casa_core.model.confidence import (
    beta_hat,
    suboptimality,
)
from casa_core.model.inference import (
    log_likelihood,
    posterior,
)

__all__ = [
    "alpha_belief",
    "alpha_confidence",
    "alpha_distance",
    "beta_hat",
    "blend",
    "log_likelihood",
    "posterior",
    "suboptimality",
]
