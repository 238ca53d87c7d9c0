"""The intents a replay uses: goals of the scene, learned intents by name, and where the
files of a participant's learned intents are found.

:func:`resolve_intents` builds them for :func:`casa_core.analysis.replay.replay_trial`;
:func:`library_files` and :func:`kept_intent_files` say which casa-intent files serve a
trial (``docs/replay.md``, "Learned intents").
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from casa_core.analysis.replay_settings import ReplayError
from casa_core.assist.intents import GoalIntent, Intent
from casa_core.assist.presets import Preset
from casa_core.io.contract import INTENT_SUFFIX
from casa_core.scene import Scene, SceneError


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
            position = goal_position(scene, name, point)
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


def goal_position(scene: Scene, name: str, point: str | None) -> np.ndarray:
    """Goal ``name``'s position at ``point``; ReplayError when the scene does not give it."""
    try:
        return scene.goal(name, point)
    except SceneError as error:
        raise ReplayError(f"measured at {point}: {error}") from None
