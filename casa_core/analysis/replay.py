"""Replay: offline inference over a recorded casa-trial/1 log.

A replay feeds the logged states and keys to an :class:`~casa_core.assist.assistant.Assistant`
tick by tick, as the closed loop that recorded the trial did: every ``dt`` (0.5 s) the
assistant updates its inference with the logged state, and every control tick it is
told the user's action (from the logged keys) and the authority alpha the arm actually
applied (the logged ``alpha``; 1 when the log has none: the arm was unassisted). So
under commanded evidence the robot's share removed from the evidence is the share the
arm really had.

With the trial's own settings (its ``meta["inference"]``, the arbitration of its
method, its intents and scene) a replay of a simulated trial reproduces the logged
beta, belief and alpha exactly. Any setting can be changed: that is a counterfactual.
A trial recorded under NA replayed with arbitration ``"confidence"`` shows what CASA's
confidence and alpha would have been *on that trajectory*; under CASA the robot would
have moved too, so the trajectory itself, and with it everything after the first
assisted step, would have differed. ``docs/replay.md`` describes the outputs.

Examples
--------
>>> import pandas as pd
>>> from casa_core.scene import load_scene
>>> meta = {"participant": "p01", "task": "known_goal", "method": "NA",
...         "phase": "no_misspecification", "source": "human"}
>>> t = [round(0.05 * k, 6) for k in range(21)]
>>> frame = pd.DataFrame({"t": t, "x": [0.45 + 0.0025 * k for k in range(21)],
...                       "y": -0.22, "z": 0.38, "rot": 0.0, "keys": "x+"})
>>> replayed = replay_trial(meta, frame, load_scene())
>>> replayed[["t", "intent", "theta_star", "alpha"]]
     t  intent theta_star  alpha
0  0.5   green      green    1.0
1  0.5  purple      green    1.0
2  1.0   green      green    1.0
3  1.0  purple      green    1.0
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from casa_core.analysis.original_numerics import original_rows
from casa_core.analysis.replay_settings import ReplayError, trial_point, trial_settings
from casa_core.assist.assistant import Assistant
from casa_core.assist.intents import GoalIntent, Intent
from casa_core.assist.presets import DEFECTS, Preset
from casa_core.defaults import DT, EPSILON, HORIZON
from casa_core.io.contract import INTENT_PREFIXES, INTENT_SUFFIX, JOINTS
from casa_core.robot.keys import keys_to_action, parse_keys
from casa_core.robot.kinematics import point_position
from casa_core.scene import KNOWN_GOALS, Scene, SceneError
from casa_core.vocabulary import DEFECTS_PRESET

#: The columns of a replay table, in order.
COLUMNS = ("t", "intent", "suboptimality", "beta", "belief", "theta_star", "alpha", "misspecified")


def _participant_key(name: str) -> str:
    """A participant's name with numbers unpadded: folder ``p1`` holds participant ``p01``."""
    return re.sub(r"\d+", lambda match: str(int(match.group())), str(name)).casefold()


def library_files(library: Path | str | None, participant: str | None = None) -> list[Path]:
    """The casa-intent files a replay of ``participant``'s trials may use from ``library``.

    ``library`` is one ``*.intent.json`` file or a folder of them. If the folder has a
    subfolder named after the participant (``p1`` or ``p01`` for ``p01``), only the
    files below that subfolder are used; otherwise every file below the folder.

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> for part in ("p1/unknown_goal", "p2/unknown_goal"):
    ...     (root / part).mkdir(parents=True)
    ...     _ = (root / part / "learned_red.intent.json").write_text("{}")
    >>> [p.relative_to(root).as_posix() for p in library_files(root, "p01")]
    ['p1/unknown_goal/learned_red.intent.json']
    >>> len(library_files(root)), library_files(None)
    (2, [])
    """
    if library is None:
        return []
    library = Path(library)
    if library.is_file():
        return [library]
    if participant is not None and library.is_dir():
        key = _participant_key(participant)
        own = [
            p for p in sorted(library.iterdir()) if p.is_dir() and _participant_key(p.name) == key
        ]
        if own:
            return sorted(path for folder in own for path in folder.rglob(f"*{INTENT_SUFFIX}"))
    return sorted(library.rglob(f"*{INTENT_SUFFIX}"))


