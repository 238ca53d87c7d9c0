"""A simulated operator's parameters, and their draw from the study's population.

:class:`ParticipantParams` holds one participant's parameters (units and sources:
:mod:`casa_core.study.participants`, docs/departures.md); :func:`draw_participants` draws
them from a :class:`~casa_core.study.settings.Population`. Intermittent control's
``bout``, ``pause`` and ``planning`` are :data:`BOUT`, 0 and 0 unless the population sets
them.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from casa_core.study.settings import LOGNORMAL_PARAMETERS, Lognormal, Population
from casa_core.vocabulary import INTERMITTENT_PARAMETERS

#: Longest the predictive operator holds keys before it lets go to watch the arm, s.
BOUT = 1.0
#: The priors of intermittent control's population medians, s: ranges uniform in log space,
#: fixed from the literature before any fit (docs/departures.md, "Where each operator
#: parameter comes from"): the bout a factor 3 either side of BOUT, holding manual
#: control's open-loop intervals of 0.5-1.25 s (Loram et al. 2011); the pause from below the
#: refractory duration (0.25-0.55 s, van de Kamp et al. 2013) to seconds of move and wait
#: (Ferrell 1965); planning a factor 3 either side of the Keystroke-Level Model's
#: M = 1.35 s (Card, Moran & Newell 1980).
INTERMITTENT_PRIORS = {"bout": (1 / 3, 3.0), "pause": (0.1, 3.0), "planning": (0.45, 4.05)}
#: Spread (lognormal sigma) between people of each intermittent parameter when a fitted
#: population sets its median and the config no spread: that of the population's other
#: chosen duration, ``lapse_duration`` (docs/departures.md).
INTERMITTENT_SIGMA = 0.3


@dataclass(frozen=True)
class ParticipantParams:
    """One participant's operator parameters (units in :mod:`casa_core.study.participants`).

    ``bout``, ``pause`` and ``planning`` (s) are the predictive operator's intermittent
    control (:class:`~casa_core.study.participants.PredictiveParticipant`).
    """

    reaction_time: float
    perception_noise: float
    deadband: float
    lapse_rate: float
    lapse_duration: float
    wrong_key: float
    max_keys: int
    bout: float = BOUT
    pause: float = 0.0
    planning: float = 0.0

    def as_dict(self) -> dict:
        return asdict(self)


def _lognormal(spec: Lognormal, rng: np.random.Generator) -> float:
    return float(spec.median * np.exp(spec.sigma * rng.standard_normal()))


def draw_participants(
    n: int, population: Population, rng: np.random.Generator
) -> list[ParticipantParams]:
    """Draw ``n`` participants from the population of the study's settings.

    Each parameter is lognormal (:class:`~casa_core.study.settings.Lognormal`) except
    ``max_keys``, one of its ``values`` drawn with the probabilities ``p``. The
    parameters of intermittent control the population sets are drawn last, after every
    participant's other parameters, in the order of
    :data:`~casa_core.vocabulary.INTERMITTENT_PARAMETERS`: with or without them, the
    other parameters are the same draws.

    Examples
    --------
    >>> from casa_core.config import DEFAULT_CONFIG, load_config
    >>> from casa_core.study.settings import StudySettings
    >>> population = StudySettings.from_config(load_config(DEFAULT_CONFIG)).population
    >>> plain = draw_participants(2, population, np.random.default_rng(1))
    >>> paused = replace(population, pause=Lognormal(0.5, 0.3))
    >>> drawn = draw_participants(2, paused, np.random.default_rng(1))
    >>> [p.deadband for p in drawn] == [p.deadband for p in plain], plain[0].pause
    (True, 0.0)
    >>> 0.2 < drawn[0].pause < 1.5
    True
    """
    drawn = []
    for _ in range(n):
        values: dict[str, float] = {}
        for name in LOGNORMAL_PARAMETERS:
            values[name] = _lognormal(getattr(population, name), rng)
        values["wrong_key"] = min(values["wrong_key"], 0.5)
        keys = population.max_keys
        max_keys = int(rng.choice(keys.values, p=keys.p))
        drawn.append(ParticipantParams(**values, max_keys=max_keys))
    present = [name for name in INTERMITTENT_PARAMETERS if getattr(population, name) is not None]
    if not present:
        return drawn
    drawn_last: list[dict] = [
        {name: _lognormal(getattr(population, name), rng) for name in present} for _ in drawn
    ]
    return [replace(params, **extra) for params, extra in zip(drawn, drawn_last, strict=True)]
