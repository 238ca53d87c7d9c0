"""The verdict of a hypothesis (H1-H4 of :mod:`casa_core.stats.claims`) from its checks.

The checks come from :mod:`casa_core.stats._claim_tests`; :func:`judge_checks` gives the
criterion, the numbers, the verdict, its cause (:mod:`casa_core.stats.causes`) and the
verdict of each form on its own.
"""

from __future__ import annotations

import numpy as np

from casa_core.stats import _claim_tests as tests
from casa_core.stats import causes
from casa_core.stats.verdicts import PARTLY_SHARE, TOO_FEW, too_few


def _requirements(checks: list[tests.Check]) -> str:
    """What the checks ask, each once, in the paper's direction (lower is better)."""
    metrics = ", ".join(dict.fromkeys(check.metric for check in checks if check.metric))
    asked = "; ".join(dict.fromkeys(check.requirement for check in checks if check.requirement))
    if not asked:
        return ""
    # The hypotheses' "more accurate, efficient, and effortless": lower is better.
    return (
        f"on each of {metrics} (lower is better), in the paper's form and in the "
        f"within-subjects form: {asked}. "
    )


def _not_passed(checks: list[tests.Check]) -> str:
    """Why the checks that did not pass did not, counted by reason: ``failed: 2 ...``."""
    said = []
    for outcome, name in ((False, "failed"), (None, "undecided")):
        reasons = [check.reason or "no reason given" for check in checks if check.passed is outcome]
        counts = {reason: reasons.count(reason) for reason in dict.fromkeys(reasons)}
        if counts:
            said.append(f"{name}: " + "; ".join(f"{n} {reason}" for reason, n in counts.items()))
    return "; ".join(said)


def judge_checks(checks: list[tests.Check], participants: int) -> dict:
    """H1-H3 from their checks: every check of both forms passes (holds), at least half do
    (partly); the cause of another verdict (``participants``: the dataset's).

    Returns the row's ``criterion, measured, value, verdict, details, cause`` and, when
    both forms have checks, ``by_form``.

    >>> row = judge_checks([tests.Check(True, "error (paper): pass", form="paper")], 11)
    >>> row["verdict"], row["value"], row["measured"]
    ('holds', 1.0, '1 of 1 checks passed (1 decided)')
    """
    criterion = (
        f"{_requirements(checks)}holds: every check below testable and passed; partly: at least "
        f"{PARTLY_SHARE:.0%} of the checks passed; differs: fewer; not testable: too few "
        "participants when a check's test was not computed for want of participants"
    )
    details = "\n".join(check.text for check in checks)
    share, verdict = checks_verdict(checks)
    if verdict == "not testable":
        measured = "no check could be decided" if checks else "no checks"
    else:
        testable = sum(check.passed is not None for check in checks)
        passed = sum(bool(check.passed) for check in checks)
        measured = f"{passed} of {len(checks)} checks passed ({testable} decided)"
    why = _not_passed(checks)
    measured += f"; {why}" if why else ""
    cause = ""
    if verdict.startswith(TOO_FEW):
        cause = causes.too_few_cause(checks)
    elif verdict in ("partly", "differs"):
        cause = causes.hypothesis_cause(checks, participants, tests.OPPOSITE)
    row = dict(criterion=criterion, measured=measured, value=share, verdict=verdict)
    row |= dict(details=details, cause=cause if verdict != "holds" else "")
    forms = {form: [check for check in checks if check.form == form] for form in FORM_NAMES}
    if all(forms.values()):
        row["by_form"] = "; ".join(
            f"{FORM_NAMES[form]}: {checks_verdict(mine)[1]}" for form, mine in forms.items()
        )
    return row


#: The names of the two forms of the checks of H1-H3 (:data:`_claim_tests.FORMS`).
FORM_NAMES = dict(zip(tests.FORMS, ("paper form", "within subjects"), strict=True))


def checks_verdict(checks: list[tests.Check]) -> tuple[float, str]:
    """The share of checks passed and the verdict: holds when all pass, partly when at
    least :data:`PARTLY_SHARE` do; not testable when none is decided, and
    :func:`too_few` when a check is undecided because a test it needs was not computed
    for too few participants (holds asks every check to be decided, so the verdict
    waits for the participants the test needs).

    >>> waiting = tests.Check(None, "error (within): undecided", shortfall=(2, 3))
    >>> checks_verdict([tests.Check(False, "a"), waiting])
    (nan, 'not testable: too few participants (2, needs 3)')
    """
    shortfalls = [check.shortfall for check in checks if check.passed is None and check.shortfall]
    if shortfalls:
        got = min(got for got, _ in shortfalls)
        return np.nan, too_few(got, max(needed for _, needed in shortfalls))
    if not any(check.passed is not None for check in checks):
        return np.nan, "not testable"
    share = sum(bool(check.passed) for check in checks) / len(checks)
    if share == 1.0:
        return share, "holds"
    return share, "partly" if share >= PARTLY_SHARE else "differs"
