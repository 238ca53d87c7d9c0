"""What a check reports: a :class:`Problem` per broken rule, a :class:`LogError` listing them.

Examples
--------
>>> problem = Problem("t.csv", "column 'x', line 3", "finite-number", "got 'far'")
>>> print(LogError([problem]))
t.csv: column 'x', line 3: [finite-number] got 'far'
>>> print(Problem("t.csv", "column 't'", "tick-irregular", "steps vary", "warning"))
t.csv: column 't': warning [tick-irregular] steps vary
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True, order=True)
class Problem:
    """One way in which a file breaks the contract.

    Attributes
    ----------
    file : str
        The file, as given or found.
    where : str
        The key, column and/or line numbers (line 1 is the CSV header).
    rule : str
        A short name of the rule broken, e.g. ``"required-key"``.
    message : str
        What is wrong and what is expected.
    severity : str
        ``"error"`` (the file breaks the contract and is left out) or ``"warning"``
        (reported, the file is kept).

    Examples
    --------
    >>> print(Problem("t.json", "key 'task'", "required-key", "missing"))
    t.json: key 'task': [required-key] missing
    """

    file: str
    where: str
    rule: str
    message: str
    severity: str = "error"

    @property
    def is_error(self) -> bool:
        """True unless the problem is only a warning."""
        return self.severity != "warning"

    def __str__(self) -> str:
        where = f": {self.where}" if self.where else ""
        mark = "warning " if self.severity == "warning" else ""
        return f"{self.file}{where}: {mark}[{self.rule}] {self.message}"


def errors(problems: Sequence[Problem]) -> list[Problem]:
    """The problems that are errors (not warnings).

    Examples
    --------
    >>> found = [Problem("a", "", "x", "m"), Problem("a", "", "y", "m", "warning")]
    >>> [p.rule for p in errors(found)]
    ['x']
    """
    return [p for p in problems if p.is_error]


class LogError(ValueError):
    """Raised when a log breaks the contract; ``problems`` lists every problem found.

    Examples
    --------
    >>> error = LogError([Problem("a.csv", "", "non-empty", "no rows")])
    >>> str(error), len(error.problems)
    ('a.csv: [non-empty] no rows', 1)
    """

    def __init__(self, problems: Sequence[Problem]):
        self.problems = list(problems)
        super().__init__("\n".join(str(p) for p in self.problems))
