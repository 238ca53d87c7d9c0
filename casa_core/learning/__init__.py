"""Learning new intents from demonstrations by deep maximum-entropy IRL (paper, Sec. II-E).

``MaxEntIRL(name, config=IRLConfig(), seed=0).fit(demonstrations, objects)`` learns a
:class:`NeuralIntent`, a cost over states whose optimum the assistant plans. The modules,
each with one job:

- :mod:`~casa_core.learning.features`: the cost's inputs, network and formula;
- :mod:`~casa_core.learning.network`: the network run in torch, its products in a fixed order;
- :mod:`~casa_core.learning.neural_intent`: the learned intent and its calibration;
- :mod:`~casa_core.learning.config`: the settings (:class:`IRLConfig`);
- :mod:`~casa_core.learning.demonstrations`: demonstrations resampled for IRL;
- :mod:`~casa_core.learning.maxent`: the estimator (:class:`MaxEntIRL`);
- :mod:`~casa_core.learning.numpy_cost`, :mod:`~casa_core.learning.adam`: the same cost
  and its gradient without autograd, and the network's Adam written out;
- :mod:`~casa_core.learning.library`: the intent file format (casa-intent): save, load,
  check, list (imported on its own: it uses this package).
"""

from casa_core.learning.config import IRLConfig
from casa_core.learning.demonstrations import demo_steps, demo_waypoints
from casa_core.learning.features import (
    bounded_cost,
    cost_logits,
    cost_network,
    feature_names,
    object_positions,
    state_features,
)
from casa_core.learning.maxent import MaxEntIRL, end_match, kept_record, stop_reason
from casa_core.learning.neural_intent import NeuralIntent, calibrate

__all__ = [
    "IRLConfig",
    "MaxEntIRL",
    "NeuralIntent",
    "bounded_cost",
    "calibrate",
    "cost_logits",
    "cost_network",
    "demo_steps",
    "demo_waypoints",
    "end_match",
    "feature_names",
    "kept_record",
    "object_positions",
    "state_features",
    "stop_reason",
]
