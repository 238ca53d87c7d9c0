"""Modelling variants of the simulated study: the config's ``robustness`` block.

The paper leaves modelling choices open (the inference preset, the evidence, the
operator model). Each variant of ``robustness.variants`` is an overlay of those keys
only (:data:`OVERLAY_KEYS`) on the study's config; :func:`variant_config` builds the
whole config one variant's jobs read. Every variant keeps the study's seeds, scene and
population, so that variants differ in the overlaid choices alone. The variant named
:data:`DEFAULT_VARIANT` overlays nothing: it is the study's own settings.

Examples
--------
>>> from casa_core.config import DEFAULT_CONFIG, load_config
>>> config = load_config(DEFAULT_CONFIG)
>>> variant_names(config)
['default', 'original', 'paper', 'executed', 'lookahead']
>>> built = variant_config(config, "lookahead")
>>> built["simulation"]["operator"], built["inference"]["preset"]
('lookahead', 'casa')
>>> settings_text(variant_config(config, "original"))
'preset original, evidence executed, operator predictive'
"""

from __future__ import annotations

import copy
from collections.abc import Mapping

from casa_core.assist.presets import preset
from casa_core.config import merge, validate_config

#: The keys an overlay may set: section -> its keys (None: every key of the section).
OVERLAY_KEYS: dict[str, tuple[str, ...] | None] = {
    "inference": None,
    "simulation": ("operator",),
}
#: The config blocks of the targets that run variants, left out of a variant's config.
RUNNING_BLOCKS = ("robustness", "power")


def variant_names(config: Mapping) -> list[str]:
    """The variants the ``robustness`` target runs: ``robustness.run``, else every one.

    Examples
    --------
    >>> variant_names({"robustness": {"variants": {"default": {}, "x": {}}, "run": ["x"]}})
    ['x']
    """
    block = config["robustness"]
    return list(block["run"] if block.get("run") else block["variants"])


def variant_config(config: Mapping, name: str, *, participants: int | None = None) -> dict:
    """The whole config of variant ``name``: its overlay on ``config``, validated.

    ``simulation.participants`` becomes ``participants``, by default
    ``robustness.participants``; the ``robustness`` and ``power`` blocks (the targets
    that run variants) are left out, so that a variant's config changes only with what
    its jobs read.

    Raises
    ------
    KeyError
        If ``name`` is not a variant.
    casa_core.config.ConfigError
        If the result is not a valid config.

    Examples
    --------
    >>> from casa_core.config import DEFAULT_CONFIG, load_config
    >>> config = load_config(DEFAULT_CONFIG)
    >>> built = variant_config(config, "paper")
    >>> built["inference"]["preset"], built["simulation"]["participants"], "robustness" in built
    ('paper', 11, False)
    >>> variant_config(config, "paper", participants=24)["simulation"]["participants"]
    24
    """
    variants = config["robustness"]["variants"]
    if name not in variants:
        known = ", ".join(variants)
        raise KeyError(f"robustness.variants: no variant {name!r} (variants: {known})")
    built = copy.deepcopy({k: v for k, v in config.items() if k not in RUNNING_BLOCKS})
    merge(built, variants[name])
    built["simulation"]["participants"] = participants or config["robustness"]["participants"]
    validated = validate_config(built, source=f"robustness variant {name}")
    for block in RUNNING_BLOCKS:
        validated.pop(block, None)
    return validated


def settings_text(config: Mapping) -> str:
    """The modelling choices of a config in words: preset, evidence (resolved), operator.

    Examples
    --------
    >>> settings_text({"inference": {"preset": "casa", "evidence": None},
    ...                "simulation": {"operator": "predictive"}})
    'preset casa, evidence commanded, operator predictive'
    """
    inference = config["inference"]
    evidence = preset(inference["preset"], evidence=inference.get("evidence")).evidence
    operator = config["simulation"]["operator"]
    return f"preset {inference['preset']}, evidence {evidence}, operator {operator}"
