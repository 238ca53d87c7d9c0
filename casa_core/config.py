"""The workflow config: one loader, one schema, defaults written once.

:func:`load_config` reads one or more YAML files, merges each over the ones before it
(nested mappings key by key, as Snakemake merges ``--configfile`` over the Snakefile's
``configfile:``), applies command-line overrides, validates the result against
:data:`SCHEMA_PATH` (``casa_core/config.schema.yaml``: every key, its type, range and
default) and fills in the schema's defaults. The config is read once, at the edge (the
workflow's ``common.smk`` and the ``casa`` commands); code below takes plain values.

Every error names the file, the dotted key and the rule it breaks, e.g.
``config/ci.yaml: simulation.max_duraton: unknown key``.

Examples
--------
>>> import tempfile
>>> folder = Path(tempfile.mkdtemp())
>>> _ = (folder / "overlay.yaml").write_text("simulation: {participants: 3}\\n")
>>> config = load_config(DEFAULT_CONFIG, folder / "overlay.yaml")
>>> config["simulation"]["participants"], config["simulation"]["seed"]
(3, 2021)
>>> load_config() == load_config(DEFAULT_CONFIG) | {"scene": None}  # no file: the defaults
True
>>> _ = (folder / "typo.yaml").write_text("simulation: {max_duraton: 20}\\n")
>>> load_config(DEFAULT_CONFIG, folder / "typo.yaml")  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
casa_core.config.ConfigError: .../typo.yaml: simulation.max_duraton: unknown key; did you ...
"""

from __future__ import annotations

import copy
import difflib
import hashlib
import json
import math
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

if TYPE_CHECKING:
    import jsonschema

#: The schema of the workflow config: every key the package reads, its type, range and default.
SCHEMA_PATH = Path(__file__).with_name("config.schema.yaml")
#: The study's config, ``config/config.yaml`` of the repository.
DEFAULT_CONFIG = Path(__file__).resolve().parents[1] / "config" / "config.yaml"
#: What errors call the config when no file is given: the schema's defaults alone.
PACKAGE_DEFAULTS = "the package's defaults"
#: Where ``--config KEY=VALUE`` overrides are said to come from in errors.
OVERRIDES = "--config"
#: The variant that overlays nothing: the study's config as it is.
DEFAULT_VARIANT = "default"
#: The keys that choose what a run builds, not what a job reads: left out of the config
#: files the workflow writes for its jobs, so that another choice reruns nothing.
TARGET_KEYS = ("datasets", "simulate")
#: Hex digits of the sha256 that name an effective config: enough to tell configurations
#: apart at a glance, short enough for a line of a table or a figure's caption.
DIGEST_LENGTH = 12


class ConfigError(ValueError):
    """A config that cannot be used; the message names the file, the dotted key and the rule."""


@cache
def schema() -> dict:
    """The parsed :data:`SCHEMA_PATH` (read once; do not modify it)."""
    return yaml.safe_load(SCHEMA_PATH.read_text(encoding="utf-8"))


def default(key: str) -> Any:
    """The schema's default of the dotted ``key``.

    Examples
    --------
    >>> default("simulation.epsilon"), default("allow_invalid")
    (1.0, False)
    """
    node = schema()
    for name in key.split("."):
        node = node["properties"][name]
    return copy.deepcopy(node["default"])


