"""The ROS 2 nodes: the simulated arm and the assistant behind the topics (needs rclpy).

Both run a control loop of their own at :data:`~casa_core.ros2.messages.CONTROL_RATE`
(20 Hz): they spin the node until the next tick's deadline; callbacks store the newest
message (and when it arrived, on this machine's monotonic clock, so that a remote
publisher's clock never makes a message look fresh) and the tick does the work. The
assistant's user-command callback also answers the command at once
(:meth:`~casa_core.ros2.loop.AssistLoop.respond`), so that it acts without waiting for
the tick. Inputs, outputs and the stated ages are ROS parameters
(:mod:`casa_core.ros2.parameters`). The conversions and checks are
:mod:`casa_core.ros2.messages`; the assistant's tick is
:class:`casa_core.ros2.loop.AssistLoop`.

QoS (``docs/ros2.md``): subscriptions are best effort, keep last 1, so that they match
reliable and best-effort publishers alike and only the newest message waits; commands
and state are published reliable, keep last 1 (what a ros2_control controller's
subscription asks for); the trial's metadata is reliable and transient local, so that
``ros2 bag record`` started late still gets it.
"""

from __future__ import annotations

import json
import signal
import time
from collections.abc import Callable, Sequence

import numpy as np
import rclpy
from geometry_msgs.msg import Twist, TwistStamped
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.exceptions import InvalidParameterTypeException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import JointState, Joy
from std_msgs.msg import Float64MultiArray, String

from casa_core.robot.kinematics import JOINT_MAX_SPEED
from casa_core.robot.sim import ArmSimulation
from casa_core.ros2.loop import AssistLoop, Command
from casa_core.ros2.messages import (
    JOINT_COMMANDS_TOPIC,
    JOINT_NAMES,
    JOINT_STATES_TOPIC,
    JOY_TOPIC,
    MAX_COMMAND_AGE,
    STATE_TOPIC,
    TRIAL_TOPIC,
    TWIST_OUTPUT_TOPIC,
    USER_COMMAND_TOPIC,
    MessageError,
    joint_command,
    joint_positions,
    joy_action,
    user_action,
)
from casa_core.ros2.parameters import PARAMETERS, NodeParameters, ParameterError, node_parameters
from casa_core.ros2.stats import LoopStats

#: Subscriptions: the newest message only, from any publisher.
LATEST = QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.BEST_EFFORT
)
#: Commands and state.
COMMAND = QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE
)
#: The trial's metadata, for late joiners.
LATCHED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)


class Stop:
    """Set by SIGINT or SIGTERM: the loops end at their next tick and write what they have."""

    def __init__(self):
        self.requested = False
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, self._handle)

    def _handle(self, signum, frame) -> None:
        self.requested = True


def start(name: str, remaps: list[str], ros_args: Sequence[str] = ()) -> Node:
    """rclpy started with the remaps (``FROM:=TO``) and other ROS arguments (``-p``,
    ``--params-file``), our own signal handling, and a node."""
    args = ["casa", "--ros-args"] + [part for remap in remaps for part in ("-r", remap)]
    args += list(ros_args)
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    return Node(name)


def run_loop(node: Node, period: float, tick: Callable[[float], None], stop: Stop, until: float):
    """Call ``tick(now)`` every ``period`` s (monotonic) until ``stop`` or ``until``."""
    deadline = time.monotonic()
    while not stop.requested and time.monotonic() < until:
        rclpy.spin_once(node, timeout_sec=max(deadline - time.monotonic(), 0.0))
        now = time.monotonic()
        if now >= deadline:
            tick(now)
            deadline += period
            if deadline < now:  # a late tick is not made up: the next one is a period on
                deadline = now + period


