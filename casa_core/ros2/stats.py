"""How well a control loop held its rate, and how long a user command took to act.

:class:`LoopStats` is fed by the node (``casa ros2 assist``): each tick's start and
end, the arrival of each user command, and each command published between ticks in
answer to one. It reports the rate held, the tick period's spread, the tick's compute
time and the latency from a command's arrival to the first blended command that used it
(answered on arrival, or at the next tick when it could not be: then up to a period).

Examples
--------
>>> stats = LoopStats()
>>> stats.arrived(0.01)
>>> for i in range(3):
...     stats.ticked(0.05 * i, 0.05 * i + 0.002, used=0.01 if i else None)
>>> summary = stats.summary()
>>> summary["ticks"], round(summary["rate_hz"], 1), round(summary["latency_p99_ms"], 1)
(3, 20.0, 42.0)
>>> stats.arrived(0.11)
>>> stats.published(0.112, used=0.11)
>>> round(stats.summary()["latency_p50_ms"], 1), stats.summary()["answered_on_arrival"]
(22.0, 1)
"""

from __future__ import annotations

import numpy as np


class LoopStats:
    """Tick times and command latencies of one run of a control loop."""

    def __init__(self):
        self.starts: list[float] = []
        self.compute: list[float] = []
        self.latency: list[float] = []
        self._pending: float | None = None
        self.answered_on_arrival = 0

    def arrived(self, when: float) -> None:
        """A user command arrived at monotonic time ``when``."""
        if self._pending is None:
            self._pending = when

    def ticked(self, start: float, end: float, *, used: float | None) -> None:
        """A tick ran from ``start`` to ``end`` (published then), on the command of ``used``."""
        self.starts.append(start)
        self.compute.append(end - start)
        self._answered(end, used)

    def published(self, end: float, *, used: float) -> None:
        """Between ticks, a command computed from the user command of ``used`` went out."""
        if self._answered(end, used):
            self.answered_on_arrival += 1

    def _answered(self, end: float, used: float | None) -> bool:
        if self._pending is not None and used is not None and used >= self._pending:
            self.latency.append(end - self._pending)
            self._pending = None
            return True
        return False

    def summary(self) -> dict:
        """Ticks, rate (Hz), period p50/p99, compute p50/p99, latency p50/p99 (ms), and how
        many commands were answered on arrival."""
        out: dict = {"ticks": len(self.starts), "answered_on_arrival": self.answered_on_arrival}
        periods = np.diff(self.starts)
        if len(periods):
            out["rate_hz"] = float(1.0 / periods.mean())
        for name, values in (("period", periods), ("compute", self.compute)):
            if len(values):
                out[f"{name}_p50_ms"], out[f"{name}_p99_ms"] = (
                    float(v) * 1e3 for v in np.percentile(values, [50, 99])
                )
        if self.latency:
            out["latency_p50_ms"], out["latency_p99_ms"] = (
                float(v) * 1e3 for v in np.percentile(self.latency, [50, 99])
            )
        return out

    def text(self) -> str:
        """The summary in one line."""
        s = self.summary()
        parts = [f"{s['ticks']} ticks"]
        if "rate_hz" in s:
            parts.append(
                f"{s['rate_hz']:.2f} Hz (period p50 {s['period_p50_ms']:.1f} ms, "
                f"p99 {s['period_p99_ms']:.1f} ms)"
            )
        if "compute_p50_ms" in s:
            parts.append(
                f"tick compute p50 {s['compute_p50_ms']:.2f} ms, p99 {s['compute_p99_ms']:.2f} ms"
            )
        if "latency_p50_ms" in s:
            parts.append(
                f"command-to-output latency p50 {s['latency_p50_ms']:.1f} ms, "
                f"p99 {s['latency_p99_ms']:.1f} ms ({len(self.latency)} commands, "
                f"{s['answered_on_arrival']} answered on arrival)"
            )
        return "; ".join(parts)