def load_config(*paths: Path | str, overrides: Mapping | None = None) -> dict:
    """Read, merge and validate config files; the effective config with defaults filled in.

    Parameters
    ----------
    *paths : path-like
        YAML files, each a mapping; a later file overrides an earlier one key by key
        (nested mappings are merged, other values replaced). Relative paths resolve
        against the working directory. None: the package's defaults, the schema's,
        which are the repository's ``config/config.yaml`` (its ``scene`` aside: null,
        the package's own scene), so that a command works from any folder.
    overrides : mapping, optional
        Applied last, like ``snakemake --config``; strings given for a boolean, integer
        or number key are converted (``"true"``, ``"3"``, ``"0.5"``).

    Returns
    -------
    dict
        The validated config, every default of the schema filled in.

    Raises
    ------
    ConfigError
        Naming the file (or ``--config``), the dotted key and the rule: an unreadable
        file, an unknown key, a value of the wrong type or out of range, a missing
        required key.
    """
    merged: dict = {}
    sources = []
    layers = [(str(path), _read(Path(path))) for path in paths]
    if overrides:
        layers.append((OVERRIDES, _coerce(_plain(overrides), schema())))
    for source, layer in layers:
        _raise(source, _problems(layer, partial=True))
        merge(merged, layer)
        sources.append(source)
    return validate_config(merged, source=" + ".join(sources) or PACKAGE_DEFAULTS)


def validate_config(data: Any, source: str = "config") -> dict:
    """Validate a whole config; a copy with the schema's defaults filled in.

    ``source`` names the config in errors. Raises :class:`ConfigError`.

    Examples
    --------
    >>> validate_config({"simulation": {"participants": 0}}, source="mine.yaml")
    Traceback (most recent call last):
    ...
    casa_core.config.ConfigError: mine.yaml: simulation.participants: must be >= 1, got 0
    """
    config = _plain(data)
    _raise(source, _problems(config, partial=False))
    _raise(source, _consistency(config))
    return config


def merge(base: dict, overlay: Mapping) -> dict:
    """Merge ``overlay`` into ``base`` in place: nested mappings key by key; returns ``base``.

    The same rule as Snakemake's for ``--configfile`` and ``--config``.

    Examples
    --------
    >>> merge({"a": {"b": 1, "c": 2}, "d": 3}, {"a": {"c": 5}, "d": {"e": 6}})
    {'a': {'b': 1, 'c': 5}, 'd': {'e': 6}}
    """
    for key, value in overlay.items():
        if isinstance(value, Mapping) and isinstance(base.get(key), dict):
            merge(base[key], value)
        else:
            base[key] = copy.deepcopy(dict(value) if isinstance(value, Mapping) else value)
    return base


def config_text(config: Mapping) -> str:
    """The config as YAML text, keys sorted: the same config always gives the same bytes."""
    return yaml.safe_dump(_plain(config), sort_keys=True)


def config_digest(path: Path | str) -> str:
    """The first :data:`DIGEST_LENGTH` hex digits of the sha256 of a config file's text.

    The file is the effective config the workflow writes (``data/interim/config.yaml``,
    :func:`config_text`, less :data:`TARGET_KEYS`), so the same configuration always has
    the same digest, and any changed key, default or ``--config`` override another.

    Raises
    ------
    OSError
        If the file cannot be read.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "config.yaml"
    >>> _ = path.write_text(config_text({"simulation": {"seed": 2021}}))
    >>> config_digest(path) == hashlib.sha256(b"simulation:\\n  seed: 2021\\n").hexdigest()[:12]
    True
    """
    text = Path(path).read_text(encoding="utf-8")
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:DIGEST_LENGTH]


@dataclass(frozen=True)
class Provenance:
    """Which configuration built an output: the config files layered and the digest.

    ``files`` are named as the workflow gives them (relative to the repository, as its
    ``config_layers()`` shows them), so that an output names no absolute path and stays
    the same bytes between two runs of one configuration.

    Examples
    --------
    >>> built = Provenance(("config/config.yaml", "config/ci.yaml"), "1a2b3c4d5e6f")
    >>> built.line()
    'Built from config/config.yaml + config/ci.yaml (effective config sha256 1a2b3c4d5e6f)'
    >>> built.label
    'config/config.yaml + config/ci.yaml (effective config sha256 1a2b3c4d5e6f)'
    """

    files: tuple[str, ...]
    digest: str

    @classmethod
    def of(cls, files: Sequence[str], effective: Path | str) -> Provenance:
        """The config files as given and the digest of the effective config
        (:func:`config_digest`)."""
        return cls(tuple(map(str, files)), config_digest(effective))

    @property
    def label(self) -> str:
        """The config files in the order they are merged, joined by ``+``, and the digest:
        a table's cell (text, never read back as a number, as a bare digest of digits
        and an ``e`` would be)."""
        return f"{' + '.join(self.files)} (effective config sha256 {self.digest})"

    def line(self) -> str:
        """The sentence an output opens or ends with, without its full stop."""
        return f"Built from {self.label}"


