"""A test's own node over DDS: the arm's joint states and the user's commands out, the
assistant's commands, twists and state in (needs rclpy)."""

from __future__ import annotations

import json
import time

import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from rclpy.executors import SingleThreadedExecutor
from sensor_msgs.msg import JointState, Joy
from std_msgs.msg import Float64MultiArray, String

from casa_core.ros2.messages import JOINT_NAMES


class Harness:
    """Publishes joint states and user commands (``user``: twist, twist_stamped or joy),
    and keeps what the assistant publishes: ``states``, ``commands``, ``twists``."""

    def __init__(self, env: dict, *, user: str = "twist"):
        self.context = rclpy.Context()
        rclpy.init(context=self.context, domain_id=int(env["ROS_DOMAIN_ID"]))
        self.node = rclpy.create_node("test_harness", context=self.context)
        self.joints = self.node.create_publisher(JointState, "joint_states", 1)
        self.kind = user
        kinds = {"twist": (Twist, "cmd_vel"), "twist_stamped": (TwistStamped, "cmd_vel")}
        kind, topic = kinds.get(user, (Joy, "joy"))
        self.user = self.node.create_publisher(kind, topic, 1)
        self.states: list[dict] = []
        self.commands: list[list[float]] = []
        self.twists: list[TwistStamped] = []
        self.node.create_subscription(
            String, "casa/state", lambda m: self.states.append(json.loads(m.data)), 10
        )
        self.node.create_subscription(
            Float64MultiArray,
            "velocity_controller/commands",
            lambda m: self.commands.append(list(m.data)),
            10,
        )
        self.node.create_subscription(
            TwistStamped, "servo_node/delta_twist_cmds", self.twists.append, 10
        )
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def run(
        self,
        seconds: float,
        *,
        names=JOINT_NAMES,
        positions=None,
        twist=(0.05, 0, 0, 0),
        joy=None,
    ):
        """Publish for ``seconds``: joint states at ``positions`` with ``names``, and the
        user's ``twist`` (``[vx, vy, vz, vrot]``) or ``joy`` (``(axes, buttons)``); None
        keeps that topic silent."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if positions is not None:
                message = JointState(name=list(names), position=list(positions))
                self.joints.publish(message)
            if self.kind == "joy" and joy is not None:
                axes, buttons = joy
                self.user.publish(Joy(axes=[float(v) for v in axes], buttons=list(buttons)))
            elif self.kind != "joy" and twist is not None:
                message = TwistStamped() if self.kind == "twist_stamped" else Twist()
                body = message.twist if self.kind == "twist_stamped" else message
                body.linear.x, body.linear.y, body.linear.z = (float(v) for v in twist[:3])
                body.angular.z = float(twist[3])
                self.user.publish(message)
            self.executor.spin_once(timeout_sec=0.05)

    def wait_until_assisting(self, positions, seconds: float = 30.0, **user) -> None:
        """Publish until the node says it assists (its start and DDS discovery)."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline and not (
            self.states and self.states[-1]["fault"] is None
        ):
            self.run(0.5, positions=positions, **user)
        assert self.states and self.states[-1]["fault"] is None, self.states[-3:]

    def close(self):
        self.node.destroy_node()
        rclpy.shutdown(context=self.context)
