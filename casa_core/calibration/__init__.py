"""`casa calibrate`: the simulated operators fitted to people by simulation-based inference.

- :mod:`~casa_core.calibration.summaries`: the summaries of a trial, and per cell;
- :mod:`~casa_core.calibration.design`: a dataset's human trials, what to simulate;
- :mod:`~casa_core.calibration.simulator`: the design run by candidate operators in pybullet;
- :mod:`~casa_core.calibration.fit`: the prior and sbi's neural posterior estimation;
- :mod:`~casa_core.calibration.calibrate`: the fit, the population and the predictive table;
- :mod:`~casa_core.calibration.checks`: parameter recovery and the hold-out check.
"""
