"""The rules of casa-trial/1 for a trial's metadata (its ``.json``).

Each rule is a row of :data:`META_RULES`; :func:`check_meta` reports every problem of a
metadata object at once. The contract is ``docs/data-contracts.md``.

Examples
--------
>>> meta = {"schema": "casa-trial/1", "participant": "p01", "task": "known_goal",
...         "method": "CASA", "phase": "no_misspecification", "source": "robot"}
>>> [str(p) for p in check_meta(meta, "t.json")]
["t.json: key 'source': [enum] is 'robot', expected one of human, simulated"]
"""

from __future__ import annotations

import math
import unicodedata
from collections.abc import Callable

from casa_core.io.contract import (
    INFERENCE_STEPS_KEYS,
    INTENT_PREFIXES,
    JOINTS,
    META_ENUMS,
    META_OPTIONAL,
    META_REQUIRED,
    METHODS,
    PHASE_METHOD,
    PHASES,
    SCHEMA,
    TASK_PHASES,
    TASKS,
    TRIAL_FLAGS,
)
from casa_core.io.problems import Problem
from casa_core.vocabulary import EVIDENCE, POINTS, REPLAY_PRESETS

__all__ = ["META_RULES", "check_meta", "participant_id_problem"]

#: A metadata rule's check: (value of its key, whole metadata) -> what is wrong, or None.
MetaCheck = Callable[[object, dict], str | None]


def _schema(value, meta: dict) -> str | None:
    return None if value == SCHEMA else f"is {value!r}, expected {SCHEMA!r}"


def _non_empty_string(value, meta: dict) -> str | None:
    if isinstance(value, str) and value.strip():
        return None
    return f"is {value!r}, expected a non-empty string"


def participant_id_problem(value: str) -> str | None:
    """What makes a participant id unusable as a name (and later a path part), or None.

    An id has no ``/`` or ``\\``, is not ``.`` or ``..``, has no control characters and
    no leading or trailing white space.

    Examples
    --------
    >>> participant_id_problem("p01") is None, participant_id_problem("../x")
    (True, "is '../x', must not contain '/' or '\\\\'")
    """
    if "/" in value or "\\" in value:
        return f"is {value!r}, must not contain '/' or '\\'"
    if value in (".", ".."):
        return f"is {value!r}, must not be '.' or '..'"
    if any(unicodedata.category(c) == "Cc" for c in value):
        return f"is {value!r}, must not contain control characters"
    if value != value.strip():
        return f"is {value!r}, must not start or end with white space"
    return None


def _participant_id(value, meta: dict) -> str | None:
    return participant_id_problem(value) if isinstance(value, str) and value.strip() else None


def _integer(value, meta: dict) -> str | None:
    if isinstance(value, int) and not isinstance(value, bool):
        return None
    return f"is {value!r}, expected an integer"


def _one_of(allowed: tuple[str, ...]) -> MetaCheck:
    def check(value, meta: dict) -> str | None:
        return None if value in allowed else f"is {value!r}, expected one of {', '.join(allowed)}"

    return check


def _task_phase(phase, meta: dict) -> str | None:
    task = meta.get("task")
    if task in TASKS and phase in PHASES and phase not in TASK_PHASES[task]:
        expected = " or ".join(TASK_PHASES[task])
        return f"{phase!r} is not a phase of task {task!r} ({expected})"
    return None


def _phase_method(method, meta: dict) -> str | None:
    phase = meta.get("phase")
    expected = PHASE_METHOD.get(phase) if isinstance(phase, str) else None
    if expected is not None and method in METHODS and method != expected:
        return f"phase {phase!r} is run with {expected!r}"
    return None


def _intent_names(intents, meta: dict) -> str | None:
    if not (isinstance(intents, list) and all(isinstance(n, str) and n.strip() for n in intents)):
        return "expected a list of non-empty strings"
    if len(set(intents)) != len(intents):
        return "an intent name is listed twice"
    return None


def _positive_number(value, meta: dict) -> str | None:
    number = isinstance(value, int | float) and not isinstance(value, bool)
    if number and math.isfinite(value) and value > 0:
        return None
    return f"is {value!r}, expected a positive number of seconds"


def _inference(value, meta: dict) -> str | None:
    allowed = {"preset": REPLAY_PRESETS, "evidence": EVIDENCE, "point": POINTS}
    required = ("preset", "evidence")
    if not isinstance(value, dict) or not set(required) <= set(value) <= set(allowed):
        return f"expected an object with the keys {', '.join(required)} (and optionally point)"
    for key, names in allowed.items():
        if key in value and value[key] not in names:
            return f"{key} is {value[key]!r}, expected one of {', '.join(names)}"
    return None


def _finite(value) -> bool:
    number = isinstance(value, int | float) and not isinstance(value, bool)
    return number and math.isfinite(value)


