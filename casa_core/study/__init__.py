"""The study: who holds the keys, the closed loop, the protocol and the simulated study.

- :mod:`~casa_core.study.participants`, :mod:`~casa_core.study.arm_estimate`: simulated
  participants (operator models) and the predictive operator's estimate of the arm;
  :mod:`~casa_core.study.operator_params`: their parameters, drawn from the population;
- :mod:`~casa_core.study.key_sources`: scripted key sources and their protocol;
  :mod:`~casa_core.study.command_sources`: a continuous device's commanded velocity in
  their place (a gamepad, a SpaceMouse, a script);
- :mod:`~casa_core.study.closed_loop`: one trial, pybullet in the loop;
  :mod:`~casa_core.study.drive`: how a tick's keys and the robot's action move the arm, per
  teleoperation mode;
- :mod:`~casa_core.study.teleop_session`: a person's session at the window (``casa teleop``);
- :mod:`~casa_core.study.protocol`: the trials in order, counterbalancing, misspecification;
- :mod:`~casa_core.study.session`: a participant's whole study (``casa session``), its
  steps and where to resume; :mod:`~casa_core.study.session_texts`: what its window says;
  :mod:`~casa_core.study.session_run`: its loop, each step recorded when done;
- :mod:`~casa_core.study.simulate`: the simulated study and the expert case study;
- :mod:`~casa_core.study.settings`: what they read from the config, read once at the edge;
- :mod:`~casa_core.study.learn_from_logs`: demonstration logs in, an intent file out;
- :mod:`~casa_core.study.learning_evidence`: what the learner sees and how it is judged;
- :mod:`~casa_core.study.likert`: the simulated Likert answers;
- :mod:`~casa_core.study.arbitration_comparison`: the three arbitrations along one path.
"""
