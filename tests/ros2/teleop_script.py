"""A scripted operator over DDS: holds the keys toward a goal, as a Twist on cmd_vel.

``python teleop_script.py X Y Z SECONDS``: reads joint_states, computes the tool's
position (the arm's kinematics), publishes at 20 Hz the Twist of the keys a
:class:`~casa_core.study.key_sources.WaypointKeys` expert holds toward ``[X, Y, Z]``,
then a zero Twist once there, for SECONDS.
"""

from __future__ import annotations

import sys
import time

import rclpy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import JointState

from casa_core.robot import kinematics as kin
from casa_core.robot.keys import keys_to_action
from casa_core.ros2.messages import joint_positions
from casa_core.study.key_sources import WaypointKeys


def main() -> None:
    x, y, z, seconds = (float(v) for v in sys.argv[1:5])
    rclpy.init()
    node = rclpy.create_node("scripted_teleop")
    publisher = node.create_publisher(Twist, "cmd_vel", 1)
    pose = {}
    node.create_subscription(
        JointState,
        "joint_states",
        lambda m: pose.update(q=joint_positions(m.name, m.position)),
        1,
    )
    # rot is not part of this goal: a tolerance no rotation reaches.
    expert = WaypointKeys([[x, y, z, 0.0]], rot_tolerance=1e9)
    end = time.monotonic() + seconds
    next_tick = time.monotonic()
    while time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=max(next_tick - time.monotonic(), 0.0))
        if time.monotonic() < next_tick or "q" not in pose:
            continue
        next_tick += 0.05
        frame = kin.forward_kinematics(pose["q"])
        state = [*frame[:3, 3].tolist(), 0.0]
        action = keys_to_action(expert.keys(0.0, state))
        message = Twist()
        message.linear.x, message.linear.y, message.linear.z = action[:3].tolist()
        message.angular.z = float(action[3])
        publisher.publish(message)
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    main()
