"""The pouring skill as an intent, and the cup's orientation as a function of rot.

Pouring (the Unknown Skill task, paper Sec. IV) is more than a goal: the cup must
be carried upright to the pouring target and tilted there. It is written as a
differentiable per-state cost and planned with :mod:`casa_core.planning`.

Orientation of the cup
    The original's "cup upright" feature is ``1 - (x-axis of the last link .
    world z)`` (NOTES section 1): 0 with the cup upright, 1 on its side, 2
    upside down. The end effector's rotation is the arm's own
    (:func:`casa_core.robot.kinematics.ee_rotation`): at rot = 0 the tool's x
    axis (the cup's axis) points up and its z axis (the last joint's) is
    horizontal; the rotate keys turn the tool about its z axis by rot, so
    ``R(rot) = R0 @ Rz(rot)`` and the cup's tilt from upright is ``|rot|``
    (wrapped to [0, pi]). Here it is written in torch, to be differentiable.
"""

from __future__ import annotations

import numpy as np
import torch

from casa_core.planning import PlannedIntent, PlannerConfig
from casa_core.robot.kinematics import EE_ROTATION_AT_ZERO

#: R(0): columns are the tool's x (cup axis, up), y and z axes in the base frame.
R0 = EE_ROTATION_AT_ZERO


