"""Kinematics of the JACO model: our numpy FK against pybullet's, the EE orientation, IK.

Expected values come from pybullet's own forward kinematics and Jacobian of our URDF
(an independent implementation of the same joint chain), from finite differences,
and from the definitions in ``casa_core.robot.kinematics`` (orthonormal frames,
the cup upright at rot = 0).
"""

import xml.etree.ElementTree as ET

import numpy as np
import pybullet as p
import pytest

from casa_core.robot import kinematics as kin
from casa_core.robot.sim import TOOL_LINK, URDF_PATH
from casa_core.scene import load_scene


@pytest.fixture(scope="module")
def bullet():
    client = p.connect(p.DIRECT)
    robot = p.loadURDF(str(URDF_PATH), useFixedBase=True, physicsClientId=client)
    yield client, robot
    p.disconnect(client)


def _random_configurations(n, seed):
    rng = np.random.default_rng(seed)
    low = np.where(np.isfinite(kin.JOINT_LOWER), kin.JOINT_LOWER, -np.pi)
    high = np.where(np.isfinite(kin.JOINT_UPPER), kin.JOINT_UPPER, np.pi)
    return rng.uniform(low, high, size=(n, kin.N_JOINTS))


def _set(bullet, q):
    client, robot = bullet
    for joint, angle in enumerate(q):
        p.resetJointState(robot, joint, angle, physicsClientId=client)


def test_forward_kinematics_matches_pybullet_for_random_configurations(bullet):
    client, robot = bullet
    for q in _random_configurations(50, seed=1):
        _set(bullet, q)
        link = p.getLinkState(
            robot, TOOL_LINK, computeForwardKinematics=True, physicsClientId=client
        )
        pose = kin.forward_kinematics(q)
        np.testing.assert_allclose(pose[:3, 3], link[4], atol=1e-6)
        rotation = np.array(p.getMatrixFromQuaternion(link[5])).reshape(3, 3)
        np.testing.assert_allclose(pose[:3, :3], rotation, atol=1e-6)


def test_jacobian_matches_pybullet_and_finite_differences(bullet):
    client, robot = bullet
    zeros = [0.0] * kin.N_JOINTS
    for q in _random_configurations(10, seed=2):
        _set(bullet, q)
        linear, angular = p.calculateJacobian(
            robot, TOOL_LINK, [0, 0, 0], q.tolist(), zeros, zeros, physicsClientId=client
        )
        jac = kin.jacobian(q)
        np.testing.assert_allclose(jac, np.vstack([linear, angular]), atol=1e-6)
        # Linear rows: central differences of the FK position.
        h = 1e-6
        numeric = np.column_stack(
            [
                (
                    kin.forward_kinematics(q + h * e)[:3, 3]
                    - kin.forward_kinematics(q - h * e)[:3, 3]
                )
                / (2 * h)
                for e in np.eye(kin.N_JOINTS)
            ]
        )
        np.testing.assert_allclose(jac[:3], numeric, atol=1e-6)


def test_urdf_joints_follow_the_notes_table_and_kinova_limits():
    root = ET.parse(URDF_PATH).getroot()
    joints = [j for j in root.findall("joint") if j.get("name").startswith("joint_")]
    arm = [j for j in joints if j.get("type") in ("revolute", "continuous")]
    assert len(arm) == 7
    for i, joint in enumerate(arm):
        xyz = [float(v) for v in joint.find("origin").get("xyz").split()]
        rpy = [float(v) for v in joint.find("origin").get("rpy").split()]
        np.testing.assert_allclose(xyz, kin.JOINT_ORIGINS[i][0], atol=1e-9)
        np.testing.assert_allclose(rpy, kin.JOINT_ORIGINS[i][1], atol=1e-8)
        assert joint.find("axis").get("xyz") == "0 0 1"
        limit = joint.find("limit")
        if np.isfinite(kin.JOINT_LOWER[i]):
            assert joint.get("type") == "revolute"
            assert float(limit.get("lower")) == pytest.approx(kin.JOINT_LOWER[i])
            assert float(limit.get("upper")) == pytest.approx(kin.JOINT_UPPER[i])
        else:
            assert joint.get("type") == "continuous"
    # Kinova's j2s7s300 limits, in degrees: 47-313 (joint 2), 30-330 (4), 65-295 (6).
    np.testing.assert_allclose(np.degrees(kin.JOINT_LOWER[[1, 3, 5]]), [47, 30, 65], atol=1e-3)
    np.testing.assert_allclose(np.degrees(kin.JOINT_UPPER[[1, 3, 5]]), [313, 330, 295], atol=1e-3)
    links = {link.get("name") for link in root.findall("link")}
    assert {"tool", "cup"} <= links


