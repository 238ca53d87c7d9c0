"""Why a claim is not seen: one sentence computed from the tables, and where the docs discuss it.

:mod:`casa_core.stats.claims` gives each verdict other than ``holds`` a ``cause``: C2 names
the intent whose beta_hat rose above epsilon in the CASA trials before learning and for
how long; C3 the conditions of the arbitration comparison that were not met; C1 and C4
how the trials that miss the claim miss it; H1-H3 how many failed checks found the
opposite effect and how many found none. Each ends with a link to the section of
docs/departures.md on that cause (:data:`SECTIONS`), relative to a dataset's results.md.
The functions take the tables and thresholds they are given and know nothing of robots.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

import numpy as np
import pandas as pd

from casa_core.io.contract import CONDITION_KEYS

#: The docs page the causes link to, relative to ``data/processed/<dataset>/results.md``.
DOCS = "../../../docs/departures.md"
#: Per kind of cause, the heading of its section of docs/departures.md.
SECTIONS = {
    "confidence": "C2 and C3: a known intent's confidence rises above epsilon",
    "assisting": "C1 and C4: the intended intent does not lead",
    "checks": "H1-H4: no effect found, or the opposite one",
    "too_few": "Not testable: too few participants",
}


def anchor(heading: str) -> str:
    """GitHub's anchor of a Markdown heading.

    >>> anchor("C1 and C4: the intended intent does not lead")
    'c1-and-c4-the-intended-intent-does-not-lead'
    """
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def link(kind: str) -> str:
    """The Markdown link to the section of :data:`SECTIONS` on ``kind``.

    >>> link("too_few").split("](")[0]
    'Why: docs/departures.md, [Not testable: too few participants'
    """
    heading = SECTIONS[kind]
    return f"Why: docs/departures.md, [{heading}]({DOCS}#{anchor(heading)})."


def _median(values, unit: str = "") -> str:
    values = np.asarray(values, dtype=float)
    # "median" only where the trials differ.
    return f"{'median ' * bool(np.ptp(values) > 0)}{np.median(values):.3g}{unit}"


def _trials(n: int) -> str:
    return f"{n} trial{'s' * (n != 1)}"


def above_epsilon(steps: pd.DataFrame, epsilon: float) -> pd.DataFrame:
    """Per trial and intent of ``steps.csv``: the seconds beta_hat spent above ``epsilon``.

    A tick lasts until the next one (the trial's last tick as long as its median tick).

    Returns
    -------
    pandas.DataFrame
        Columns ``trial, intent, seconds, peak, duration, nearest``: the time above
        epsilon, the highest beta_hat, the trial's length (its ticks' lengths summed) and
        the arm's least distance to the intent's goal (NaN where ``steps`` has no
        ``distance`` for it).

    Examples
    --------
    >>> steps = pd.DataFrame({"trial": "a", "t": [0.0, 0.5, 1.0], "intent": "green",
    ...                       "beta": [0.0, 1.5, 2.0], "distance": [0.3, 0.2, 0.25]})
    >>> above_epsilon(steps, 1.0).iloc[0].to_dict()
    {'trial': 'a', 'intent': 'green', 'seconds': 1.0, 'peak': 2.0, 'duration': 1.5, 'nearest': 0.2}
    """
    columns = ["trial", "intent", "seconds", "peak", "duration", "nearest"]
    rows = []
    for trial, part in steps.groupby("trial", sort=True):
        ticks = np.sort(part["t"].unique())
        gaps = np.diff(ticks)
        last = float(np.median(gaps)) if gaps.size else 0.0
        length = dict(zip(ticks, np.append(gaps, last), strict=True))
        for intent, mine in part.dropna(subset=["beta"]).groupby("intent", sort=True):
            above = mine[mine["beta"] > epsilon]
            distance = mine["distance"] if "distance" in mine.columns else pd.Series(np.nan)
            rows.append(
                dict(trial=trial, intent=intent,
                     seconds=float(sum(length[t] for t in above["t"])),
                     peak=float(mine["beta"].max()), duration=float(sum(length.values())),
                     nearest=float(distance.min()))
            )  # fmt: skip
    return pd.DataFrame(rows, columns=columns)


def c2_cause(
    steps: pd.DataFrame, lost: pd.DataFrame, kept: int, *, epsilon: float, thresholds
) -> str:
    """Why C2 is not seen: which intent's beta_hat rose above epsilon, for how long, and
    how near the arm came to that intent's goal.

    ``lost`` holds the CASA trials before learning whose alpha fell below the first of
    ``thresholds`` (``(in control, taken)``: 0.95 and 0.5), one row each with ``trial``;
    ``kept`` counts the participant-tasks whose PBA trial left alpha at or above the
    second. ``steps`` has a ``trial`` column.

    >>> steps = pd.DataFrame({"trial": "a", "t": [0.0, 0.5], "intent": "green",
    ...                       "beta": [0.0, 2.0], "distance": [0.4, 0.3]})
    >>> print(c2_cause(steps, pd.DataFrame({"trial": ["a"]}), 0, epsilon=1.0,
    ...                thresholds=(0.95, 0.5)).split(") ")[1].split(". Why")[0])
    for 0.5 s of trials lasting 1 s, peaking at 2, the arm coming within 0.3 m of its goal
    """
    in_control, taken = thresholds
    said = []
    if len(lost):
        over = above_epsilon(steps[steps["trial"].isin(lost["trial"])], epsilon)
        over = over[over["seconds"] > 0]
        top = over.sort_values(["seconds", "intent"], ascending=[False, True])
        top = top.drop_duplicates("trial")
        named = ", ".join(f"{intent} in {n}" for intent, n in top["intent"].value_counts().items())
        if len(top):
            said.append(
                f"in {_trials(len(lost))} of CASA before learning alpha fell below "
                f"{in_control} as a known intent's beta_hat rose above epsilon = {epsilon:g} "
                f"({named}) for {_median(top['seconds'], ' s')} of trials lasting "
                f"{_median(top['duration'], ' s')}, peaking at {_median(top['peak'])}"
                + _nearest(top["nearest"])
            )
        if len(lost) > len(top):
            said.append(f"in {len(lost) - len(top)} alpha fell with no beta_hat above epsilon")
    if kept:
        said.append(f"in {kept} PBA left alpha at or above {taken}")
    return f"Cause: {'; '.join(said)}. {link('confidence')}" if said else ""


def _nearest(distances: pd.Series) -> str:
    """The clause on how near the arm came to the goal, where the steps give the distance."""
    known = distances.dropna()
    if known.empty:
        return ""
    return f", the arm coming within {_median(known, ' m')} of its goal"


def c3_cause(frame: pd.DataFrame, met: Mapping[str, bool], *, epsilon: float) -> str:
    """Why C3 is not seen: the conditions of the arbitration comparison not met.

    ``met`` maps ``belief``, ``beta`` and ``confidence`` to whether that condition holds;
    ``frame`` is the arbitration table (``t, intent, beta, alpha_belief,
    alpha_confidence``).

    >>> frame = pd.DataFrame({"t": [0.0, 1.0], "intent": "green", "beta": [0.0, 1.5],
    ...                       "alpha_belief": 0.0, "alpha_confidence": [1.0, 0.67]})
    >>> met = {"belief": True, "beta": False, "confidence": False}
    >>> print(c3_cause(frame, met, epsilon=1.0).split("goal, ")[1].split(". Why")[0])
    for 1 s of 2 s, up to 1.5, and confidence arbitration's alpha fell to 0.67
    """
    said = []
    if not met["beta"]:
        over = above_epsilon(frame.assign(trial="comparison"), epsilon)
        top = over.sort_values("seconds", ascending=False).iloc[0]
        said.append(
            f"{top['intent']}'s beta_hat rose above epsilon = {epsilon:g} along the optimal "
            f"trajectory to the unknown goal, for {top['seconds']:.3g} s of "
            f"{top['duration']:.3g} s, up to {top['peak']:.3g}"
        )
    if not met["confidence"]:
        lowest = float(frame["alpha_confidence"].min())
        said.append(f"confidence arbitration's alpha fell to {lowest:.3g}")
    if not met["belief"]:
        lowest = float(frame["alpha_belief"].min())
        said.append(f"belief arbitration's alpha stayed at {lowest:.3g} or above")
    return f"Cause: {', and '.join(said)}. {link('confidence')}" if said else ""


def assisting_cause(
    missed: pd.DataFrame, targets: pd.Series, *, epsilon: float, taken: float
) -> str:
    """Why C1 or C4 is not seen: how the trials that miss it miss it.

    ``missed`` holds the trials (rows of :func:`casa_core.stats.claims.trial_outcomes`)
    that do not meet the criterion, ``targets`` their intended intents. Each trial is
    counted once, by the first way it misses: another intent leads at the last tick, two
    tie, the intended intent leads at or below epsilon, or alpha never falls below
    ``taken``.

    >>> missed = pd.DataFrame({"top": ["green"], "top_beta": [3.0]})
    >>> print(assisting_cause(missed, pd.Series(["learned_red"]), epsilon=1.0,
    ...                       taken=0.5).split(", ")[1].split(". Why")[0])
    in 1 another intent had the highest beta_hat at the end (green 1)
    """
    if missed.empty:
        return ""
    other = (missed["top"] != targets) & (missed["top"] != "")
    tied = missed["top"] == ""
    low = ~other & ~tied & (missed["top_beta"] <= epsilon)
    leaders = ", ".join(f"{k} {n}" for k, n in missed.loc[other, "top"].value_counts().items())
    parts = [
        (int(other.sum()), f"another intent had the highest beta_hat at the end ({leaders})"),
        (int(tied.sum()), "two intents tied at the end"),
        (int(low.sum()), f"the intended intent led at or below epsilon = {epsilon:g}"),
        (int((~other & ~tied & ~low).sum()), f"alpha never fell below {taken}"),
    ]
    said = ", ".join(f"in {n} {text}" for n, text in parts if n)
    miss = "misses" if len(missed) == 1 else "miss"
    return f"Cause: of the {_trials(len(missed))} that {miss} it, {said}. {link('assisting')}"


def hypothesis_cause(checks, participants: int, opposite: str) -> str:
    """Why H1-H3 does not hold: how many failed checks found the opposite effect.

    ``checks`` are the hypothesis' :class:`casa_core.stats._claim_tests.Check`;
    ``opposite`` is the words of a reason for a significant effect the other way round.

    >>> from casa_core.stats._claim_tests import Check
    >>> failed = [Check(False, "a", reason="not significant")]
    >>> print(hypothesis_cause(failed, 2, "in the opposite direction").split("; ")[1][:57])
    they found no significant effect or too wide a bound with
    """
    failed = [check for check in checks if check.passed is False]
    undecided = sum(check.passed is None for check in checks)
    against = sum(f"significant, but {opposite}" in check.reason for check in failed)
    weak = f"no significant effect or too wide a bound with {participants} participants"
    if against:
        said = [
            f"{against} of the {len(failed)} checks that fail found a significant effect "
            f"opposite to the paper's, the other {len(failed) - against} {weak}"
        ]
    else:
        said = [f"none of the {len(failed)} checks that fail found an effect opposite to "
                f"the paper's; they found {weak}"]  # fmt: skip
    if undecided:
        said.append(f"{undecided} could not be decided")
    return "Cause: " + "; ".join(said) + f". {link('checks')}"


def too_few_cause(checks) -> str:
    """Why H1-H4 waits for participants: how many checks need a test not computed.

    >>> from casa_core.stats._claim_tests import Check
    >>> checks = [Check(None, "a", shortfall=(2, 3)), Check(True, "b")]
    >>> print(too_few_cause(checks).split("; ")[1].split(". Why")[0])
    this dataset has 2 with every condition
    """
    waiting = [c for c in checks if c.passed is None and c.shortfall]
    got = min(got for got, _ in (c.shortfall for c in waiting))
    needed = max(needed for _, needed in (c.shortfall for c in waiting))
    return (
        f"Cause: {len(waiting)} of the {len(checks)} checks need a test computed only with "
        f"{needed} or more participants; this dataset has {got} with every condition. "
        f"{link('too_few')}"
    )


def trial_key(steps: pd.DataFrame) -> pd.Series:
    """Each row's trial: the ``trial`` column, else its condition (one trial each).

    >>> trial_key(pd.DataFrame({"participant": ["p1"], "task": ["known_goal"],
    ...     "method": ["CASA"], "phase": ["no_misspecification"]})).tolist()
    ['p1/known_goal/CASA/no_misspecification']
    """
    if "trial" in steps.columns:
        return steps["trial"]
    return steps[list(CONDITION_KEYS)].astype(str).agg("/".join, axis=1)
