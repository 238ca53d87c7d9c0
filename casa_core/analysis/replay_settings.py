"""The settings a replay uses: preset, evidence, arbitration, the point it measures and the
path its steps read.

Each is the trial's own (its metadata) unless given; :mod:`casa_core.analysis.replay`
redoes the inference with them.
"""

from __future__ import annotations

from typing import Any

from casa_core.assist.assistant import ARBITRATIONS
from casa_core.assist.presets import DEFAULT_PRESET, DEFECTS, Preset
from casa_core.assist.presets import preset as named_preset
from casa_core.vocabulary import DEFECTS_PRESET, METHOD_ARBITRATION, POINTS, REPLAY_PATHS


class ReplayError(ValueError):
    """A trial that cannot be replayed as asked; the message names the trial and the reason."""


def trial_settings(
    meta: dict,
    *,
    preset: str | None = None,
    evidence: str | None = None,
    arbitration: str | None = None,
) -> tuple[Preset, str]:
    """The preset (evidence applied) and arbitration a replay of the trial uses.

    Each is the trial's own unless given: the preset and evidence of
    ``meta["inference"]`` (absent: :data:`~casa_core.assist.presets.DEFAULT_PRESET` and its
    evidence), the arbitration of ``meta["method"]`` (:data:`METHOD_ARBITRATION`).

    Examples
    --------
    >>> meta = {"method": "PBA", "inference": {"preset": "original", "evidence": "executed"}}
    >>> chosen, arbitration = trial_settings(meta)
    >>> chosen.name, chosen.evidence, arbitration
    ('original', 'executed', 'distance')
    >>> trial_settings(meta, preset="casa", arbitration="confidence")[0].evidence
    'commanded'
    """
    recorded: Any = meta.get("inference") if isinstance(meta.get("inference"), dict) else {}
    if preset is None:
        preset = recorded.get("preset", DEFAULT_PRESET)
        # The trial's evidence goes with its own preset; another preset brings its own.
        evidence = recorded.get("evidence") if evidence is None else evidence
    if preset == DEFECTS_PRESET:
        if evidence not in (None, DEFECTS.evidence):
            raise ReplayError(f"preset {DEFECTS_PRESET} observes the executed path, not {evidence}")
        chosen = DEFECTS
    else:
        chosen = named_preset(preset, evidence=evidence)
    if arbitration is None:
        method = meta.get("method")
        if method not in METHOD_ARBITRATION:
            raise ReplayError(f"method {method!r} has no arbitration; give one")
        arbitration = METHOD_ARBITRATION[method]
    if arbitration not in ARBITRATIONS:
        raise ReplayError(f"arbitration must be one of {', '.join(ARBITRATIONS)}: {arbitration!r}")
    return chosen, arbitration


def trial_point(meta: dict, point: str | None = None) -> str:
    """Where a replay of the trial measures the arm: ``point`` if given, else the trial's
    own (``meta["inference"]["point"]``), else ``"tool"``.

    The point says where the log's numbers were measured, so it is kept under another
    preset unless given.

    Examples
    --------
    >>> trial_point({"inference": {"preset": "original", "point": "link7"}})
    'link7'
    >>> trial_point({}), trial_point({}, "link7")
    ('tool', 'link7')
    """
    recorded: Any = meta.get("inference") if isinstance(meta.get("inference"), dict) else {}
    point = recorded.get("point", POINTS[0]) if point is None else point
    if point not in POINTS:
        raise ReplayError(f"point must be one of {', '.join(POINTS)}: {point!r}")
    return point


def replay_path(meta: dict, chosen: Preset, path: str | None = None) -> str:
    """What a replay's steps read: ``"waypoints"`` or ``"ticks"``.

    ``"waypoints"``: the trial's recorded waypoints (``meta["inference_steps"]``, written
    by ``casa import original``), each step at its logged start over the waypoints it ran
    over; ``"ticks"``: the log's state every ``dt``. Default: the waypoints where the trial
    has them and the preset's evidence is the executed path (commanded evidence needs the
    keys of every tick), else the ticks.

    Examples
    --------
    >>> from casa_core.assist.presets import preset
    >>> meta = {"inference_steps": {"started": [0.5], "waypoint": [1],
    ...                             "waypoints": [[0.0] * 7, [0.1] * 7]}}
    >>> replay_path(meta, preset("original")), replay_path(meta, preset("casa"))
    ('waypoints', 'ticks')
    >>> replay_path({}, preset("original")), replay_path(meta, preset("original"), "ticks")
    ('ticks', 'ticks')
    """
    if path is not None and path not in REPLAY_PATHS:
        raise ReplayError(f"path must be one of {', '.join(REPLAY_PATHS)}: {path!r}")
    steps = meta.get("inference_steps")
    recorded = isinstance(steps, dict) and "waypoints" in steps
    if path == "waypoints":
        if not recorded:
            raise ReplayError("path waypoints: the trial has no recorded waypoints")
        if chosen.evidence != "executed":
            raise ReplayError(
                f"path waypoints: evidence {chosen.evidence} needs the user's keys of every "
                "tick; the waypoints are the executed path"
            )
    if path is None:
        path = "waypoints" if recorded and chosen.evidence == "executed" else "ticks"
    return path