def _read(path: Path) -> dict:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"cannot read the config {path}: {error}") from None
    except yaml.YAMLError as error:
        raise ConfigError(f"{path}: not valid YAML: {error}") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: must be a mapping of keys, got {type(data).__name__}")
    return data


def _plain(data: Any) -> Any:
    """Plain dicts, lists, strings and numbers (Snakemake hands over its own mapping types)."""
    return json.loads(json.dumps(data, default=dict))


def _coerce(value: Any, node: dict) -> Any:
    """Command-line strings converted to the type the schema wants there, where they parse."""
    if isinstance(value, dict):
        properties = node.get("properties", {})
        others = node.get("additionalProperties")
        others = others if isinstance(others, dict) else None
        return {
            k: _coerce(v, properties.get(k, others)) if k in properties or others else v
            for k, v in value.items()
        }
    if isinstance(value, list):  # --config 'power={sizes: [10, 12]}' gives ['10', '12']
        items = node.get("items")
        return [_coerce(v, items) for v in value] if isinstance(items, dict) else value
    if not isinstance(value, str):
        return value
    kind = node.get("type")
    if kind == "boolean" and value.lower() in ("true", "false"):
        return value.lower() == "true"
    if kind in ("integer", "number") and re.fullmatch(r"[+-]?\d+", value):
        return int(value)  # as YAML reads 3: an int, which the schema's numbers admit
    if kind == "number":
        try:
            number = float(value)
        except ValueError:
            return value
        return number if math.isfinite(number) else value
    return value


@cache
def _validator(partial: bool) -> jsonschema.protocols.Validator:
    """A validator that fills in defaults; ``partial`` (an overlay) skips ``required``."""
    import jsonschema  # imported here: every ``casa`` command imports this module

    base = jsonschema.Draft202012Validator
    check_properties = base.VALIDATORS["properties"]

    def properties(validator, props, instance, node):
        if not partial and validator.is_type(instance, "object"):
            for name, sub in props.items():
                if "default" in sub and name not in instance:
                    instance[name] = copy.deepcopy(sub["default"])
        yield from check_properties(validator, props, instance, node)

    rules = {"properties": properties}
    if partial:
        rules["required"] = lambda *args: iter(())
    return jsonschema.validators.extend(base, rules)(schema())


def _problems(config: Any, *, partial: bool) -> list[str]:
    """``key: rule`` for every problem of ``config``, in the order of the keys."""
    errors = sorted(_validator(partial).iter_errors(config), key=lambda e: list(map(str, e.path)))
    # dict.fromkeys: one missing key is reported once, not once per missing sibling.
    return list(dict.fromkeys(problem for error in errors for problem in _describe(error)))


