"""Forward kinematics, Jacobian and inverse kinematics of the Kinova JACO 7-DoF (j2s7s300).

The joint origins are those of the JACO description the original implementation used;
every arm joint turns about its local z axis, and joint angles mean what they mean on
the original's (and Kinova's) arm: the tests put the original's four reference
configurations at its link-7 positions to 1 mm. Our URDF ``j2s7s300.urdf`` is built
from the same numbers, and the tests check this numpy forward kinematics against
pybullet's.

Two points of the hand have a name. The *link-7 origin* (:func:`link7_position`) is
what the original implementation called the end effector: its costs, goals and PBA
distances are measured there. Our *end effector* (EE) is the ``tool`` frame, 0.16 m
further along the last joint's axis, where the cup is held; the state ``[x, y, z,
rot]`` and the ``x, y, z`` of every casa-trial/1 log are its position. While the tool
orientation is held (our teleoperation), the two points differ by a constant offset,
so path lengths and distances are the same for both.

The EE frame's orientation is fixed during teleoperation except for the turn of the
last joint, measured by the state's angle ``rot``:

* at ``rot = 0`` the tool's z axis (the last joint's axis, pointing away from the
  wrist) is horizontal, at 45 degrees between the base's +x and +y axes, and the
  tool's x axis (the cup's axis, pointing out of its mouth) is vertical, up; so the
  cup is upright;
* turning the last joint by ``rot`` turns the tool about its own z axis, which tilts
  the cup: at ``rot = pi/2`` the cup lies on its side, mouth toward ``(1, -1, 0)``.

Why 45 degrees: with the fixed orientation every scene position must be reachable
along straight paths from the start without a joint reaching a limit. Approach
directions from 0 to 90 degrees in steps of 15 were driven in simulation to every
goal and the pouring pose; 0 degrees (along +x) folds the elbow into its 30 degree
limit on the way to the red goal, 90 degrees stalls before the purple goal, 30 to 60
degrees reach all of them.

:func:`ee_rotation` gives that orientation for any ``rot``; learned intents use its
nine entries as features, and the original's "cup upright" feature
``1 - (x axis of the tool . world z)`` is 0 at ``rot = 0``.
"""

from __future__ import annotations

import numpy as np

from casa_core.fixed_order import matmul, solve_spd

#: Joint origins parent -> child, ``(xyz [m], rpy [rad])``, the original's. The first
#: seven are the revolute arm joints 1..7, the last is the fixed joint to the tool.
JOINT_ORIGINS: tuple[tuple[tuple[float, float, float], tuple[float, float, float]], ...] = (
    ((0.0, 0.0, 0.15675), (0.0, np.pi, 0.0)),
    ((0.0, 0.0016, -0.11875), (-np.pi / 2, 0.0, np.pi)),
    ((0.0, -0.205, 0.0), (np.pi / 2, 0.0, np.pi)),
    ((0.0, 0.0, -0.205), (np.pi / 2, 0.0, np.pi)),
    ((0.0, 0.2073, -0.0114), (-np.pi / 2, 0.0, np.pi)),
    ((0.0, 0.0, -0.10375), (np.pi / 2, 0.0, np.pi)),
    ((0.0, 0.10375, 0.0), (-np.pi / 2, 0.0, np.pi)),
    ((0.0, 0.0, -0.16), (np.pi, 0.0, 0.0)),
)

N_JOINTS = 7

#: Joint limits (rad) of the j2s7s300 as Kinova specifies them: joints 1, 3, 5, 7 turn
#: without end (``-inf, inf``); joints 2, 4, 6 are bounded (47-313, 30-330, 65-295 deg).
JOINT_LOWER = np.array([-np.inf, 0.820305, -np.inf, 0.523599, -np.inf, 1.134464, -np.inf])
JOINT_UPPER = np.array([np.inf, 5.462881, np.inf, 5.759587, np.inf, 5.148721, np.inf])

#: Maximum joint speeds (rad/s) of the j2s7s300: 36 deg/s for the large actuators
#: (joints 1-4), 48 deg/s for the small ones (joints 5-7).
JOINT_MAX_SPEED = np.array([0.6283, 0.6283, 0.6283, 0.6283, 0.8378, 0.8378, 0.8378])

_H = np.sqrt(0.5)

#: Orientation of the tool at ``rot = 0`` in the base frame: columns are the tool's x
#: (cup axis: up), y and z (last joint axis: horizontal, along ``(1, 1, 0) / sqrt 2``) axes.
EE_ROTATION_AT_ZERO = np.array(
    [
        [0.0, _H, _H],
        [0.0, -_H, _H],
        [1.0, 0.0, 0.0],
    ]
)

#: Seed of inverse kinematics: the elbow-up solution for the start pose of
#: ``config/scene.yaml`` with the widest joint-limit margin among 300 random seeds.
HOME_CONFIGURATION = np.array([-1.456, 4.48, 4.626, 4.785, -0.175, 2.329, 1.478])


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rotation matrix of URDF roll-pitch-yaw angles, ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return matmul(matmul(rz, ry), rx)