def run_sim(scene, *, remaps: list[str], duration: float) -> int:
    """``casa ros2 sim``: the pybullet JACO as a joint velocity controlled arm."""
    node = start("casa_sim", remaps)
    stop = Stop()
    sim = ArmSimulation(scene)
    latest: dict = {"qdot": None, "time": None}
    holding = {"still": True}  # said once each time the commands stop

    def on_command(message: Float64MultiArray) -> None:
        try:
            # Within the joints' speed limits, as the arm's own controller would hold them.
            qdot = np.clip(joint_command(message.data), -JOINT_MAX_SPEED, JOINT_MAX_SPEED)
        except MessageError as error:
            node.get_logger().warning(
                f"{JOINT_COMMANDS_TOPIC}: refused a command: {error}; holding still"
            )
            latest.update(qdot=None, time=None)
            return
        latest.update(qdot=qdot, time=time.monotonic())

    node.create_subscription(Float64MultiArray, JOINT_COMMANDS_TOPIC, on_command, LATEST)
    publisher = node.create_publisher(JointState, JOINT_STATES_TOPIC, COMMAND)
    period = scene.teleop.dt

    def tick(now: float) -> None:
        fresh = latest["time"] is not None and now - latest["time"] <= MAX_COMMAND_AGE
        if not fresh and latest["time"] is not None and not holding["still"]:
            node.get_logger().warning(
                f"{JOINT_COMMANDS_TOPIC}: no command for {MAX_COMMAND_AGE} s: holding still"
            )
        holding["still"] = not fresh
        sim.step_joints(latest["qdot"] if fresh else np.zeros(len(JOINT_NAMES)))
        message = JointState()
        message.header.stamp = node.get_clock().now().to_msg()
        message.name = list(JOINT_NAMES)
        message.position = sim.q.tolist()
        publisher.publish(message)

    node.get_logger().info(
        f"simulated JACO: {JOINT_STATES_TOPIC} at {1 / period:g} Hz, commands on "
        f"{JOINT_COMMANDS_TOPIC}"
    )
    try:
        run_loop(node, period, tick, stop, time.monotonic() + duration)
    finally:
        sim.close()
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def run_assist(
    make_loop: Callable[[NodeParameters], AssistLoop],
    *,
    remaps: list[str],
    ros_args: list[str],
    duration: float,
    stats: LoopStats,
) -> AssistLoop:
    """``casa ros2 assist``: an :class:`AssistLoop` on the topics until ``duration`` or a signal.

    ``make_loop`` builds the loop from the node's parameters (:mod:`casa_core.ros2.parameters`,
    set by ``ros_args``: ``-p NAME:=VALUE``, ``--params-file FILE``); the loop is returned
    closed, with the trial it recorded. Each user command is answered on arrival
    (:meth:`AssistLoop.respond`); the 20 Hz tick records, infers and publishes the state.

    Raises
    ------
    ParameterError
        Naming a parameter whose value breaks its rule (nothing has been published).
    """
    node = start("casa_assist", remaps, ros_args)
    try:
        parameters = node_parameters(_declared(node))
        loop = make_loop(parameters)
    except BaseException:
        node.destroy_node()
        rclpy.try_shutdown()
        raise
    try:
        _assist(node, loop, parameters, duration, stats)
    finally:
        loop.close()
        node.destroy_node()
        rclpy.try_shutdown()
    return loop


def _declared(node: Node) -> dict:
    """The values of :data:`PARAMETERS` on ``node``, declared read-only with their defaults."""
    values = {}
    for name, (default, description) in PARAMETERS.items():
        descriptor = ParameterDescriptor(description=description, read_only=True)
        try:
            value = node.declare_parameter(name, default, descriptor).value
        except InvalidParameterTypeException as error:
            raise ParameterError(
                f"parameter {name}: the wrong type ({error}); the default is {default!r}"
            ) from None
        values[name] = value if isinstance(value, str | bool | int | float) else list(value)
    return values


