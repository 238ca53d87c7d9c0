"""Learning from recorded trials: demonstration logs in, an intent file in a library out."""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from pathlib import Path

from casa_core.io import find_files, load_meta, read_trial
from casa_core.io.contract import INTENT_SUFFIX
from casa_core.learning.config import IRLConfig
from casa_core.learning.library import intent_path, save_intent
from casa_core.learning.maxent import MaxEntIRL


def read_demonstrations(
    folder: Path | str,
    task: str | None = None,
    *,
    phase: str | None = "demonstration",
    logs: Mapping[Path, tuple] | None = None,
) -> tuple[list, list[dict]]:
    """The demonstrations in ``folder`` (the casa-trial/1 logs below it, sorted).

    Logs are read with :func:`casa_core.io.read_trial` (which validates them; a log whose
    metadata is valid and names another task or phase is skipped without reading its table);
    with ``task``, only that task's trials are kept; with ``phase`` (by default
    ``"demonstration"``), only the trials of that phase, so that a participant's
    folder can be given whole: its assisted trials, where the robot pulled the
    arm toward another intent, are not demonstrations. ``phase=None`` keeps
    every phase. The logs in ``logs`` (by the ``.json``'s path, as
    :func:`casa_core.io.write_trial` returns them) are not read again.

    Returns
    -------
    demos : list of numpy.ndarray
        Each ``(n, 5)`` of ``[t, x, y, z, rot]``.
    metas : list of dict
        Their metadata, in the same order.

    Raises
    ------
    ValueError
        If the folder has no trial (of that task and phase); :class:`casa_core.io.LogError`
        if a log breaks the contract.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise ValueError(f"{folder}: demonstrations folder not found")
    # A dataset keeps its learned intents beside the logs (*.intent.json): not trials.
    stems = [
        p.with_suffix("")
        for p in find_files(folder)
        if p.suffix == ".json" and not p.name.endswith(INTENT_SUFFIX)
    ]
    demos, metas, skipped, logs = [], [], set(), logs or {}
    for stem in stems:
        json_path = stem.with_suffix(".json")
        if json_path in logs:  # written and checked by write_trial
            meta, frame = logs[json_path]
        else:
            # A log whose valid metadata names another task or phase is skipped unread (its
            # table is the costly part); every log that is kept is read and validated whole.
            meta, problems = load_meta(json_path)
            valid = meta is not None and all(p.severity != "error" for p in problems)
            if meta is None or not valid or _wanted(meta, task, phase):
                meta, frame = read_trial(stem)
        if not _wanted(meta, task, phase):
            if task is None or meta.get("task") == task:
                skipped.add(meta.get("phase"))
            continue
        demos.append(frame[["t", "x", "y", "z", "rot"]].to_numpy(dtype=float))
        metas.append(meta)
    if not demos:
        which = f" of task {task!r}" if task else ""
        which += f" in phase {phase!r}" if phase else ""
        found = f" (found phases: {', '.join(sorted(skipped))})" if skipped else ""
        raise ValueError(
            f"{folder}: no trial log{which} found (casa-trial/1 .json + .csv pairs){found}"
        )
    return demos, metas


def _wanted(meta: dict, task: str | None, phase: str | None) -> bool:
    return (task is None or meta.get("task") == task) and (
        phase is None or meta.get("phase") == phase
    )


def learn_to_library(
    demos_folder: Path | str,
    name: str,
    *,
    library: Path | str,
    objects: Mapping,
    seed: int = 0,
    task: str | None = None,
    participant: str | None = None,
    config: IRLConfig | None = None,
    phase: str | None = "demonstration",
    progress: Callable[[int, int], None] | None = None,
    demonstrations: tuple[list, list[dict]] | None = None,
) -> tuple[Path, list[dict], float]:
    """Learn intent ``name`` from the logs in ``demos_folder`` and save it in ``library``.

    ``task`` and ``phase`` filter the logs (:func:`read_demonstrations`); the
    scene ``objects`` (name -> position) are the cost's features
    (:meth:`MaxEntIRL.fit`). The task and participant stored default to those of
    the logs when they all agree (else ""); ``progress`` is
    :class:`~casa_core.learning.maxent.MaxEntIRL`'s. ``demonstrations``, when given, is
    what :func:`read_demonstrations` returns for these logs, so they are not read again.
    Returns the file, the training history and the training time in seconds.
    """
    config = IRLConfig() if config is None else config
    intent_path(library, name)  # a bad name fails before training
    if demonstrations is None:
        demonstrations = read_demonstrations(demos_folder, task, phase=phase)
    demos, metas = demonstrations

    def agreed(key: str) -> str:
        values = {str(m.get(key, "")) for m in metas}
        return values.pop() if len(values) == 1 else ""

    began = time.perf_counter()
    learner = MaxEntIRL(name, config=config, seed=seed, progress=progress).fit(demos, objects)
    seconds = time.perf_counter() - began
    path = save_intent(
        library,
        learner.intent_,
        task=agreed("task") if task is None else task,
        participant=agreed("participant") if participant is None else participant,
        seed=seed,
        demos=demos,
        history=learner.history_,
        config=config,
    )
    return path, learner.history_, seconds
