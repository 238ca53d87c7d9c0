"""Confidence-Aware Shared Autonomy (CASA).

The algorithm of Zurek, Bobu, Brown and Dragan, "Situational Confidence
Assistance for Lifelong Shared Autonomy" (ICRA 2021).  The modules
``confidence``, ``inference`` and ``arbitration`` hold the paper's equations
(numpy only); ``intents`` and ``assistant`` put them together.
"""

__version__ = "0.1.0"
