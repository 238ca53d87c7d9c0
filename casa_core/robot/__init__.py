"""The simulated Kinova JACO 7-DoF arm (j2s7s300) in pybullet.

``kinematics``: forward/inverse kinematics and the end-effector orientation in numpy;
``keys``: the 8-key keyboard map; ``scene``: table, goals and pouring target;
``sim``: the 20 Hz Cartesian controller with pybullet in the loop; ``teleop``: the
pybullet window and its keyboard. The robot knows nothing of learning or the study.
"""
