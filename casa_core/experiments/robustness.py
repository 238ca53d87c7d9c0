"""Modelling variants of the simulated study: the config's ``robustness`` block.

The paper leaves modelling choices open (the inference preset, the evidence, the
operator model), and the study can run on two setups (the scene and its teleoperation:
ours, or the authors' layout driven the authors' way). Each variant of
``robustness.variants`` is an overlay of those keys only (:data:`OVERLAY_KEYS`) on the
study's config; :func:`variant_config` builds the whole config one variant's jobs read.
Every variant keeps the study's seeds and population, so that variants differ in the
overlaid choices alone. The variant named :data:`DEFAULT_VARIANT` overlays nothing: it is
the study's own settings.

Examples
--------
>>> from casa_core.config import DEFAULT_CONFIG, load_config
>>> config = load_config(DEFAULT_CONFIG)
>>> variant_names(config)
['default', 'original', 'paper', 'executed', 'lookahead', 'authors', 'authors_via_green']
>>> built = variant_config(config, "lookahead")
>>> built["simulation"]["operator"], built["inference"]["preset"]
('lookahead', 'casa')
>>> settings_text(variant_config(config, "original"))
'scene scene.yaml (teleop held), preset original, evidence executed, operator predictive'
>>> setup_text(variant_config(config, "authors"))
'scene scene-original.yaml (teleop original)'
"""

from __future__ import annotations

import copy
from collections.abc import Mapping
from pathlib import PurePath

from casa_core.assist.presets import preset
from casa_core.config import merge, validate_config

#: The keys an overlay may set: section -> its keys (None: every key of the section, or
#: the whole value of a key that is not a section, such as ``scene``).
OVERLAY_KEYS: dict[str, tuple[str, ...] | None] = {
    "scene": None,
    "teleop": None,
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
    """The modelling choices of a config in words: preset, evidence (resolved), operator;
    first its setup (:func:`setup_text`) where it names one.

    Examples
    --------
    >>> settings_text({"inference": {"preset": "casa", "evidence": None},
    ...                "simulation": {"operator": "predictive"}})
    'preset casa, evidence commanded, operator predictive'
    """
    inference = config["inference"]
    evidence = preset(inference["preset"], evidence=inference.get("evidence")).evidence
    operator = config["simulation"]["operator"]
    words = f"preset {inference['preset']}, evidence {evidence}, operator {operator}"
    setup = setup_text(config)
    return f"{setup}, {words}" if setup else words


def setup_text(config: Mapping) -> str:
    """The setup a config names, in words: its scene file's name and, where the config
    sets one, its teleoperation mode; empty when it names neither.

    Examples
    --------
    >>> setup_text({"scene": "config/scene.yaml", "teleop": {"mode": "held"}})
    'scene scene.yaml (teleop held)'
    """
    scene = config.get("scene")
    mode = (config.get("teleop") or {}).get("mode")
    if scene is None and mode is None:
        return ""
    words = f"scene {PurePath(scene).name}" if scene else "the package's scene"
    if mode is None and scene:
        mode = _scene_mode(scene)
    return f"{words} (teleop {mode})" if mode else words


def _scene_mode(path) -> str | None:
    """The teleoperation mode a scene file declares; None where it cannot be read."""
    from casa_core.scene import SceneError, load_scene

    try:
        return load_scene(path).teleop.mode
    except SceneError:
        return None
