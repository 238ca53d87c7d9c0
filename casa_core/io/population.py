"""The operator population file that `casa calibrate` writes (format version 1).

A JSON object (docs/calibration.md, "The population file"):

``format``, ``version``
    ``"casa-operator-population"`` and ``1``.
``dataset``, ``operator``, ``fit_methods``, ``seed``, ``simulations``, ``usable_simulations``
    What was fitted, with which operator model, to which methods' trials, and how.
``population``
    The population to draw simulated participants from, in the shape of the config's
    ``simulation.population``: each lognormal parameter's ``median`` and ``sigma``, and
    ``max_keys``; intermittent control's ``bout``, ``pause`` and ``planning`` when they were
    fitted (the predictive operator's).
``posterior``
    ``parameters`` (names), ``prior_log_bounds`` (``[low, high]`` of each log-median) and
    ``log_median_samples`` (one row per posterior sample).

:func:`read_population` checks a file against this and names the key that breaks it; it
never runs code from the file.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path

import jsonschema

from casa_core.config import ConfigError
from casa_core.io.atomic import atomic_write_text
from casa_core.vocabulary import INTERMITTENT_PARAMETERS

FORMAT = "casa-operator-population"
VERSION = 1
#: Whom the simulated participants are drawn from when no population file is set.
CONFIG_POPULATION = "simulation.population of the config"
LOGNORMAL: tuple[str, ...] = ("reaction_time", "perception_noise", "deadband", "lapse_rate")
LOGNORMAL += ("lapse_duration", "wrong_key")

_NUMBER = {"type": "number"}
_POSITIVE = {"type": "number", "exclusiveMinimum": 0}
_LOGNORMAL = {
    "type": "object",
    "additionalProperties": False,
    "required": ["median", "sigma"],
    "properties": {"median": _POSITIVE, "sigma": {"type": "number", "minimum": 0}},
}
SCHEMA = {
    "type": "object",
    "required": ["format", "version", "dataset", "operator", "population", "posterior"],
    "properties": {
        "format": {"const": FORMAT},
        "version": {"const": VERSION},
        "dataset": {"type": "string"},
        "operator": {"enum": ["lookahead", "predictive"]},
        "fit_methods": {"type": "array", "items": {"type": "string"}},
        "seed": {"type": "integer"},
        "simulations": {"type": "integer", "minimum": 0},
        "usable_simulations": {"type": "integer", "minimum": 0},
        "population": {
            "type": "object",
            "additionalProperties": False,
            "required": [*LOGNORMAL, "max_keys"],
            "properties": {
                **{name: _LOGNORMAL for name in (*LOGNORMAL, *INTERMITTENT_PARAMETERS)},
                "max_keys": {
                    "type": "object",
                    "additionalProperties": False,
                    "required": ["values", "p"],
                    "properties": {
                        "values": {"type": "array", "minItems": 1, "items": {"type": "integer"}},
                        "p": {"type": "array", "minItems": 1, "items": _NUMBER},
                    },
                },
            },
        },
        "posterior": {
            "type": "object",
            "required": ["parameters", "prior_log_bounds", "log_median_samples"],
            "properties": {
                "parameters": {"type": "array", "items": {"type": "string"}},
                "prior_log_bounds": {
                    "type": "array",
                    "items": {"type": "array", "items": _NUMBER, "minItems": 2, "maxItems": 2},
                },
                "log_median_samples": {
                    "type": "array",
                    "items": {"type": "array", "items": _NUMBER},
                },
            },
        },
    },
}


class PopulationFileError(ConfigError):
    """A population file that cannot be used; the message names the file and the key."""


def read_population(path: Path | str) -> dict:
    """The checked document of a population file (module docstring).

    Raises
    ------
    PopulationFileError
        When the file is missing, is not JSON, or breaks the format; names the key.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "p.json"
    >>> _ = path.write_text('{"format": "casa-operator-population", "version": 2}')
    >>> read_population(path)
    Traceback (most recent call last):
    ...
    casa_core.io.population.PopulationFileError: ...: key (top level): 'dataset' is ...
    """
    path = Path(path)
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise PopulationFileError(f"{path}: no such population file") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise PopulationFileError(f"{path}: not a JSON population file ({error})") from None
    problems = sorted(
        jsonschema.Draft202012Validator(SCHEMA).iter_errors(document), key=lambda e: list(e.path)
    )
    if problems:
        first = problems[0]
        where = "/".join(str(part) for part in first.path) or "(top level)"
        raise PopulationFileError(
            f"{path}: key {where}: {first.message} (format {FORMAT} version {VERSION})"
        )
    keys = document["population"]["max_keys"]
    if len(keys["values"]) != len(keys["p"]) or abs(sum(keys["p"]) - 1) > 1e-9:
        raise PopulationFileError(
            f"{path}: key population/max_keys: `p` must have one probability per value, "
            "summing to 1"
        )
    return document


def population_label(simulation: Mapping) -> str:
    """Whom a config's simulated participants are drawn from, in words.

    Examples
    --------
    >>> population_label({"operator_population": None})
    'simulation.population of the config'
    """
    path = simulation.get("operator_population")
    if path is None:
        return CONFIG_POPULATION
    document = read_population(path)
    return f"{Path(path).name}, fitted by casa calibrate to dataset {document['dataset']}"


def write_population(path: Path | str, document: dict) -> Path:
    """Write a population document atomically, after checking it as :func:`read_population` does.

    Examples
    --------
    >>> import tempfile
    >>> write_population(Path(tempfile.mkdtemp()) / "p.json", {"format": "x"})
    Traceback (most recent call last):
    ...
    jsonschema.exceptions.ValidationError: ...
    """
    jsonschema.validate(document, SCHEMA)
    return atomic_write_text(path, json.dumps(document, indent=1) + "\n")
