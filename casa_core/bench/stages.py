"""``casa bench``: where a trial's and a protocol's CPU time goes.

:class:`StageClock` charges the CPU time of this process spent inside chosen functions
to named stages while it is active: it replaces each function, for the duration of a
``with`` block, by a wrapper that times the call, and puts the function back on leaving
(nothing of the package is changed outside the block). Two uses:

- ``pybullet``: every function of the ``pybullet`` module, so a trial's physics alone
  (stepping, inverse kinematics, Jacobians, link and joint reads, motor commands; the
  same calls the trial makes, in the same run) is measured beside the trial's whole
  cost. The ratio is ``trial_cost_over_physics``: 1 would be a trial that costs no more
  than its pybullet work.
- a protocol's stages: its trials (:func:`casa_core.study.closed_loop.simulated_trial`), its
  learning (:func:`casa_core.study.simulate.learn_from_demonstrations`) and its logging
  (the trial logs written, :func:`casa_core.study.simulate._write`); the rest is what
  the protocol's total leaves.

A stage entered while another is running is charged to the inner stage only, so the
stages never count a CPU second twice. Each timed call costs two clock reads; the clock
subtracts that overhead, measured on entry (:meth:`StageClock.overhead_ns`), from every
call it charges.
"""

from __future__ import annotations

import functools
import time
from collections import defaultdict
from collections.abc import Iterable

#: The protocol's stages: the module and function name of each, and the stage's name.
PROTOCOL_STAGES = (
    ("casa_core.study.simulate", "simulated_trial", "trials"),
    ("casa_core.study.simulate", "learn_from_demonstrations", "learning"),
    ("casa_core.study.simulate", "_write", "logging"),
)


class StageClock:
    """CPU seconds of this process spent in each stage while the clock is active.

    Parameters
    ----------
    stages : iterable of (module, name, stage)
        Each function ``module.name`` is charged to ``stage``. A module may be given as
        the module object or its import name.

    Attributes
    ----------
    seconds : dict
        CPU seconds per stage, accumulated over every ``with`` block.
    calls : dict
        Calls timed per stage.

    Examples
    --------
    >>> import math
    >>> sqrt = math.sqrt
    >>> clock = StageClock([(math, "sqrt", "roots")])
    >>> with clock:
    ...     _ = [math.sqrt(x) for x in range(1000)]
    >>> clock.calls["roots"], clock.seconds["roots"] >= 0.0
    (1000, True)
    >>> math.sqrt is sqrt  # put back on leaving
    True
    """

    def __init__(self, stages: Iterable[tuple]):
        self.stages = tuple(stages)
        self.seconds: dict[str, float] = defaultdict(float)
        self.calls: dict[str, int] = defaultdict(int)
        self._originals: list[tuple] = []
        self._running: list[str] = []
        self._overhead = 0

    @classmethod
    def pybullet(cls) -> StageClock:
        """A clock charging every function of the ``pybullet`` module to ``pybullet``."""
        import pybullet

        names = [name for name in dir(pybullet) if callable(getattr(pybullet, name))]
        return cls((pybullet, name, "pybullet") for name in names if not name[0].isupper())

    def __enter__(self) -> StageClock:
        import importlib

        self._overhead = self.overhead_ns()
        for module, name, stage in self.stages:
            module = importlib.import_module(module) if isinstance(module, str) else module
            original = getattr(module, name)
            self._originals.append((module, name, original))
            setattr(module, name, self._timed(original, stage))
        return self

    def __exit__(self, *exc) -> None:
        for module, name, original in reversed(self._originals):
            setattr(module, name, original)
        self._originals.clear()

    def _timed(self, function, stage: str):
        clock = time.process_time_ns

        @functools.wraps(function)
        def timed(*args, **kwargs):
            self._running.append(stage)
            began = clock()
            try:
                return function(*args, **kwargs)
            finally:
                spent = max(clock() - began - self._overhead, 0)
                self._running.pop()
                self.seconds[stage] += spent / 1e9
                self.calls[stage] += 1
                if self._running:
                    # Charged to the inner stage only: taken off the one running it.
                    self.seconds[self._running[-1]] -= spent / 1e9

        return timed

    @staticmethod
    def overhead_ns(repeats: int = 2000) -> int:
        """The median CPU nanoseconds two clock reads around nothing cost."""
        clock = time.process_time_ns
        spans = []
        for _ in range(repeats):
            began = clock()
            spans.append(clock() - began)
        spans.sort()
        return spans[len(spans) // 2]