def _index(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0


def _increasing(values) -> bool:
    return all(b > a for a, b in zip(values, values[1:], strict=False))


def _inference_steps(value, meta: dict) -> str | None:
    if not isinstance(value, dict) or not {"started", "waypoint"} <= set(value):
        return "expected an object with the keys started and waypoint"
    unknown = sorted(set(value) - set(INFERENCE_STEPS_KEYS))
    if unknown:
        return f"{unknown[0]!r} is not a key of it; allowed: {', '.join(INFERENCE_STEPS_KEYS)}"
    started, at = value["started"], value["waypoint"]
    if not (isinstance(started, list) and all(_finite(t) and t >= 0 for t in started)):
        return "started: expected a list of times in seconds, each >= 0"
    if not (isinstance(at, list) and all(_index(w) and w >= 1 for w in at)):
        return "waypoint: expected a list of waypoint indices, each >= 1"
    if len(at) != len(started):
        return f"waypoint has {len(at)} entries, started {len(started)}: one per step"
    if not (_increasing(started) and _increasing(at)):
        return "started and waypoint must strictly increase: each step after the last"
    waypoints = value.get("waypoints")
    if waypoints is not None:
        rows = isinstance(waypoints, list) and len(waypoints) >= 2
        if not rows or not all(
            isinstance(row, list) and len(row) == len(JOINTS) and all(map(_finite, row))
            for row in waypoints
        ):
            return f"waypoints: expected 2 or more lists of {len(JOINTS)} joint angles (rad)"
        if at and at[-1] >= len(waypoints):
            return f"waypoint {at[-1]} of the last step is not among the {len(waypoints)} waypoints"
    after = value.get("after_trial")
    if after is None:
        return None
    if not isinstance(after, dict) or not set(after) <= {"waypoint", *INTENT_PREFIXES}:
        return "after_trial: expected an object with the keys waypoint, beta and belief"
    if "waypoint" in after and not _index(after["waypoint"]):
        return "after_trial: waypoint must be a waypoint index"
    if "waypoint" in after and waypoints is not None and after["waypoint"] >= len(waypoints):
        return f"after_trial: waypoint {after['waypoint']} is not among the {len(waypoints)}"
    intents = meta.get("intents") if isinstance(meta.get("intents"), list) else None
    for key in INTENT_PREFIXES:
        values = after.get(key, {})
        if not isinstance(values, dict) or not all(
            v is None or _finite(v) for v in values.values()
        ):
            return f"after_trial: {key} must map intent names to numbers (or null)"
        stray = [name for name in values if intents is not None and name not in intents]
        if stray:
            return f"after_trial: {key} names {stray[0]!r}, which is not in intents"
    return None


def _flags(value, meta: dict) -> str | None:
    if not (isinstance(value, list) and all(isinstance(flag, str) for flag in value)):
        return "expected a list of flags"
    unknown = [flag for flag in value if flag not in TRIAL_FLAGS]
    if unknown:
        return f"{unknown[0]!r} is not a flag; known: {', '.join(TRIAL_FLAGS)}"
    if len(set(value)) != len(value):
        return "a flag is listed twice"
    return None


#: The metadata rules after the required and unknown keys, in the order they are
#: reported: (key, rule, check). A check runs when its key is present.
META_RULES: tuple[tuple[str, str, MetaCheck], ...] = (
    ("schema", "schema", _schema),
    ("participant", "non-empty-string", _non_empty_string),
    ("participant", "participant-id", _participant_id),
    *((key, "enum", _one_of(allowed)) for key, allowed in META_ENUMS),
    ("phase", "task-phase", _task_phase),
    ("method", "phase-method", _phase_method),
    ("intents", "intent-names", _intent_names),
    ("max_duration", "positive-number", _positive_number),
    ("seed", "integer", _integer),
    ("inference", "inference-settings", _inference),
    ("inference_steps", "inference-steps", _inference_steps),
    ("flags", "trial-flags", _flags),
)


def check_meta(meta, file: str) -> list[Problem]:
    """Every way in which a trial's metadata breaks casa-trial/1.

    Parameters
    ----------
    meta : object
        The parsed ``.json``; anything but a dict is one ``json-object`` problem.
    file : str
        The file's name, used in problems.

    Returns
    -------
    list of Problem
        Missing keys, unknown keys, then :data:`META_RULES` in order; empty when valid.

    Examples
    --------
    >>> meta = {"schema": "casa-trial/1", "participant": "p01", "task": "unknown_goal",
    ...         "method": "PBA", "phase": "demonstration", "source": "human"}
    >>> [(p.where, p.rule) for p in check_meta(meta, "t.json")]
    [("key 'method'", 'phase-method')]
    >>> [p.rule for p in check_meta({"participant": "p01"}, "t.json")][:2]
    ['required-key', 'required-key']
    """
    if not isinstance(meta, dict):
        return [Problem(file, "", "json-object", "the metadata must be a JSON object")]
    problems = []

    def bad(key: str, rule: str, message: str) -> None:
        problems.append(Problem(file, f"key {key!r}", rule, message))

    for key in META_REQUIRED:
        if key not in meta:
            bad(key, "required-key", "missing")
    allowed = ", ".join(META_REQUIRED + META_OPTIONAL)
    for key in sorted(set(meta) - set(META_REQUIRED) - set(META_OPTIONAL)):
        bad(key, "unknown-key", f"not part of {SCHEMA}; allowed keys: {allowed}")
    for key, rule, check in META_RULES:
        if key in meta:
            message = check(meta[key], meta)
            if message is not None:
                bad(key, rule, message)
    return problems
