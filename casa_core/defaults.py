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
