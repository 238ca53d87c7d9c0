"""The round trip from a user command to the assistant's output over DDS (docs/ros2.md).

``python -m tests.ros2.latency_probe [N]``: starts ``casa ros2 assist`` (NA, twist output
on) on a private domain, holds the arm's joint state, and N times (default 200) publishes
a Twist of the opposite sign to the last, at random intervals of 30-50 ms (seeded), and
times until the node's twist output has that sign. The time includes both DDS hops (to
the node and back) and this process's own executor, so it bounds the node's
command-to-output latency from above. Prints the p50, p99 and maximum, and the node's own
summary line. A measurement, not a test.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tests.ros2.ros_processes import casa, ros_env, stop


def main(n: int = 200) -> None:
    env = ros_env()
    for name in ("RMW_IMPLEMENTATION", "ROS_AUTOMATIC_DISCOVERY_RANGE"):
        os.environ[name] = env[name]
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import JointState

    from casa_core.robot import kinematics as kin
    from casa_core.ros2.messages import JOINT_NAMES
    from casa_core.scene import load_scene
    from tests.ros2.harness import Harness

    scene = load_scene()
    q = kin.inverse_kinematics(np.asarray(scene.start_state[:3]), scene.start_state[3])
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as folder:
        out, log = Path(folder) / "probe", Path(folder) / "assist.log"
        args = ["ros2", "assist", "--task", "known_goal", "--method", "NA", "--participant"]
        args += ["probe", "--out", str(out), "--duration", "60", "--param", "twist_output:=true"]
        assist = casa(args, env, log)
        harness = Harness(env)
        latencies = []
        try:
            harness.wait_until_assisting(q)
            sign = 1.0
            for _ in range(n):
                sign = -sign
                harness.joints.publish(JointState(name=list(JOINT_NAMES), position=list(q)))
                message = Twist()
                message.linear.x = 0.05 * sign
                seen = len(harness.twists)
                sent = time.monotonic()
                harness.user.publish(message)
                while time.monotonic() - sent < 0.2:
                    harness.executor.spin_once(timeout_sec=0.01)
                    if any(t.twist.linear.x * sign > 0 for t in harness.twists[seen:]):
                        latencies.append(time.monotonic() - sent)
                        break
                time.sleep(0.03 + 0.02 * rng.random())
        finally:
            harness.close()
            stop([assist])
        summary = [line for line in log.read_text().splitlines() if " Hz " in line]
    ms = np.array(latencies) * 1e3
    print(
        f"round trip, {len(ms)} of {n} commands seen: p50 {np.percentile(ms, 50):.2f} ms, "
        f"p99 {np.percentile(ms, 99):.2f} ms, max {ms.max():.2f} ms"
    )
    print(*summary, sep="\n")


if __name__ == "__main__":
    main(*(int(v) for v in sys.argv[1:2]))
