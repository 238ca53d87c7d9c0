"""The task scene: where the arm starts, the goals, the pouring target and the teleoperation.

One :class:`Scene` describes a study's layout in the robot base frame (metres, radians;
the JACO base at the origin on the table top, z up). It is loaded and validated from a
YAML file (``config/scene.yaml``) once, at the edge, and passed down; every error names
the key and the rule it breaks.

Examples
--------
>>> scene = load_scene()
>>> scene.start_state.tolist()
[0.45, -0.22, 0.38, 0.0]
>>> scene.goal("green").tolist()
[0.58, 0.0, 0.3]
>>> scene.teleop.dt
0.05
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
import yaml

from casa_core.vocabulary import POINTS, TASKS, TELEOP_MODES, VIEWS

#: The scene the package is set up with: ``config/scene.yaml`` of the repository. A path
#: given by a user is resolved against the working directory instead.
DEFAULT_SCENE = Path(__file__).resolve().parents[1] / "config" / "scene.yaml"
#: The goals the robot knows from the start (paper, Sec. IV), in the original
#: implementation's goal order.
KNOWN_GOALS = ("green", "purple")
#: Goals every study scene has: the two known goals and the unknown one.
REQUIRED_GOALS = (*KNOWN_GOALS, "red")


class SceneError(ValueError):
    """A scene file that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class Start:
    """Where every trial starts: end-effector ``position`` (m) and the rotate keys' ``rot``.

    ``joints``, optional: the seven joint angles (rad) of that start, where the layout
    gives them (the authors' start pose, whose tool orientation is not the held one). The
    ``original`` teleoperation starts there; ``held`` starts at the inverse kinematics of
    ``position`` with the held orientation.
    """

    position: tuple[float, float, float]
    rot: float
    joints: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Pouring:
    """The Unknown Skill: hold the cup at ``position``, above the ``bowl``, tilted to ``tilt``."""

    position: tuple[float, float, float]
    bowl: tuple[float, float, float]
    tilt: float


@dataclass(frozen=True)
class Teleop:
    """The keyboard: ``speed`` (m/s per key), ``rot_speed`` (rad/s), the tick ``dt`` (s) and
    the ``mode`` by which keys move the arm (:data:`~casa_core.vocabulary.TELEOP_MODES`)."""

    speed: float
    rot_speed: float
    dt: float
    mode: str = "held"


@dataclass(frozen=True)
class View:
    """A camera the scene pins (:mod:`casa_core.robot.camera`): pybullet's orbit camera at
    ``target`` (m), ``distance`` (m), ``yaw`` and ``pitch`` (degrees)."""

    target: tuple[float, float, float]
    distance: float
    yaw: float
    pitch: float


