"""The pouring skill as an intent, and the cup's orientation as a function of rot.

Pouring (the Unknown Skill task, paper Sec. IV) is more than a goal: the cup must
be carried upright to the pouring target and tilted there. It is written as a
differentiable per-state cost and planned with :mod:`casa_core.planning`.

Orientation of the cup
    The cup's axis is the end effector's x axis
    (:func:`casa_core.planning.rotation.end_effector_rotation`): up at rot = 0; the rotate
    keys turn the tool about its horizontal z axis, so the cup's tilt from upright
    is ``|rot|`` (wrapped to [0, pi]). The original implementation's "cup upright"
    feature is ``1 - (cup axis . world z)``: 0 with the cup upright, 1 on its side,
    2 upside down (see docs/paper-to-code.md).
"""

from __future__ import annotations

import math

import numpy as np
import torch
from numba import njit

from casa_core import portable_math
from casa_core.model._checks import require_positive
from casa_core.planning import PlannedIntent, PlannerConfig
from casa_core.planning.rotation import R0, end_effector_rotation
from casa_core.scene import Scene

#: Width over which the cost's distance (m) and chords are rounded, so gradients exist at 0.
ROUNDING = 1e-3


def cup_upright(rot: torch.Tensor) -> torch.Tensor:
    """The original's feature ``1 - (x-axis of the last link . world z)``: 0 upright, 2 inverted."""
    return 1.0 - end_effector_rotation(rot)[..., 2, 0]


def cup_tilt_deg(rot) -> np.ndarray | float:
    """Angle (degrees) between the cup's axis and world up, at angle(s) ``rot``."""
    rot_t = torch.as_tensor(np.asarray(rot, dtype=float))
    cosine = end_effector_rotation(rot_t)[..., 2, 0].clamp(-1.0, 1.0)
    tilt = np.degrees(np.arccos(cosine.numpy()))
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
    ``1 - a . z``; both chords grow linearly with the angle, so
    that their gradients do not vanish at the upright cup (``u`` alone is flat
    there and a planner would never start tilting). Away from the target (beyond
    about ``radius``) the spill term outweighs the pour term and the cup stays
    upright; near it only the pour term is left and the cup tilts. Being upright
    costs the same near and far, so the gate puts no barrier around the target.
    ``d`` and the chords are smoothed over 1 mm / 1e-3 (``ROUNDING``) so that gradients exist
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
        *,
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
        require_positive(
            f"intent {name!r}",
            scale=scale,
            pour_weight=pour_weight,
            spill_weight=spill_weight,
            radius=radius,
        )
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
        self._planning_cost = PouringCost(self)

    @classmethod
    def from_scene(cls, scene: Scene, name: str = "pour", **kwargs) -> PouringIntent:
        """The pouring intent of a scene: its ``pouring.position`` and ``pouring.tilt``.

        Examples
        --------
        >>> from casa_core.scene import load_scene
        >>> PouringIntent.from_scene(load_scene())
        PouringIntent('pour', target=[0.56, 0.22, 0.32], tilt=1.8)
        """
        return cls(name, scene.pouring.position, tilt=scene.pouring.tilt, **kwargs)

    def __repr__(self) -> str:
        return f"PouringIntent({self.name!r}, target={self.target.tolist()}, tilt={self.tilt})"

    @property
    def planning_cost(self) -> PouringCost:
        """:meth:`state_cost` and its gradient computed by hand (:class:`PouringCost`)."""
        return self._planning_cost

    def state_cost(self, states: torch.Tensor) -> torch.Tensor:
        d = _norm(states[..., :3] - self._target_t, ROUNDING)
        axis = cup_axis(states[..., 3])
        pour = _norm(axis - self._pour_axis, ROUNDING)
        spill = _norm(axis - self._up, ROUNDING)
        far = 1.0 - portable_math.exp(-((d / self.radius) ** 2))
        return (
            self.scale * self.dt * (d + self.pour_weight * pour + self.spill_weight * far * spill)
        )


def _norm(v: torch.Tensor, width: float) -> torch.Tensor:
    """Euclidean norm over the last axis, rounded over ``width`` so its gradient exists at 0."""
    return portable_math.sqrt((v * v).sum(dim=-1) + width * width) - width