def kept_intent_files(trial: Path | str, root: Path | str) -> list[Path]:
    """The learned intents a dataset keeps for a trial: its participant's library.

    The casa-intent files below the nearest folder that has any, from the trial's own
    folder up to its top folder below ``root`` (the dataset folder; ``root`` itself for
    a trial at the top): a participant's intents live in the participant's folder,
    wherever below it (``casa session`` keeps them in ``.session/library/``, the
    simulated study in ``intents/<task>/``), and never serve another participant.

    Examples
    --------
    >>> import tempfile
    >>> root = Path(tempfile.mkdtemp())
    >>> for part in ("p1/before", "p1/.session/library", "p2/before"):
    ...     (root / part).mkdir(parents=True)
    >>> _ = (root / "p1/.session/library/learned_red.intent.json").write_text("{}")
    >>> [p.relative_to(root).as_posix() for p in kept_intent_files(root / "p1/before/t.csv", root)]
    ['p1/.session/library/learned_red.intent.json']
    >>> kept_intent_files(root / "p2/before/t.csv", root)
    []
    """
    root = Path(root)
    folder = Path(trial).parent
    while True:
        found = sorted(folder.rglob(f"*{INTENT_SUFFIX}"))
        if found or folder == root or folder.parent == root or root not in folder.parents:
            return found
        folder = folder.parent


def resolve_intents(
    names: Sequence[str],
    scene: Scene,
    chosen: Preset,
    learned: Sequence = (),
    *,
    point: str | None = None,
) -> list[Intent]:
    """The intents called ``names``: goals of the scene, else learned intents by name.

    A goal's cost is the preset's, its position the scene's at ``point`` (default the
    scene's own point; a scene that does not give it there is a ReplayError).
    ``learned`` holds casa-intent files (the file of intent NAME is ``NAME.intent.json``,
    read only when NAME is needed, a fresh intent each time) or intents already built.

    Raises
    ------
    ReplayError
        Naming an intent that is neither a goal nor in ``learned``, or given twice.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> from casa_core.assist.presets import preset
    >>> [i.name for i in resolve_intents(["purple", "green"], load_scene(), preset())]
    ['purple', 'green']
    >>> try:
    ...     resolve_intents(["learned_red"], load_scene(), preset())
    ... except ReplayError as error:
    ...     print(error)  # doctest: +NORMALIZE_WHITESPACE
    intent 'learned_red' is not a goal of the scene (green, purple, red)
    nor a learned intent given (none)
    """
    built = {item.name: item for item in learned if isinstance(item, Intent)}
    files: dict[str, list[Path]] = {}
    for item in learned:
        if not isinstance(item, Intent):
            path = Path(item)
            files.setdefault(path.name.removesuffix(INTENT_SUFFIX), []).append(path)
    intents: list[Intent] = []
    for name in names:
        if name in scene.goals:
            position = _goal_at(scene, name, point)
            intents.append(GoalIntent(name, position, **chosen.goal_options()))
        elif name in built:
            intents.append(built[name])
        elif len(files.get(name, ())) == 1:
            intents.append(_load_learned(files[name][0], name))
        elif name in files:
            found = ", ".join(str(p) for p in files[name])
            raise ReplayError(f"intent {name!r} is in several files ({found}); give one")
        else:
            known = ", ".join(sorted({*built, *files})) or "none"
            raise ReplayError(
                f"intent {name!r} is not a goal of the scene ({', '.join(scene.goals)}) "
                f"nor a learned intent given ({known})"
            )
    return intents


def _load_learned(path: Path, name: str) -> Intent:
    from casa_core.learning.library import load_intent  # torch loads only when a trial needs it

    entry = load_intent(path)
    if entry.intent.name != name:
        raise ReplayError(f"{path} holds intent {entry.intent.name!r}, not {name!r}")
    return entry.intent


