"""The simulated Kinova JACO 7-DoF arm (j2s7s300) in pybullet, and its windows.

The robot knows nothing of learning or the study. The modules, each with one job:

- :mod:`~casa_core.robot.kinematics`: forward and inverse kinematics, the end effector's
  orientation, in numpy (the arm's model is ``j2s7s300.urdf`` beside it);
- :mod:`~casa_core.robot.sim`: the arm in pybullet under a 20 Hz Cartesian velocity
  controller; :mod:`~casa_core.robot.control_kernel`: that controller's tick, compiled;
- :mod:`~casa_core.robot.scene`: the scene's bodies (goals, cup, bowl) in pybullet;
- :mod:`~casa_core.robot.keys`: the keyboard map, held keys to a Cartesian velocity;
- :mod:`~casa_core.robot.original_teleop`: the original implementation's teleoperation,
  held keys to joint velocities through inverse kinematics of link 7's position;
- :mod:`~casa_core.robot.teleop`: the teleoperation window and its keyboard;
- :mod:`~casa_core.robot.screens`: the window of ``casa session``, screen by screen;
- :mod:`~casa_core.robot.render`: the scene rendered for ``figures/scene.png``;
- :mod:`~casa_core.robot.camera`: where the window and the scene figure look;
- :mod:`~casa_core.robot.devices`: a gamepad or a SpaceMouse read as the keyboard's
  ``[x, y, z, rot]``, or a recorded trace of one.
"""
