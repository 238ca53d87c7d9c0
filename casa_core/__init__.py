"""Confidence-Aware Shared Autonomy (CASA).

The algorithm of Zurek, Bobu, Brown and Dragan, "Situational Confidence Assistance
for Lifelong Shared Autonomy" (ICRA 2021), and its user study, simulated. The
modules: ``confidence``, ``inference`` and ``arbitration`` hold the paper's equations
(numpy only; ``_checks`` guards their arguments); ``intents`` are costs over
trajectories and ``assistant`` runs one assistance step over them; ``planning/``
optimizes trajectories in torch for intents without a closed form (``skills`` is the
pouring one, ``rotation`` the cup's orientation); ``learning/`` learns new intents by
deep maximum-entropy IRL and ``library`` stores them as files; ``robot/`` is the JACO
arm in pybullet; ``study/`` runs trials (key sources, the closed loop, the protocol,
the simulated study); ``io/`` holds the trial-log contract, its one reader and
writer, its validation and the one atomic writer; ``metrics`` and ``datasets``
turn logs into tables (``tasks``: what each task intends), which ``stats/`` and
``figures/`` take; the study's names are in ``vocabulary``, the task scene in
``scene``, the workflow config's loader in ``config``; ``bench`` times the package
and ``cli/`` is the ``casa`` command; ``numerics`` caps the libraries' CPU code paths
so results are the same on every x86-64 machine, and ``portable_math`` computes torch's
sin, cos, exp and sqrt past the one library that ignores those caps. Imports run one
way: equations <- intents, assistant <- planning <- learning <- study. The paper's
symbols are mapped to functions in docs/paper-to-code.md, our departures from it in
docs/departures.md.
"""

# Before numpy, torch or numba load: their code paths are chosen then (numerics.py).
from casa_core import numerics as _numerics

_numerics.pin_environment()

__version__ = "0.1.0"