def replay_trial(
    meta: dict,
    frame: pd.DataFrame,
    scene: Scene,
    *,
    preset: str | None = None,
    evidence: str | None = None,
    arbitration: str | None = None,
    point: str | None = None,
    lam: float | None = None,
    epsilon: float = EPSILON,
    intents: Sequence[str] | None = None,
    learned: Sequence = (),
) -> pd.DataFrame:
    """Redo the inference of one trial over its logged states and keys.

    Parameters
    ----------
    meta, frame : dict, pandas.DataFrame
        The trial as :func:`casa_core.io.read_trial` returns it.
    scene : Scene
        Its goals and keyboard (speeds, control tick).
    preset, evidence, arbitration : str, optional
        Default: the trial's own (:func:`trial_settings`). The preset
        :data:`~casa_core.vocabulary.DEFECTS_PRESET` redoes the original's numerics with
        their defects (:mod:`casa_core.analysis.original_numerics`) over the scene's goals.
    point : {"tool", "link7"}, optional
        Where the arm is measured (:func:`trial_point`), with the scene's goals at that
        point: the log's positions where they were measured there (the scene's
        ``point``), else that point of the logged joint angles.
    lam : float, optional
        Rate of the prior on beta; default the preset's.
    epsilon : float, default EPSILON
        Misspecification threshold.
    intents : sequence of str, optional
        The intents' names; default ``meta["intents"]``, else the known goals green and
        purple. Resolved by :func:`resolve_intents`.
    learned : sequence of path or Intent
        Learned intents available by name (casa-intent files).

    Returns
    -------
    pandas.DataFrame
        :data:`COLUMNS`: one row per inference step and intent, in step order, then the
        intents' order; ``t`` is the log's time of the step; ``alpha``, ``theta_star``
        and ``misspecified`` repeat over a step's rows.

    Raises
    ------
    ReplayError
        On settings that do not fit (an unknown intent, a tick that does not divide
        ``dt``); :class:`ValueError` from the assistant on a bad ``lam`` or ``epsilon``.
    """
    chosen, arbitration = trial_settings(
        meta, preset=preset, evidence=evidence, arbitration=arbitration
    )
    point = trial_point(meta, point)
    names = intents if intents is not None else meta.get("intents") or list(KNOWN_GOALS)
    teleop = scene.teleop
    per_step = int(round(DT / teleop.dt))
    if per_step < 1 or abs(per_step * teleop.dt - DT) > 1e-9:
        raise ReplayError(f"scene: teleop.dt = {teleop.dt} s does not divide {DT} s")
    t = frame["t"].to_numpy(dtype=float)
    states = _measured_states(frame, point, scene.point)
    # The tick of each row (t = tick * dt); inference runs at each multiple of per_step.
    ticks = np.rint(t / teleop.dt).astype(int)
    if chosen is DEFECTS:
        if lam is not None:
            raise ReplayError(f"preset {DEFECTS_PRESET} has the original's lambda; give no lam")
        chosen_goals = _defect_goals(scene, list(names), point)
        return _replay_defects(
            t, ticks, per_step, states, chosen_goals, list(names), arbitration, epsilon
        )
    built = resolve_intents(list(names), scene, chosen, learned, point=point)
    options = chosen.assistant_options()
    if lam is not None:
        options["lam"] = lam
    assistant = Assistant(
        built,
        arbitration=arbitration,
        epsilon=epsilon,
        dt=DT,
        speed=teleop.speed,
        rot_speed=teleop.rot_speed,
        tick=teleop.dt,
        **options,
    )
    keys = frame["keys"].fillna("").astype(str).tolist()
    applied = frame["alpha"].to_numpy(dtype=float) if "alpha" in frame else np.ones(len(t))
    rows: list[dict] = []
    assistant.reset(states[0])
    done: set[int] = set()
    for i in range(len(t)):
        tick = int(ticks[i])
        if i > 0 and tick > 0 and tick % per_step == 0 and tick not in done:
            done.add(tick)
            step = assistant.update(states[i])
            for name in assistant.names:
                rows.append(
                    {
                        "t": float(t[i]),
                        "intent": name,
                        "suboptimality": step.suboptimality[name],
                        "beta": step.beta[name],
                        "belief": step.belief[name],
                        "theta_star": step.intent,
                        "alpha": step.alpha,
                        "misspecified": step.misspecified,
                    }
                )
        if i + 1 < len(t):  # the closed loop acts after every row but the last
            action = keys_to_action(parse_keys(keys[i]), teleop.speed, teleop.rot_speed)
            elapsed = (tick % per_step) * teleop.dt
            assistant.act(states[i], action, elapsed_in_step=elapsed, alpha=applied[i])
    return pd.DataFrame(rows, columns=list(COLUMNS))