def rot_z(angle: float) -> np.ndarray:
    """Rotation matrix of a turn by ``angle`` about the z axis."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _origin_transform(xyz, rpy) -> np.ndarray:
    transform = np.eye(4)
    transform[:3, :3] = rpy_matrix(*rpy)
    transform[:3, 3] = xyz
    return transform


_ORIGINS = np.stack([_origin_transform(xyz, rpy) for xyz, rpy in JOINT_ORIGINS])


def _check_q(q) -> np.ndarray:
    q = np.asarray(q, dtype=float)
    if q.shape != (N_JOINTS,):
        raise ValueError(f"joint vector must have shape (7,), got {q.shape}")
    return q


def link_frames(q) -> np.ndarray:
    """Frames of links 1..7 and of the tool in the base frame.

    Parameters
    ----------
    q : array_like, shape (7,)
        Joint angles (rad).

    Returns
    -------
    numpy.ndarray, shape (8, 4, 4)
        Homogeneous transforms; entry ``i < 7`` is the frame of link ``i + 1`` (whose z
        axis is joint ``i + 1``'s axis), entry 7 the tool frame.
    """
    q = _check_q(q)
    frames = np.empty((8, 4, 4))
    current = np.eye(4)
    for i in range(N_JOINTS):
        turn = np.eye(4)
        turn[:3, :3] = rot_z(q[i])
        current = matmul(matmul(current, _ORIGINS[i]), turn)
        frames[i] = current
    frames[7] = matmul(current, _ORIGINS[7])
    return frames


def forward_kinematics(q) -> np.ndarray:
    """Pose of the tool (end effector) in the base frame: a 4x4 homogeneous transform."""
    return link_frames(q)[7]


def link7_position(q) -> np.ndarray:
    """Position ``(3,)`` of the link-7 origin, the original implementation's end effector.

    Examples
    --------
    >>> start = np.radians([180, 175, 180, 300, 180, 180, 190])  # the original's start
    >>> link7_position(start).round(3)
    array([-0.376,  0.01 ,  0.446])
    """
    return point_position(q, "link7")


#: The entry of :func:`link_frames` of each point the arm may be measured at
#: (:data:`~casa_core.vocabulary.POINTS`): the tool point, or the link-7 origin.
POINT_FRAMES = {"tool": 7, "link7": 6}


def point_position(q, point: str = "tool") -> np.ndarray:
    """Position ``(3,)`` of ``point`` (``"tool"`` or ``"link7"``) at joint angles ``q``.

    Examples
    --------
    >>> start = np.radians([180, 175, 180, 300, 180, 180, 190])
    >>> bool(np.array_equal(point_position(start, "link7"), link7_position(start)))
    True
    """
    return link_frames(q)[POINT_FRAMES[point]][:3, 3].copy()


def jacobian(q, point: str = "tool") -> np.ndarray:
    """Geometric Jacobian ``(6, 7)`` of ``point`` (default the tool): rows ``[v; omega]`` in
    the base frame."""
    frames = link_frames(q)
    tip = frames[POINT_FRAMES[point]][:3, 3]
    axes = frames[:7, :3, 2]
    origins = frames[:7, :3, 3]
    return np.vstack([np.cross(axes, tip - origins).T, axes.T])


def ee_rotation(rot: float) -> np.ndarray:
    """Orientation ``(3, 3)`` of the tool for the state angle ``rot`` (see module docs)."""
    return matmul(EE_ROTATION_AT_ZERO, rot_z(rot))


def rot_of(rotation: np.ndarray) -> float:
    """The angle ``rot`` in ``(-pi, pi]`` of a tool orientation, about the last joint's axis.

    Only the turn about the tool's z axis counts; a small tilt of that axis (tracking
    error) leaves it nearly unchanged.
    """
    relative = matmul(EE_ROTATION_AT_ZERO.T, rotation)
    return float(np.arctan2(relative[1, 0], relative[0, 0]))


def orientation_error(target: np.ndarray, current: np.ndarray) -> np.ndarray:
    """Rotation vector (base frame) that turns ``current`` into ``target``, for small errors."""
    delta = matmul(target, current.T)
    return 0.5 * np.array(
        [delta[2, 1] - delta[1, 2], delta[0, 2] - delta[2, 0], delta[1, 0] - delta[0, 1]]
    )


def damped_least_squares(jac: np.ndarray, twist: np.ndarray, damping: float) -> np.ndarray:
    """Joint velocities ``J^T (J J^T + damping^2 I)^-1 twist``: stable near singularities."""
    jjt = matmul(jac, jac.T)
    return matmul(jac.T, solve_spd(jjt + damping**2 * np.eye(jjt.shape[0]), twist))


def within_limits(q, margin: float = 0.0) -> bool:
    """True when every bounded joint is inside its limits by at least ``margin`` radians."""
    q = _check_q(q)
    return bool(np.all(q >= JOINT_LOWER + margin) and np.all(q <= JOINT_UPPER - margin))


def inverse_kinematics(
    position,
    rot: float = 0.0,
    seed=None,
    tol: float = 1e-6,
    max_iter: int = 500,
) -> np.ndarray:
    """Joint angles putting the tool at ``position`` with orientation ``ee_rotation(rot)``.

    Newton steps with damped least squares from ``seed`` (default
    :data:`HOME_CONFIGURATION`); bounded joints are clipped into their limits.

    Raises
    ------
    ValueError
        If no configuration within the joint limits reaches the pose to ``tol``
        (position in m, orientation in rad): the pose is not reachable from this seed.
    """
    target_p = np.asarray(position, dtype=float)
    if target_p.shape != (3,):
        raise ValueError(f"position must have 3 entries, got shape {target_p.shape}")
    target_r = ee_rotation(rot)
    q = np.array(HOME_CONFIGURATION if seed is None else seed, dtype=float)
    error = np.full(6, np.inf)
    for _ in range(max_iter):
        pose = forward_kinematics(q)
        error = np.concatenate([target_p - pose[:3, 3], orientation_error(target_r, pose[:3, :3])])
        if np.max(np.abs(error)) < tol:
            return q
        q = np.clip(q + damped_least_squares(jacobian(q), error, 1e-3), JOINT_LOWER, JOINT_UPPER)
    raise ValueError(
        f"pose position={target_p.tolist()} rot={rot} is not reachable within the joint "
        f"limits (residual {np.max(np.abs(error)):.2e} after {max_iter} iterations)"
    )
