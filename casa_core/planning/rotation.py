"""The end effector's orientation as a differentiable function of the state's ``rot``.

The orientation is the arm's own (:func:`casa_core.robot.kinematics.ee_rotation`): at
rot = 0 the tool's x axis (the cup's axis) points up and its z axis (the last joint's)
is horizontal; the rotate keys turn the tool about its z axis by rot, so
``R(rot) = R0 @ Rz(rot)``. Here it is written in torch, so that costs built on it
(the pouring skill, the features of learned intents) have gradients in rot.

Examples
--------
>>> import torch
>>> end_effector_rotation(torch.tensor(0.0, dtype=torch.float64))[:, 0].tolist()
[0.0, 0.0, 1.0]
"""

from __future__ import annotations

import torch

from casa_core import portable_math
from casa_core.robot.kinematics import EE_ROTATION_AT_ZERO

#: R(0): columns are the tool's x (cup axis, up), y and z axes in the base frame.
R0 = EE_ROTATION_AT_ZERO


def end_effector_rotation(rot: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``(..., 3, 3)`` of the end effector at angles ``rot`` ``(...)``.

    ``R(rot) = R0 @ Rz(rot)`` (see the module docstring); differentiable in rot.
    Written as ``cos(rot) A + sin(rot) B + C`` with constant matrices (the
    columns of R0 turned by Rz), which is cheaper than building Rz per state.

    Examples
    --------
    >>> import torch
    >>> matrix = end_effector_rotation(torch.tensor([0.3, 1.8], dtype=torch.float64))
    >>> matrix.shape
    torch.Size([2, 3, 3])
    >>> torch.allclose(matrix[0].T @ matrix[0], torch.eye(3, dtype=torch.float64))
    True
    """
    r0 = torch.as_tensor(R0, dtype=rot.dtype)
    zero = torch.zeros(3, dtype=rot.dtype)
    # R0 @ Rz(rot): column x = c r0x + s r0y, column y = -s r0x + c r0y, column z = r0z.
    a = torch.stack([r0[:, 0], r0[:, 1], zero], dim=-1)
    b = torch.stack([r0[:, 1], -r0[:, 0], zero], dim=-1)
    c = torch.stack([zero, zero, r0[:, 2]], dim=-1)
    return (
        portable_math.cos(rot)[..., None, None] * a
        + portable_math.sin(rot)[..., None, None] * b
        + c
    )