@dataclass(frozen=True)
class Scene:
    """A study's layout; build it with :func:`load_scene` or :meth:`Scene.from_dict`.

    Attributes
    ----------
    start : Start
    goals : Mapping[str, tuple of 3 floats]
        Goal positions by name (read-only); at least ``green``, ``purple`` and ``red``.
    pouring : Pouring
    teleop : Teleop
    point : str
        The point of the arm whose position the state is, and of which the start, the goals
        and the pouring pose are positions (:data:`~casa_core.vocabulary.POINTS`):
        ``tool``, the tool point (default), or ``link7``, the origin of link 7 (the
        original implementation's end effector, 0.16 m before the tool point).
    goals_elsewhere : Mapping[str, Mapping[str, tuple of 3 floats]]
        Optional: the same goals at the other point, by point (the file's section named
        for it), for a replay that measures the arm there; empty when not given.
    via : Mapping[str, tuple of (3 floats)]
        Optional: by task, the positions its intended path passes through, in order,
        between the start and the task's end (:func:`casa_core.assist.tasks.task_waypoints`);
        a task not named goes straight.
    view : Mapping[str, View]
        Optional: the cameras the scene pins, by view (:data:`~casa_core.vocabulary.VIEWS`:
        ``window``, ``figure``); a view not pinned frames the scene's positions
        (:func:`casa_core.robot.camera.scene_camera`).
    trial_length : float or None
        Optional (s): every trial runs exactly this long, and an operator who has arrived
        waits with no key held until it ends (the original's protocol, 15 s). None
        (default): a trial ends when the operator is done, or at its time limit.
    """

    start: Start
    goals: MappingProxyType
    pouring: Pouring
    teleop: Teleop
    point: str = POINTS[0]
    goals_elsewhere: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    via: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    view: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    trial_length: float | None = None

    @property
    def start_state(self) -> np.ndarray:
        """The state ``[x, y, z, rot]`` in which every trial starts."""
        return np.array([*self.start.position, self.start.rot], dtype=float)

    def with_teleop_mode(self, mode: str | None) -> Scene:
        """The same layout driven by teleoperation ``mode``; ``None`` keeps the scene's.

        Examples
        --------
        >>> load_scene().with_teleop_mode("original").teleop.mode
        'original'
        """
        if mode is None:
            return self
        if mode not in TELEOP_MODES:
            raise SceneError(f"teleop mode {mode!r}: expected one of {', '.join(TELEOP_MODES)}")
        return dataclasses.replace(self, teleop=dataclasses.replace(self.teleop, mode=mode))

    def goals_at(self, point: str | None = None) -> MappingProxyType:
        """The goals by name at ``point`` (``"tool"`` or ``"link7"``; default the scene's
        :attr:`point`); empty where the scene does not give them there."""
        if point is None or point == self.point:
            return self.goals
        return self.goals_elsewhere.get(point, MappingProxyType({}))

    def goal(self, name: str, point: str | None = None) -> np.ndarray:
        """The position of goal ``name`` at ``point`` (as :meth:`goals_at`).

        Raises
        ------
        SceneError
            Naming the goals the scene has at that point.
        """
        goals = self.goals_at(point)
        if name not in goals:
            key = "goals" if goals is self.goals else point
            raise SceneError(f"scene: {key} has no {name!r}; it has {', '.join(goals) or 'none'}")
        return np.array(goals[name], dtype=float)

    @classmethod
    def from_dict(cls, data: Any, source: str = "scene") -> Scene:
        """Validate a parsed scene file; ``source`` names it in errors.

        Its sections and keys are checked first (:func:`_sections`), then its values.
        """
        reader = _Reader(source)
        parts = _sections(reader, data)
        start, goals, pouring, teleop = parts.start, parts.goals, parts.pouring, parts.teleop
        return cls(
            start=Start(
                reader.vector(start, "start.position"),
                reader.number(start, "start.rot"),
                reader.joints(start, "start.joints") if "joints" in start else None,
            ),
            goals=MappingProxyType(
                {str(name): reader.vector(goals, f"goals.{name}") for name in goals}
            ),
            pouring=Pouring(
                reader.vector(pouring, "pouring.position"),
                reader.vector(pouring, "pouring.bowl"),
                reader.number(pouring, "pouring.tilt"),
            ),
            teleop=Teleop(
                reader.number(teleop, "teleop.speed", positive=True),
                reader.number(teleop, "teleop.rot_speed", positive=True),
                reader.number(teleop, "teleop.dt", positive=True),
                parts.mode,
            ),
            point=parts.point,
            via=MappingProxyType(
                {task: reader.path(parts.via, f"via.{task}") for task in parts.via}
            ),
            view=MappingProxyType(
                {name: reader.view(parts.view, f"view.{name}") for name in parts.view}
            ),
            goals_elsewhere=MappingProxyType(
                {
                    other: MappingProxyType(
                        {str(name): reader.vector(named, f"{other}.{name}") for name in named}
                    )
                    for other, named in parts.elsewhere.items()
                }
            ),
            trial_length=parts.trial_length,
        )


@dataclass(frozen=True)
class _Sections:
    """A scene file's sections, their keys checked and their values not yet read."""

    point: str
    start: dict
    goals: dict
    pouring: dict
    teleop: dict
    mode: str
    via: dict
    view: dict
    elsewhere: dict  # the goals at the other points, by point
    trial_length: float | None


