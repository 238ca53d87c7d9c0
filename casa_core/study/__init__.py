"""The study: who holds the keys, the closed loop, the protocol and the simulated study.

- :mod:`~casa_core.study.key_sources`: scripted key sources and their protocol;
- :mod:`~casa_core.study.participants`: simulated participants (operator models);
- :mod:`~casa_core.study.closed_loop`: one trial, pybullet in the loop;
- :mod:`~casa_core.study.teleop_session`: a person's session at the window (``casa teleop``);
- :mod:`~casa_core.study.protocol`: the trials in order, counterbalancing, misspecification;
- :mod:`~casa_core.study.simulate`: the simulated study and the expert case study;
- :mod:`~casa_core.study.learning_evidence`: what the learner sees and how it is judged;
- :mod:`~casa_core.study.likert`: the simulated Likert answers;
- :mod:`~casa_core.study.arbitration_comparison`: the three arbitrations along one path.
"""