def end_effector_rotation(rot: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(..., 3, 3)`` of the end effector at angles ``rot`` ``(...)``.

    ``R(rot) = R0 @ Rz(rot)`` (see the module docstring); differentiable in rot.
    Written as ``cos(rot) A + sin(rot) B + C`` with constant matrices (the
    columns of R0 turned by Rz), which is cheaper than building Rz per state.
    """
    r0 = torch.as_tensor(R0, dtype=rot.dtype)
    zero = torch.zeros(3, dtype=rot.dtype)
    # R0 @ Rz(rot): column x = c r0x + s r0y, column y = -s r0x + c r0y, column z = r0z.
    a = torch.stack([r0[:, 0], r0[:, 1], zero], dim=-1)
    b = torch.stack([r0[:, 1], -r0[:, 0], zero], dim=-1)
    c = torch.stack([zero, zero, r0[:, 2]], dim=-1)
    return torch.cos(rot)[..., None, None] * a + torch.sin(rot)[..., None, None] * b + c


def cup_upright(rot: torch.Tensor) -> torch.Tensor:
    """The original's feature ``1 - (x-axis of the last link . world z)``: 0 upright, 2 inverted."""
    return 1.0 - end_effector_rotation(rot)[..., 2, 0]


def cup_tilt_deg(rot) -> np.ndarray | float:
    """Angle (degrees) between the cup's axis and world up, at angle(s) ``rot``."""
    rot_t = torch.as_tensor(np.asarray(rot, dtype=float))
    cosine = end_effector_rotation(rot_t)[..., 2, 0].clamp(-1.0, 1.0)
    tilt = np.degrees(torch.arccos(cosine).numpy())
    return float(tilt) if tilt.ndim == 0 else tilt


def cup_axis(rot: torch.Tensor) -> torch.Tensor:
    """The cup's axis (the tool's x axis) in the base frame, ``(..., 3)``."""
    return end_effector_rotation(rot)[..., :, 0]


class PouringIntent(PlannedIntent):
    """Carry the cup upright to the pouring target, then tilt it to pour.

    With ``a`` the cup's axis at the state's rot, ``a*`` the axis at the pouring
    tilt, ``up`` the world z axis and d the distance to the target, the cost of a
    state ``[x, y, z, rot]`` (summed over the states after the start) is

        scale * dt * ( d + pour_weight * |a - a*| + spill_weight * (1 - g(d)) * |a - up| ),
        g(d) = exp(-(d / radius)^2).

    ``|a - up|`` is ``sqrt(2 u)`` with u the original's cup-upright feature
    ``1 - a . z`` (NOTES section 1); both chords grow linearly with the angle, so
    that their gradients do not vanish at the upright cup (``u`` alone is flat
    there and a planner would never start tilting). Away from the target (beyond
    about ``radius``) the spill term outweighs the pour term and the cup stays
    upright; near it only the pour term is left and the cup tilts. Being upright
    costs the same near and far, so the gate puts no barrier around the target.
    ``d`` and the chords are smoothed over 1 mm / 1e-3 so that gradients exist
    everywhere. ``scale * dt * d`` is a goal intent's ``distance_sum`` cost, so
    the two compare on one scale; the weights are metres per unit of chord (ours).

    Parameters
    ----------
    name : str
        Intent name.
    target : array_like, shape (3,)
        Where the cup is held to pour (scene ``pouring.position``), metres.
    tilt : float
        rot at which the cup pours (scene ``pouring.tilt``), radians.
    scale : float
        Cost per metre-second of distance (as GoalIntent's ``distance_sum``).
    pour_weight, spill_weight : float
        Metres of distance that one unit of each chord is worth;
        ``spill_weight > pour_weight`` keeps the cup upright while carrying it.
    radius : float
        Distance (m) from the target within which the cup may tilt.
    planner : PlannerConfig, optional
        Horizon, dt, speed limits and optimizer settings.
    """

    def __init__(
        self,
        name: str,
        target,
        tilt: float,
        scale: float = 227.0,
        pour_weight: float = 0.1,
        spill_weight: float = 0.2,
        radius: float = 0.05,
        planner: PlannerConfig | None = None,
    ):
        super().__init__(name, planner)
        target = np.asarray(target, dtype=float)
        if target.shape != (3,) or not np.isfinite(target).all():
            raise ValueError(f"target of intent {name!r} must be 3 finite numbers, got {target!r}")
        weights = (
            ("scale", scale),
            ("pour_weight", pour_weight),
            ("spill_weight", spill_weight),
            ("radius", radius),
        )
        for key, value in weights:
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{key} of intent {name!r} must be positive, got {value!r}")
        if not np.isfinite(tilt):
            raise ValueError(f"tilt of intent {name!r} must be finite, got {tilt!r}")
        self.target = target
        self.tilt = float(tilt)
        self.scale = float(scale)
        self.pour_weight = float(pour_weight)
        self.spill_weight = float(spill_weight)
        self.radius = float(radius)
        self._target_t = torch.as_tensor(target, dtype=torch.float64)
        self._pour_axis = cup_axis(torch.tensor(self.tilt, dtype=torch.float64))
        self._up = torch.tensor([0.0, 0.0, 1.0], dtype=torch.float64)

    @classmethod
    def from_scene(cls, scene: dict, name: str = "pour", **kwargs) -> PouringIntent:
        """The pouring intent of a scene (keys ``pouring.position`` and ``pouring.tilt``)."""
        try:
            pouring = scene["pouring"]
            return cls(name, pouring["position"], pouring["tilt"], **kwargs)
        except KeyError as error:
            raise ValueError(f"scene has no pouring.{error.args[0]} (needed by {name!r})") from None

    def __repr__(self) -> str:
        return f"PouringIntent({self.name!r}, target={self.target.tolist()}, tilt={self.tilt})"

    def state_cost(self, states: torch.Tensor) -> torch.Tensor:
        d = _norm(states[..., :3] - self._target_t, 1e-3)
        axis = cup_axis(states[..., 3])
        pour = _norm(axis - self._pour_axis, 1e-3)
        spill = _norm(axis - self._up, 1e-3)
        far = 1.0 - torch.exp(-((d / self.radius) ** 2))
        return (
            self.scale * self.dt * (d + self.pour_weight * pour + self.spill_weight * far * spill)
        )


def _norm(v: torch.Tensor, width: float) -> torch.Tensor:
    """Euclidean norm over the last axis, rounded over ``width`` so its gradient exists at 0."""
    return torch.sqrt((v * v).sum(dim=-1) + width * width) - width