def _sections(reader: _Reader, data: Any) -> _Sections:
    """The sections of a parsed scene file: each key known, each required one there."""
    top = reader.mapping(
        data,
        "",
        ("start", "goals", "pouring", "teleop"),
        ("point", *POINTS, "via", "view", "trial_length"),
    )
    point = top.get("point", POINTS[0])
    if point not in POINTS:
        reader.fail("point", f"must be one of {', '.join(POINTS)}, got {point!r}")
    if point in top:
        reader.fail(point, f"the scene's own point ({point}): its goals go in goals")
    start = reader.mapping(top["start"], "start", ("position", "rot"), ("joints",))
    if point != POINTS[0] and "joints" not in start:
        reader.fail("start.joints", f"required at point {point}: the arm starts at its joints")
    goals = reader.mapping(top["goals"], "goals", None)
    missing = [name for name in REQUIRED_GOALS if name not in goals]
    if missing:
        raise SceneError(
            f"{reader.source}: goals.{missing[0]}: missing (required: green, purple, red)"
        )
    pouring = reader.mapping(top["pouring"], "pouring", ("position", "bowl", "tilt"))
    teleop = reader.mapping(top["teleop"], "teleop", ("speed", "rot_speed", "dt"), ("mode",))
    mode = teleop.get("mode", "held")
    if mode not in TELEOP_MODES:
        reader.fail("teleop.mode", f"must be one of {', '.join(TELEOP_MODES)}, got {mode!r}")
    via = reader.mapping(top.get("via", {}), "via", (), TASKS)
    view = reader.mapping(top.get("view", {}), "view", (), VIEWS)
    elsewhere = {other: reader.mapping(top[other], other, None) for other in POINTS if other in top}
    for other, named in elsewhere.items():
        for name in named:
            if name not in goals:
                reader.fail(f"{other}.{name}", f"not a goal of the scene ({', '.join(goals)})")
    trial_length = top.get("trial_length")
    if trial_length is not None:
        trial_length = reader.number(top, "trial_length", positive=True)
    return _Sections(point, start, goals, pouring, teleop, mode, via, view, elsewhere, trial_length)


def load_scene(path: Path | str | None = None) -> Scene:
    """Load and validate a scene file; default :data:`DEFAULT_SCENE`.

    Raises
    ------
    SceneError
        Naming the file and the key: a missing or unreadable file, a missing or unknown
        key, a value of the wrong kind.
    """
    path = DEFAULT_SCENE if path is None else Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(f"cannot read the scene {path}: {error}") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise SceneError(f"{path}: not valid YAML: {error}") from None
    return Scene.from_dict(data, str(path))


class _Reader:
    """Checks of one scene file, each error naming the file and the dotted key."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str, rule: str):
        where = f"{self.source}: {key}" if key else self.source
        raise SceneError(f"{where}: {rule}")

    def mapping(
        self, node, key: str, required: tuple[str, ...] | None, optional: tuple[str, ...] = ()
    ) -> dict:
        if not isinstance(node, dict):
            self.fail(key, f"must be a mapping, got {node!r}")
        if required is not None:
            prefix = f"{key}." if key else ""
            for name in required:
                if name not in node:
                    self.fail(f"{prefix}{name}", "missing")
            known = (*required, *optional)
            for name in node:
                if name not in known:
                    self.fail(f"{prefix}{name}", f"unknown key; expected {', '.join(known)}")
        return node

    def number(self, node: dict, key: str, *, positive: bool = False) -> float:
        value = node[key.rsplit(".", 1)[-1]]
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            self.fail(key, f"must be a finite number, got {value!r}")
        if positive and value <= 0:
            self.fail(key, f"must be positive, got {value!r}")
        return float(value)

    def numbers(self, node: dict, key: str, count: int, what: str) -> tuple[float, ...]:
        """``count`` finite numbers at ``key``; ``what`` says what they are in the error."""
        value = node[key.rsplit(".", 1)[-1]]
        numbers = isinstance(value, list) and all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in value
        )
        if not numbers or len(value) != count:
            self.fail(key, f"must be {count} finite {what}, got {value!r}")
        return tuple(float(v) for v in value)

    def joints(self, node: dict, key: str) -> tuple[float, ...]:
        """Seven joint angles given in degrees (the original's convention), in radians."""
        degrees = self.numbers(node, key, 7, "joint angles in degrees")
        return tuple(math.radians(v) for v in degrees)

    def path(self, node: dict, key: str) -> tuple[tuple[float, float, float], ...]:
        """A non-empty list of positions ``[x, y, z]``; an error names ``key.<index>``."""
        value = node[key.rsplit(".", 1)[-1]]
        if not isinstance(value, list) or not value:
            self.fail(key, f"must be a list of positions [x, y, z], got {value!r}")
        positions = {str(index): position for index, position in enumerate(value)}
        return tuple(self.vector(positions, f"{key}.{index}") for index in positions)

    def view(self, node: dict, key: str) -> View:
        """A pinned camera: ``target`` [x, y, z], ``distance`` (positive), ``yaw``, ``pitch``."""
        camera = self.mapping(
            node[key.rsplit(".", 1)[-1]], key, ("target", "distance", "yaw", "pitch")
        )
        return View(
            self.vector(camera, f"{key}.target"),
            self.number(camera, f"{key}.distance", positive=True),
            self.number(camera, f"{key}.yaw"),
            self.number(camera, f"{key}.pitch"),
        )

    def vector(self, node: dict, key: str) -> tuple[float, float, float]:
        x, y, z = self.numbers(node, key, 3, "numbers [x, y, z]")
        return (x, y, z)
