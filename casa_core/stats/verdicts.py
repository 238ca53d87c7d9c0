"""The verdicts of the paper's claims (:mod:`casa_core.stats.claims`) and their shares.

A verdict is one of :data:`VERDICTS`; :func:`too_few`'s names the participants too, and
:func:`verdict_kind` says which of :data:`VERDICTS` a verdict is (the robustness table and
figure, results.md).
"""

from __future__ import annotations

#: H4's verdict when the Likert answers are a model's output, whatever they show.
MODEL_OUTPUT = "not testable: model output"
#: A hypothesis' verdict when a test it needs was not computed for too few participants;
#: the verdict names the participants and the number needed (:func:`too_few`).
TOO_FEW = "not testable: too few participants"
VERDICTS = ("holds", "partly", "differs", "not testable", MODEL_OUTPUT, TOO_FEW)
#: A claim about every participant holds when it is seen in at least 90% of the trials:
#: one trial in 11 (the paper's participants) may miss it, two may not.
HOLDS_SHARE = 0.9
#: ... and partly when it is seen in at least half of them; below that it differs.
PARTLY_SHARE = 0.5


def too_few(got: int, needed: int) -> str:
    """The verdict of a hypothesis whose test needs ``needed`` participants, ``got`` given.

    >>> too_few(2, 3)
    'not testable: too few participants (2, needs 3)'
    """
    return f"{TOO_FEW} ({got}, needs {needed})"


def verdict_kind(verdict: str) -> str:
    """The member of :data:`VERDICTS` a verdict is: itself, or :data:`TOO_FEW` for
    :func:`too_few`'s; a ``ValueError`` names any other.

    >>> verdict_kind("not testable: too few participants (2, needs 3)")
    'not testable: too few participants'
    """
    if verdict in VERDICTS:
        return verdict
    if str(verdict).startswith(f"{TOO_FEW} ("):
        return TOO_FEW
    raise ValueError(f"unknown verdict {verdict!r}; expected one of {', '.join(VERDICTS)}")


def share_verdict(hits: int, total: int) -> str:
    """The verdict of a claim seen in ``hits`` of ``total`` trials or participant-tasks.

    >>> share_verdict(9, 10), share_verdict(5, 10), share_verdict(4, 10)
    ('holds', 'partly', 'differs')
    """
    share = hits / total
    return "holds" if share >= HOLDS_SHARE else "partly" if share >= PARTLY_SHARE else "differs"


__all__ = [
    "HOLDS_SHARE",
    "MODEL_OUTPUT",
    "PARTLY_SHARE",
    "TOO_FEW",
    "VERDICTS",
    "share_verdict",
    "too_few",
    "verdict_kind",
]