class PouringCost:
    """:meth:`PouringIntent.state_cost` and its gradient in the states, without autograd.

    The planner evaluates the pouring cost and its gradient some hundred times per plan
    on a few dozen states; torch's per-operation and autograd overhead is most of that
    time. This computes the same formula and its derivative by hand in one compiled
    (numba) loop over the states, on numpy arrays; ``tests/robot/test_fast_tick.py`` holds
    both to torch's autograd. A snapshot of the intent's parameters at construction.

    Examples
    --------
    >>> from casa_core.scene import load_scene
    >>> intent = PouringIntent.from_scene(load_scene())
    >>> states = np.array([[[0.5, 0.2, 0.3, 0.0], [0.56, 0.22, 0.32, 1.8]]])
    >>> values, grad = intent.planning_cost.value_and_grad(states)
    >>> want = intent.state_cost(torch.from_numpy(states)).numpy()
    >>> values.shape, grad.shape, bool(np.allclose(values, want, rtol=1e-12))
    ((1, 2), (1, 2, 4), True)
    """

    def __init__(self, intent: PouringIntent):
        # cup_axis(rot) = cos(rot) x0 + sin(rot) y0, the tool's x and y axes at rot = 0.
        self._params = np.concatenate(
            [
                intent.target,
                intent._pour_axis.numpy(),
                R0[:, 0],
                R0[:, 1],
                [intent.scale * intent.dt, intent.pour_weight, intent.spill_weight],
                [intent.radius, ROUNDING],
            ]
        )

    def __call__(self, states) -> np.ndarray:
        """Per-state costs ``(...)`` of states ``(..., 4)``."""
        return self.value_and_grad(states)[0]

    def value_and_grad(self, states) -> tuple[np.ndarray, np.ndarray]:
        """Per-state costs ``(...)`` and the gradient of their sum in the states ``(..., 4)``."""
        states = np.asarray(states, dtype=float)
        flat = np.ascontiguousarray(states).reshape(-1, 4)
        values, grad = _pouring_cost(flat, self._params)
        return values.reshape(states.shape[:-1]), grad.reshape(states.shape)


@njit(cache=True)
def _pouring_cost(states, params):
    """The pouring cost of states ``(n, 4)`` and its gradient (see :class:`PouringCost`)."""
    n = states.shape[0]
    values = np.empty(n)
    grad = np.empty((n, 4))
    k, pour_weight, spill_weight, radius, width = params[12:17]
    width2 = width * width
    for i in range(n):
        # d = |p - target| rounded over width, and its gradient (p - target) / (d + width).
        dx = states[i, 0] - params[0]
        dy = states[i, 1] - params[1]
        dz = states[i, 2] - params[2]
        root = math.sqrt((dx * dx + dy * dy + dz * dz) + width2)
        d = root - width
        c, s = math.cos(states[i, 3]), math.sin(states[i, 3])
        pour_sq = 0.0
        spill_sq = 0.0
        pour_slope = 0.0
        spill_slope = 0.0
        for j in range(3):
            a = c * params[6 + j] + s * params[9 + j]
            da = c * params[9 + j] - s * params[6 + j]  # d axis / d rot
            to_pour = a - params[3 + j]
            to_up = a - (1.0 if j == 2 else 0.0)
            pour_sq += to_pour * to_pour
            spill_sq += to_up * to_up
            pour_slope += to_pour * da
            spill_slope += to_up * da
        pour_root = math.sqrt(pour_sq + width2)
        spill_root = math.sqrt(spill_sq + width2)
        pour = pour_root - width
        spill = spill_root - width
        ratio = d / radius
        gate = math.exp(-(ratio * ratio))
        far = 1.0 - gate
        values[i] = k * (d + pour_weight * pour + spill_weight * far * spill)
        along = k * (1.0 + spill_weight * spill * gate * 2.0 * ratio / radius) / root
        grad[i, 0] = along * dx
        grad[i, 1] = along * dy
        grad[i, 2] = along * dz
        grad[i, 3] = k * (
            pour_weight * pour_slope / pour_root + spill_weight * far * spill_slope / spill_root
        )
    return values, grad