def _assist(node: Node, loop: AssistLoop, parameters: NodeParameters, duration, stats) -> None:
    stop = Stop()
    logger = node.get_logger()
    loop.log = logger.warning
    inputs: dict = {"q": None, "q_time": None, "joint_fault": None}
    inputs |= {"action": None, "action_time": None, "user_fault": None}
    speed, rot_speed = loop.speed, loop.rot_speed
    send = _outputs(node, parameters)

    def on_joints(message: JointState) -> None:
        try:
            inputs.update(q=joint_positions(message.name, message.position))
            inputs.update(q_time=time.monotonic(), joint_fault=None)
        except MessageError as error:
            logger.warning(f"{JOINT_STATES_TOPIC}: refused a message: {error}")
            inputs["joint_fault"] = "joint-state-invalid"

    def on_user(topic: str, read: Callable[[], np.ndarray]) -> None:
        try:
            action = read()
        except MessageError as error:
            logger.warning(f"{topic}: refused a message: {error}")
            inputs["user_fault"] = "user-invalid"
            return
        arrived = time.monotonic()
        inputs.update(action=action, action_time=arrived, user_fault=None)
        stats.arrived(arrived)
        if inputs["joint_fault"] is None:
            command = loop.respond(arrived, inputs["q"], inputs["q_time"], action)
            if command is not None:
                send(command)
                stats.published(time.monotonic(), used=arrived)

    user_topic = _user_input(node, parameters, on_user, speed, rot_speed)
    node.create_subscription(JointState, JOINT_STATES_TOPIC, on_joints, LATEST)
    states = node.create_publisher(String, STATE_TOPIC, COMMAND)
    trial = node.create_publisher(String, TRIAL_TOPIC, LATCHED)
    trial.publish(String(data=json.dumps(loop.meta, sort_keys=True)))

    def tick(now: float) -> None:
        result = loop.step(now, **inputs)
        send(result.command)
        states.publish(String(data=result.state_text))
        stats.ticked(now, time.monotonic(), used=inputs["action_time"])

    outputs = [JOINT_COMMANDS_TOPIC] if parameters.joint_output else []
    outputs += [TWIST_OUTPUT_TOPIC] if parameters.twist_output else []
    logger.info(
        f"assisting ({loop.meta['task']}, {loop.meta['method']}): {JOINT_STATES_TOPIC} and "
        f"{user_topic} ({parameters.user_input}) in, {', '.join(outputs)} and {STATE_TOPIC} out"
    )
    run_loop(node, loop.scene.teleop.dt, tick, stop, time.monotonic() + duration)
    send(None)  # leave the arm still


def _user_input(node, parameters: NodeParameters, on_user, speed, rot_speed) -> str:
    """Subscribe to the user's command of the ``user_input`` parameter; return its topic."""
    if parameters.user_input == "joy":

        def on_joy(message: Joy) -> None:
            on_user(
                JOY_TOPIC,
                lambda: joy_action(
                    message.axes,
                    message.buttons,
                    axis_map=parameters.joy_axes,
                    scales=parameters.joy_scales,
                    enable_button=parameters.joy_enable_button,
                    speed=speed,
                    rot_speed=rot_speed,
                ),
            )

        node.create_subscription(Joy, JOY_TOPIC, on_joy, LATEST)
        return JOY_TOPIC
    stamped = parameters.user_input == "twist_stamped"

    def on_twist(message) -> None:
        twist = message.twist if stamped else message
        linear = (twist.linear.x, twist.linear.y, twist.linear.z)
        on_user(USER_COMMAND_TOPIC, lambda: user_action(linear, twist.angular.z, speed, rot_speed))

    kind = TwistStamped if stamped else Twist
    node.create_subscription(kind, USER_COMMAND_TOPIC, on_twist, LATEST)
    return USER_COMMAND_TOPIC


def _outputs(node: Node, parameters: NodeParameters) -> Callable[[Command | None], None]:
    """``send(command)``: publish a command on the outputs the parameters ask for (None: stop)."""
    joints = twist = None
    if parameters.joint_output:
        joints = node.create_publisher(Float64MultiArray, JOINT_COMMANDS_TOPIC, COMMAND)
    if parameters.twist_output:
        twist = node.create_publisher(TwistStamped, TWIST_OUTPUT_TOPIC, COMMAND)

    def send(command: Command | None) -> None:
        qdot = command.qdot if command is not None else np.zeros(len(JOINT_NAMES))
        blended = command.blended if command is not None else np.zeros(4)
        if joints is not None:
            joints.publish(Float64MultiArray(data=qdot.tolist()))
        if twist is not None:
            message = TwistStamped()
            message.header.stamp = node.get_clock().now().to_msg()
            message.header.frame_id = parameters.twist_output_frame
            vx, vy, vz, vrot = (float(v) for v in blended)
            message.twist.linear.x, message.twist.linear.y, message.twist.linear.z = vx, vy, vz
            message.twist.angular.z = vrot  # the wrist turn: about the tool's axis
            twist.publish(message)

    return send
