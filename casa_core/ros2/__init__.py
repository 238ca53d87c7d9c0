"""CASA on a robot over ROS 2: the nodes, their conversions, and rosbag2 import (docs/ros2.md).

Only :mod:`~casa_core.ros2.nodes` imports rclpy and the message packages (the ``ros2``
extra); the others are plain Python, so they run and are tested without DDS:

- :mod:`~casa_core.ros2.messages`: topic names and defaults, the stated ages, the checks
  and conversions of joint states, user commands and the assistant's state;
- :mod:`~casa_core.ros2.parameters`: the assistant node's ROS parameters (input device,
  outputs, stated ages), their defaults and rules;
- :mod:`~casa_core.ros2.loop`: the assistant's control tick on live inputs, with the
  fault rules, the answer to a command between ticks, and the trial it records;
- :mod:`~casa_core.ros2.stats`: the loop's rate and the command-to-output latency;
- :mod:`~casa_core.ros2.nodes`: ``casa ros2 sim`` and ``casa ros2 assist`` (rclpy);
- :mod:`~casa_core.ros2.bag`: a rosbag2 recording as a casa-trial/1 trial (``rosbags``).
"""
