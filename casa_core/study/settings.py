"""The simulated study's settings, read once from a validated workflow config.

:class:`StudySettings` is what the simulated study (:mod:`casa_core.study.simulate`) and
the expert case study take from the config: the trials' seed, length and operator
model, the protocol's demonstrations and misspecification threshold, the inference
preset and the population the participants are drawn from (:class:`Population`).
The edge (the ``casa`` commands, the benchmark) builds it with
:meth:`StudySettings.from_config` or :meth:`StudySettings.from_case_study` from a config
that :func:`casa_core.config.load_config` validated, which filled in every default of the
schema: these read keys, never defaults. Code below takes the settings, or the plain
values it needs.

Examples
--------
>>> from casa_core.config import DEFAULT_CONFIG, load_config
>>> settings = StudySettings.from_config(load_config(DEFAULT_CONFIG))
>>> settings.seed, settings.max_duration, settings.operator, settings.inference.name
(2021, 40.0, 'predictive', 'casa')
>>> settings.population.reaction_time, settings.population.max_keys.values
(Lognormal(median=0.35, sigma=0.25), (1, 2, 3))
>>> expert = StudySettings.from_case_study(load_config(DEFAULT_CONFIG))
>>> expert.demonstrations, expert.demonstrations_when, expert.population is None
(5, 'always', True)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from casa_core.assist.presets import Preset, preset
from casa_core.defaults import DEMONSTRATIONS
from casa_core.vocabulary import INTERMITTENT_PARAMETERS

#: The population's lognormal parameters, in the config's order (``max_keys`` is not one).
LOGNORMAL_PARAMETERS = (
    "reaction_time",
    "perception_noise",
    "deadband",
    "lapse_rate",
    "lapse_duration",
    "wrong_key",
)


@dataclass(frozen=True)
class Lognormal:
    """A lognormal parameter: ``value = median * exp(sigma * N(0, 1))``."""

    median: float
    sigma: float


@dataclass(frozen=True)
class MaxKeys:
    """Most keys held at once: one of ``values``, drawn with the probabilities ``p``."""

    values: tuple[int, ...]
    p: tuple[float, ...]


@dataclass(frozen=True)
class Population:
    """The population of simulated participants (``simulation.population`` of the config).

    Units and sources: :mod:`casa_core.study.participants`. ``bout``, ``pause`` and
    ``planning`` (:data:`~casa_core.vocabulary.INTERMITTENT_PARAMETERS`) are None when the
    config does not set them, which gives the operators the defaults of
    :class:`~casa_core.study.operator_params.ParticipantParams`.
    """

    reaction_time: Lognormal
    perception_noise: Lognormal
    deadband: Lognormal
    lapse_rate: Lognormal
    lapse_duration: Lognormal
    wrong_key: Lognormal
    max_keys: MaxKeys
    bout: Lognormal | None = None
    pause: Lognormal | None = None
    planning: Lognormal | None = None

    @classmethod
    def from_config(cls, population: Mapping) -> Population:
        """From a validated config's ``simulation.population`` block.

        Examples
        --------
        >>> block = {name: {"median": 1, "sigma": 0.5} for name in LOGNORMAL_PARAMETERS}
        >>> drawn = Population.from_config({**block, "max_keys": {"values": [1], "p": [1]}})
        >>> drawn.deadband, drawn.max_keys, drawn.pause
        (Lognormal(median=1.0, sigma=0.5), MaxKeys(values=(1,), p=(1.0,)), None)
        """
        keys = population["max_keys"]
        lognormals = {
            name: Lognormal(float(population[name]["median"]), float(population[name]["sigma"]))
            for name in (*LOGNORMAL_PARAMETERS, *INTERMITTENT_PARAMETERS)
            if name in population
        }
        return cls(
            **lognormals,
            max_keys=MaxKeys(tuple(int(v) for v in keys["values"]), tuple(map(float, keys["p"]))),
        )


@dataclass(frozen=True)
class StudySettings:
    """What a simulated participant's protocol reads from the config.

    Attributes
    ----------
    seed : int
        Seed of the participant's parameters and of every trial (``simulation.seed``).
    max_duration : float
        Seconds; a trial ends when the participant is done or at this time.
    demonstrations : int
        Demonstrations per unknown task.
    demonstrations_when : str
        ``always`` (the paper's protocol) or ``detected`` (only when CASA flagged
        misspecification).
    epsilon : float
        The misspecification threshold on beta_hat.
    operator : str
        The operator model (:data:`casa_core.study.participants.OPERATORS`).
    inference : Preset
        How the assistant infers (the config's ``inference`` block).
    population : Population or None
        Whom the participants are drawn from; None for the case study, whose expert is
        given (:data:`casa_core.study.simulate.EXPERT`).
    """

    seed: int
    max_duration: float
    demonstrations: int
    demonstrations_when: str
    epsilon: float
    operator: str
    inference: Preset
    population: Population | None = None

    @classmethod
    def from_config(cls, config: Mapping) -> StudySettings:
        """The simulated study's: a validated config's ``simulation`` and ``inference``."""
        simulation = config["simulation"]
        return cls(
            seed=int(simulation["seed"]),
            max_duration=float(simulation["max_duration"]),
            demonstrations=int(simulation["demonstrations"]),
            demonstrations_when=simulation["demonstrations_when"],
            epsilon=float(simulation["epsilon"]),
            operator=simulation["operator"],
            inference=inference_preset(config),
            population=configured_population(simulation),
        )

    @classmethod
    def from_case_study(cls, config: Mapping) -> StudySettings:
        """The expert case study's: a validated config's ``case_study`` and ``inference``.

        The expert follows the paper's protocol: :data:`~casa_core.defaults.DEMONSTRATIONS`
        demonstrations of every unknown task, always; there is no population.
        """
        case_study = config["case_study"]
        return cls(
            seed=int(case_study["seed"]),
            max_duration=float(case_study["max_duration"]),
            demonstrations=DEMONSTRATIONS,
            demonstrations_when="always",
            epsilon=float(case_study["epsilon"]),
            operator=case_study["operator"],
            inference=inference_preset(config),
        )


def configured_population(simulation: Mapping) -> Population:
    """The population of a validated config's ``simulation`` block.

    The fitted population of ``operator_population`` (a `casa calibrate` file,
    :func:`casa_core.io.population.read_population`) when set, else ``population``. A
    fitted population takes the intermittent control it does not set (a fit of the
    lookahead operator, which has none) from ``population``.
    """
    path = simulation.get("operator_population")
    if path is None:
        return Population.from_config(simulation["population"])
    from casa_core.io.population import read_population

    fitted = read_population(path)["population"]
    configured = simulation["population"]
    unfitted = {
        name: configured[name]
        for name in INTERMITTENT_PARAMETERS
        if name in configured and name not in fitted
    }
    return Population.from_config({**fitted, **unfitted})


def inference_preset(config: Mapping) -> Preset:
    """The inference preset of a validated config's ``inference`` block.

    Examples
    --------
    >>> inference_preset({"inference": {"preset": "original", "evidence": None}}).evidence
    'executed'
    """
    inference = config["inference"]
    return preset(inference["preset"], evidence=inference["evidence"])
