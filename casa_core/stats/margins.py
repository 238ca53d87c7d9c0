"""Non-inferiority margins: what the config's ``statistics`` section and ``casa stats`` give.

A margin is either absolute (in the metric's unit) or a fraction of the reference
condition's mean in the compared cells (for metrics whose unit the paper does not give);
either may be set for every task or per task. Beside them, the one-sided level of the
non-inferiority tests (the paper's 0.05; 0.025, a two-sided 95 % interval, is CONSORT's
and the EMA's and FDA's). The values and their sources are in
casa_core/config.schema.yaml (``statistics``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

#: The paper's one-sided level of non-inferiority (its one-sided 95 % bounds).
PAPER_ALPHA = 0.05


def _flat(values: Mapping, what: str) -> dict[str, float]:
    """``{metric: number | {task: number}}`` as ``{"metric" | "task:metric": number}``."""
    out: dict[str, float] = {}
    for metric, value in (values or {}).items():
        if value is None:
            continue  # no margin for this metric
        per_task = value if isinstance(value, Mapping) else {None: value}
        for task, number in per_task.items():
            key = str(metric) if task is None else f"{task}:{metric}"
            if isinstance(number, bool) or not isinstance(number, int | float):
                raise ValueError(f"{what}: {key}: {number!r} is not a number")
            if not (np.isfinite(number) and number > 0):
                raise ValueError(f"{what}: {key}: a margin must be a positive number, got {number}")
            out[key] = float(number)
    return out


@dataclass(frozen=True)
class Margins:
    """Margins keyed ``"metric"`` (every task) or ``"task:metric"`` (one task; it wins).

    Examples
    --------
    >>> margins = Margins.from_config({
    ...     "noninferiority_margins": {"relative_effort": {"known_goal": 0.065}},
    ...     "noninferiority_fractions": {"error": 0.05}})
    >>> margins.absolute_for("known_goal", "relative_effort"), margins.fraction_for("x", "error")
    (0.065, 0.05)
    >>> margins.absolute_for("unknown_goal", "relative_effort") is None
    True
    >>> margins.alpha
    0.05
    """

    absolute: Mapping[str, float] = field(default_factory=dict)
    fractions: Mapping[str, float] = field(default_factory=dict)
    #: The one-sided level of the non-inferiority tests (``noninferiority_alpha``).
    alpha: float = PAPER_ALPHA

    def __post_init__(self) -> None:
        alpha = self.alpha
        if isinstance(alpha, bool) or not isinstance(alpha, int | float) or not 0 < alpha < 0.5:
            raise ValueError(f"noninferiority_alpha: a level in (0, 0.5), got {alpha!r}")

    @classmethod
    def from_config(cls, statistics: Mapping | None) -> Margins:
        """From the config's ``statistics`` section (margins and level; others ignored)."""
        statistics = statistics or {}
        return cls(
            absolute=_flat(statistics.get("noninferiority_margins", {}), "noninferiority_margins"),
            fractions=_flat(
                statistics.get("noninferiority_fractions", {}), "noninferiority_fractions"
            ),
            alpha=statistics.get("noninferiority_alpha", PAPER_ALPHA),
        )

    def options(self) -> list[str]:
        """The margins and level as ``casa stats`` options (``--margin``,
        ``--margin-fraction``, ``--noninferiority-alpha``).

        Examples
        --------
        >>> margins = Margins(absolute={"known_goal:error": 0.5}, fractions={"efficiency": 0.1})
        >>> print(" ".join(margins.options()))
        --margin known_goal:error=0.5 --margin-fraction efficiency=0.1 --noninferiority-alpha 0.05
        """
        return (
            [f"--margin {key}={value!r}" for key, value in self.absolute.items()]
            + [f"--margin-fraction {key}={value!r}" for key, value in self.fractions.items()]
            + [f"--noninferiority-alpha {self.alpha!r}"]
        )

    def absolute_for(self, task: str, metric: str) -> float | None:
        return self.absolute.get(f"{task}:{metric}", self.absolute.get(metric))

    def fraction_for(self, task: str, metric: str) -> float | None:
        return self.fractions.get(f"{task}:{metric}", self.fractions.get(metric))

    def margin_in(self, data, task: str, metric: str, reference: str) -> tuple[float | None, str]:
        """The margin for ``task`` and ``metric`` in the compared cells ``data`` (columns
        ``method`` and ``metric``) and how it was set, for a note: a fraction's margin is
        that fraction of the mean of ``reference``'s cells (None if that mean is not
        positive)."""
        absolute = self.absolute_for(task, metric)
        if absolute is not None:
            return absolute, ""
        fraction = self.fraction_for(task, metric)
        cells = data.loc[data["method"] == reference, metric]
        if fraction is None or cells.empty or not np.isfinite(cells.mean()) or cells.mean() <= 0:
            return None, ""
        margin = fraction * float(cells.mean())
        return margin, f"margin {fraction:g} x mean({reference}) = {margin:.4g}"


def parse_margin(text: str, what: str = "--margin") -> tuple[str, float]:
    """``"metric=value"`` or ``"task:metric=value"`` as ``(key, value)``, or a clear error.

    Examples
    --------
    >>> parse_margin("known_goal:relative_effort=0.065")
    ('known_goal:relative_effort', 0.065)
    """
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise ValueError(f"{what} {text!r}: expected METRIC=VALUE or TASK:METRIC=VALUE")
    try:
        number = float(value)
    except ValueError:
        raise ValueError(f"{what} {text!r}: {value!r} is not a number") from None
    if not (np.isfinite(number) and number > 0):
        raise ValueError(f"{what} {text!r}: a margin must be a positive number")
    return key, number


__all__ = ["PAPER_ALPHA", "Margins", "parse_margin"]