@pytest.mark.parametrize("rot", [-2.0, -0.3, 0.0, 0.7, 1.8, 3.0])
def test_ee_rotation_is_a_rotation_and_rot_of_inverts_it(rot):
    rotation = kin.ee_rotation(rot)
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    assert kin.rot_of(rotation) == pytest.approx(rot)
    # The last joint's axis (tool z) stays horizontal whatever rot: turning it pours.
    assert rotation[2, 2] == pytest.approx(0.0, abs=1e-12)
    # Cup axis (tool x) against world up: cos(rot) by construction.
    assert rotation[2, 0] == pytest.approx(np.cos(rot))


def test_cup_is_upright_at_rot_zero():
    rotation = kin.ee_rotation(0.0)
    np.testing.assert_allclose(rotation[:, 0], [0, 0, 1], atol=1e-12)
    # The original's "cup upright" feature, 1 - (tool x . world z), is 0.
    assert 1 - rotation[:, 0] @ [0, 0, 1] == pytest.approx(0.0)


def test_orientation_error_recovers_a_small_rotation():
    current = kin.ee_rotation(0.4)
    w = np.array([0.01, -0.02, 0.005])
    angle = np.linalg.norm(w)
    k = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]) / angle
    turn = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k  # Rodrigues
    # The skew part of the relative rotation is sin(angle) times its unit axis (Rodrigues).
    expected = np.sin(angle) * w / angle
    np.testing.assert_allclose(kin.orientation_error(turn @ current, current), expected, atol=1e-12)


def test_inverse_kinematics_round_trip_and_unreachable_pose():
    position, rot = np.array([0.5, 0.1, 0.3]), 0.6
    q = kin.inverse_kinematics(position, rot)
    pose = kin.forward_kinematics(q)
    np.testing.assert_allclose(pose[:3, 3], position, atol=1e-6)
    np.testing.assert_allclose(pose[:3, :3], kin.ee_rotation(rot), atol=1e-5)
    assert kin.within_limits(q)
    with pytest.raises(ValueError, match="not reachable"):
        kin.inverse_kinematics([2.0, 0.0, 0.3], 0.0, max_iter=50)  # 2 m: beyond the arm
    with pytest.raises(ValueError, match="shape"):
        kin.forward_kinematics(np.zeros(6))


def test_scene_positions_have_an_inverse_kinematics_solution():
    scene = load_scene()
    poses = [(scene.start.position, scene.start.rot)]
    poses += [(goal, 0.0) for goal in scene.goals.values()]
    poses += [(scene.pouring.position, 0.0)]
    poses += [(scene.pouring.position, scene.pouring.tilt)]
    for position, rot in poses:
        q = kin.inverse_kinematics(position, rot)
        np.testing.assert_allclose(kin.forward_kinematics(q)[:3, 3], position, atol=1e-5)


# The original implementation's four reference configurations (degrees) and the link-7
# positions (m) its JACO description gives them, as read from its code and sessions.
ORIGINAL_REFERENCE_POSES = {
    "start": ([180, 175, 180, 300, 180, 180, 190], (-0.376, 0.010, 0.446)),
    "goal 0": ([150, 130, 160, 240, 180, 172, 280], (-0.548, -0.444, 0.424)),
    "goal 1": ([210, 130, 200, 240, 180, 172, 280], (-0.534, 0.458, 0.430)),
    "unknown goal": ([123, 155, 131, 284, 180, 176, 189], (0.043, -0.483, 0.447)),
}


@pytest.mark.parametrize("name", ORIGINAL_REFERENCE_POSES)
def test_original_reference_configurations_reach_their_link7_positions(name, bullet):
    degrees, expected = ORIGINAL_REFERENCE_POSES[name]
    q = np.radians(degrees)
    # The reference positions are given to 1 mm.
    np.testing.assert_allclose(kin.link7_position(q), expected, atol=1e-3)
    # pybullet's FK of our URDF puts link 7 (its link index 6) at the same point.
    _set(bullet, q)
    client, robot = bullet
    link7 = p.getLinkState(robot, 6, computeForwardKinematics=True, physicsClientId=client)[4]
    np.testing.assert_allclose(link7, expected, atol=1e-3)


def test_end_effector_is_the_tool_point_a_constant_offset_from_link7_while_teleoperating():
    # Our EE is 0.16 m from the link-7 origin along the tool's z axis, which teleoperation
    # holds at (1, 1, 0)/sqrt 2 whatever rot is.
    for rot in (0.0, 0.9, 1.8):
        q = kin.inverse_kinematics([0.45, -0.22, 0.38], rot)
        offset = kin.forward_kinematics(q)[:3, 3] - kin.link7_position(q)
        np.testing.assert_allclose(offset, 0.16 * np.array([1, 1, 0]) / np.sqrt(2), atol=1e-6)
