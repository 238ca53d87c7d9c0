"""The model's default settings, written once: each is the original implementation's.

The intents, the assistant, the planner, the keyboard, the simulated arm and the
protocol take their defaults from here, and the config schema's defaults equal these
(tested). Where each value comes from, and which setting restores another choice:
``docs/departures.md``; the symbols: ``docs/paper-to-code.md``.

Examples
--------
>>> HORIZON / DT + 1  # states of a full-horizon trajectory
31.0
"""

#: k, the action dimensionality: the JACO arm's 7 joint velocities.
K = 7
#: lambda, the rate of the exponential prior on beta.
LAM = 4.0
#: epsilon, the misspecification threshold on beta_hat (not in the original: related work's).
EPSILON = 1.0
#: D of distance arbitration (PBA), metres.
PBA_DISTANCE = 0.55
#: Factor on the suboptimality: the original implementation divides it by 1.8.
SUBOPT_SCALE = 1 / 1.8
#: T, the episode horizon, seconds.
HORIZON = 15.0
#: Seconds between inference steps and between trajectory states (inference twice a second).
DT = 0.5
#: End-effector speed of a Cartesian key, m/s; also the speed limit of optimal trajectories.
SPEED = 0.05
#: Rotation speed of a rotate key, rad/s; also the rotation limit of the robot's action u*.
ROT_SPEED = 0.5
#: The control tick, seconds (20 Hz).
TICK = 0.05
#: Cost per metre of end-effector path: the original implementation's 50 / 0.22 (227.27...).
COST_PER_METRE = 50 / 0.22
#: Demonstrations asked for each new intent (the paper's 5).
DEMONSTRATIONS = 5
#: How close (m) the last position must be to the intended trajectory's end for success:
#: 5 cm, the radius of the pouring target drawn in the scene, well inside the bowl's 7 cm
#: rim (a pour from there lands in the bowl), and far below the 22 cm between the two
#: nearest ends of different tasks (the green goal and the pouring position), so a
#: trial that stops at another task's end never succeeds.
SUCCESS_RADIUS = 0.05
#: How close (rad) the pour's last rotation must be to the intended tilt (scene
#: ``pouring.tilt``, 1.8 rad = 103 deg) for success: 0.2 rad keeps the cup past
#: horizontal (at least 1.6 rad = 92 deg), where it pours out.
POUR_TILT_TOLERANCE = 0.2
#: The significance level of every test the pipeline judges or marks: the paper tests every
#: hypothesis at .05.
SIGNIFICANCE = 0.05