def _describe(error: jsonschema.ValidationError) -> Iterator[str]:
    key = ".".join(str(part) for part in error.absolute_path)
    prefix = f"{key}." if key else ""
    # Any: the stubs allow a bool schema and unset values, which the errors of a
    # validation never carry.
    rule = error.validator
    node: Any = error.schema
    value: Any = error.instance
    expected: Any = error.validator_value
    if rule == "additionalProperties":
        allowed = list(node.get("properties", {}))
        for name in (name for name in value if name not in allowed):
            close = difflib.get_close_matches(name, allowed, n=1)
            hint = f"; did you mean {close[0]}?" if close else ""
            yield f"{prefix}{name}: unknown key{hint} (allowed: {', '.join(allowed)})"
    elif rule == "required":
        for name in (name for name in expected if name not in value):
            yield f"{prefix}{name}: missing (required)"
    elif rule == "type":
        names = {"object": "a mapping", "array": "a list", "integer": "an integer", "null": "null"}
        kinds = expected
        kinds = kinds if isinstance(kinds, list) else [kinds]  # a type list: any of them
        kind = " or ".join(names.get(k, f"a {k}") for k in kinds)
        yield f"{key}: must be {kind}, got {value!r}"
    elif rule == "enum":
        choices = ", ".join(map(str, expected))
        yield f"{key}: must be one of {choices}, got {value!r}"
    elif rule in _BOUNDS:
        yield f"{key}: must be {_BOUNDS[rule]} {expected}, got {value!r}"
    elif rule in ("minItems", "minLength"):
        yield f"{key}: must not be empty"
    else:
        yield f"{key}: {error.message}"


_BOUNDS = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}


def _consistency(config: dict) -> list[str]:
    """Rules across keys that the schema cannot state."""
    keys = config["simulation"]["population"]["max_keys"]
    where = "simulation.population.max_keys.p"
    if len(keys["p"]) != len(keys["values"]):
        return [f"{where}: must have as many entries as values ({len(keys['values'])})"]
    if abs(sum(keys["p"]) - 1) > 1e-8:
        return [f"{where}: must sum to 1, got {sum(keys['p'])!r}"]
    # Each modelling variant's overlay, checked against this schema.
    return variant_problems(config) + power_problems(config)


def variant_problems(config: Mapping) -> list[str]:
    """``key: rule`` for every problem of a validated config's ``robustness`` block.

    Each overlay is checked against the config's schema (an unknown preset is named as
    ``robustness.variants.NAME.inference.preset``); the default variant must exist and
    overlay nothing; every name in ``robustness.run`` must be a variant.

    Examples
    --------
    >>> block = {"variants": {"default": {}, "bad": {"inference": {"preset": "mine"}}}}
    >>> variant_problems({"robustness": block | {"run": ["default", "other"]}})
    ... # doctest: +NORMALIZE_WHITESPACE
    ["robustness.variants.bad.inference.preset: must be one of casa, original, paper,
      got 'mine'", 'robustness.run: other is not a variant (variants: default, bad)']
    """
    block = config.get("robustness") or {}
    variants = block.get("variants") or {}
    problems = []
    for name, overlay in variants.items():
        where = f"robustness.variants.{name}"
        problems += [f"{where}.{problem}" for problem in _problems(overlay, partial=True)]
        if name == DEFAULT_VARIANT and overlay:
            problems.append(
                f"{where}: must overlay nothing (it is the config's own settings); "
                "give a different choice another name"
            )
    if DEFAULT_VARIANT not in variants:
        problems.append(f"robustness.variants: must contain {DEFAULT_VARIANT!r}, the config itself")
    for name in block.get("run") or []:
        if name not in variants:
            known = ", ".join(variants)
            problems.append(f"robustness.run: {name} is not a variant (variants: {known})")
    return problems


def power_problems(config: Mapping) -> list[str]:
    """``key: rule`` for every ``power.variants`` name that is not a robustness variant.

    Examples
    --------
    >>> power_problems({"power": {"variants": ["x"]}, "robustness": {"variants": {"default": {}}}})
    ['power.variants: x is not a variant of robustness.variants (variants: default)']
    """
    known = (config.get("robustness") or {}).get("variants") or {}
    names = (config.get("power") or {}).get("variants") or []
    return [
        f"power.variants: {name} is not a variant of robustness.variants "
        f"(variants: {', '.join(known)})"
        for name in names
        if name not in known
    ]


def _raise(source: str, problems: list[str]) -> None:
    if problems:
        raise ConfigError("\n".join(f"{source}: {problem}" for problem in problems))