def _measured_states(frame: pd.DataFrame, point: str, logged: str) -> np.ndarray:
    """The states ``[x, y, z, rot]`` at ``point``: the log's where it was ``logged`` there
    (the scene's point), else ``point`` of its joint angles."""
    states = frame[["x", "y", "z", "rot"]].to_numpy(dtype=float, copy=True)
    if point != logged:
        missing = [name for name in JOINTS if name not in frame.columns]
        if missing:
            raise ReplayError(f"measured at {point}: the log has no joint angles ({missing[0]})")
        q = frame[list(JOINTS)].to_numpy(dtype=float)
        states[:, :3] = [point_position(row, point) for row in q]
    return states


def _defect_goals(scene: Scene, names: list[str], point: str) -> np.ndarray:
    """The positions of the goals ``names`` at ``point``, for :data:`DEFECTS_PRESET`."""
    unknown = [name for name in names if name not in scene.goals]
    if unknown:
        raise ReplayError(
            f"preset {DEFECTS_PRESET} redoes goals only: {unknown[0]!r} is not a goal of the "
            "scene (the original's learned costs are not in its sessions)"
        )
    return np.array([_goal_at(scene, name, point) for name in names])


def _goal_at(scene: Scene, name: str, point: str | None) -> np.ndarray:
    """Goal ``name``'s position at ``point``; ReplayError when the scene does not give it."""
    try:
        return scene.goal(name, point)
    except SceneError as error:
        raise ReplayError(f"measured at {point}: {error}") from None


def _replay_defects(t, ticks, per_step, states, goals, names, arbitration, epsilon):
    """The original's numerics, defects included, at each inference tick of the log."""
    # The inference ticks, at most the horizon's worth: the original's waypoints after the start.
    first = {int(tick): i for i, tick in reversed(list(enumerate(ticks))) if i > 0}
    steps = [i for tick, i in sorted(first.items()) if tick > 0 and tick % per_step == 0]
    steps = steps[: int(round(HORIZON / DT))]
    index = [0, *steps]
    rows = original_rows(t[index], states[index, :3], goals, names, arbitration, epsilon)
    return pd.DataFrame(rows, columns=list(COLUMNS))


def replay_differences(frame: pd.DataFrame, replayed: pd.DataFrame) -> dict:
    """The largest absolute difference between a log's inference and its replay.

    Compares the log's ``beta:NAME``, ``belief:NAME`` and ``alpha`` at the replay's
    steps (matched on ``t``) with the replay, over the intents both have.

    Returns
    -------
    dict
        ``{"beta": float, "belief": float, "alpha": float}``; NaN where the log has no
        such column (or no intent in common) or the replay has no step.

    Examples
    --------
    >>> log = pd.DataFrame({"t": [0.0, 0.5], "alpha": [1.0, 0.75], "beta:green": [0.0, 2.0]})
    >>> replayed = pd.DataFrame({"t": [0.5], "intent": ["green"], "beta": [2.5],
    ...                          "belief": [1.0], "alpha": [0.5]})
    >>> replay_differences(log, replayed)
    {'beta': 0.5, 'belief': nan, 'alpha': 0.25}
    """
    result = dict.fromkeys(("beta", "belief", "alpha"), math.nan)
    if replayed.empty:
        return result
    logged = frame.drop_duplicates("t").set_index("t")
    for what in INTENT_PREFIXES:
        gaps = []
        for name, rows in replayed.groupby("intent", sort=False):
            column = f"{what}:{name}"
            if column in logged.columns:
                values = logged[column].reindex(rows["t"].to_numpy()).to_numpy(dtype=float)
                gaps.append(np.abs(values - rows[what].to_numpy(dtype=float)))
        if gaps:
            result[what] = float(np.max(np.concatenate(gaps)))
    if "alpha" in logged.columns:
        steps = replayed.drop_duplicates("t")
        values = logged["alpha"].reindex(steps["t"].to_numpy()).to_numpy(dtype=float)
        result["alpha"] = float(np.max(np.abs(values - steps["alpha"].to_numpy(dtype=float))))
    return result
