"""The paper's claims, each with a strict criterion, the numbers behind it and a verdict.

Claims C1-C4 are what the paper reports seeing in the robot's confidence and authority
(Sec. IV); H1-H4 are its hypotheses (Sec. V-A). :func:`evaluate_claims` takes a
dataset's processed tables and returns one row per claim: the criterion, the measured
numbers, a number behind the verdict (``value``) and the verdict, one of
:data:`VERDICTS`. The thresholds are fixed here, each with the reason for it, before any
result; nothing is tuned toward the paper. The same function serves any dataset and any
modelling variant. :mod:`casa_core.stats.results` renders the rows as ``results.md``.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import pandas as pd

from casa_core.io.contract import CONDITION_KEYS
from casa_core.io.tables import numeric_columns, require_columns
from casa_core.stats import _claim_tests as tests
from casa_core.stats.study import answered_by_model
from casa_core.vocabulary import KNOWN_TASK, LEARNED_NAMES, UNKNOWN_TASKS

CLAIM_COLUMNS = ["claim", "statement", "criterion", "measured", "value", "verdict", "details"]
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
#: The user keeps control while alpha (the user's share) stays at or above 0.95: the paper
#: says no confidence warranted "an arbitration alpha below 1"; 0.05 leaves room for an
#: inference step at the threshold, far below any assistance a person would feel.
ALPHA_IN_CONTROL = 0.95
#: The robot takes control when alpha falls below 0.5: the robot's share of the command
#: then exceeds the user's.
ALPHA_TAKEN = 0.5
#: The Known Goal task's goal among the robot's intents: its intended trajectory ends at
#: the green goal (casa_core.assist.tasks.task_waypoints).
TRUE_GOAL = {KNOWN_TASK: "green"}
#: What the paper says, in brief (Sec. IV-B to IV-D; hypotheses as in Sec. V-A).
STATEMENTS = {
    "C1": "Known Goal: beta_hat of the correct goal increases with time and, as it does, "
    "alpha gradually decreases (CASA).",
    "C2": "Unknown Goal and Skill before learning: no confidence warrants an arbitration "
    "alpha below 1, so the user keeps full control under CASA; PBA erroneously takes "
    "control toward the green goal.",
    "C3": "Along the optimal trajectory to the unknown goal the confidence in each goal "
    "stays low enough to leave the user in full control, while the belief goes to 1 and "
    "belief-based arbitration sets the user's authority to 0.",
    "C4": "After learning, the newly learned intents receive confidence estimates that "
    "increase as the robot observes the user, and CASA contributes more to the control.",
    "H1": '"If there is no misspecification, assisting with CASA is not inferior to '
    'assisting with PBA, and is superior to NA."',
    "H2": '"If there is misspecification, assisting with CASA before learning is more '
    'accurate, efficient, and effortless than with PBA and not inferior to NA."',
    "H3": '"If there is misspecification, assisting with CASA after learning is more '
    'accurate, efficient, and effortless than NA."',
    "H4": '"If there is misspecification, participants will believe the robot understood '
    "what they want, feel less interaction effort, and find the assistance more useful "
    'with CASA after learning than with any other baseline."',
}


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


def _share_verdict(hits: int, total: int) -> str:
    share = hits / total
    return "holds" if share >= HOLDS_SHARE else "partly" if share >= PARTLY_SHARE else "differs"


def _row(claim, criterion, measured, value, verdict, details="") -> dict:
    return dict(
        claim=claim,
        statement=STATEMENTS[claim],
        criterion=criterion,
        measured=measured,
        value=value,
        verdict=verdict,
        details=details,
    )


def _range(values) -> str:
    values = np.asarray(values, dtype=float)
    return f"median {np.median(values):.3g}, range {values.min():.3g} to {values.max():.3g}"


def trial_outcomes(steps: pd.DataFrame) -> pd.DataFrame:
    """Per trial of ``steps.csv``: the lowest alpha and the intents' beta_hat at its last tick.

    Parameters
    ----------
    steps : pandas.DataFrame
        ``steps.csv`` (a dataset's, or the case study's, which has no ``trial`` column).

    Returns
    -------
    pandas.DataFrame
        One row per trial: ``participant, task, method, phase, trial, min_alpha, top,
        top_beta`` and ``beta:NAME`` per intent at the last tick; ``top`` is the intent
        with the highest beta_hat there, ``""`` when two share it.

    Examples
    --------
    >>> steps = pd.DataFrame({"participant": "p1", "task": "known_goal", "method": "CASA",
    ...     "phase": "no_misspecification", "t": [0.0, 0.0, 5.0, 5.0],
    ...     "alpha": [1.0, 1.0, 0.4, 0.4], "intent": ["green", "purple"] * 2,
    ...     "beta": [0.0, 0.0, 2.5, 0.3]})
    >>> trial_outcomes(steps)[["min_alpha", "top", "top_beta", "beta:purple"]]
       min_alpha    top  top_beta  beta:purple
    0        0.4  green       2.5          0.3
    """
    require_columns(steps, [*CONDITION_KEYS, "t", "alpha", "intent", "beta"], "steps table")
    frame = numeric_columns(steps, ["t", "alpha", "beta"], "steps table")
    if "trial" not in frame.columns:
        frame["trial"] = frame[list(CONDITION_KEYS)].astype(str).agg("/".join, axis=1)
    rows = []
    for trial, part in frame.groupby("trial", sort=True):
        last = part[part["t"] == part["t"].max()].dropna(subset=["beta"])
        betas = last.groupby("intent")["beta"].max().sort_values(ascending=False)
        tied = len(betas) > 1 and betas.iloc[0] == betas.iloc[1]
        row = {key: part[key].iloc[0] for key in CONDITION_KEYS} | {"trial": trial}
        row |= {"min_alpha": float(part["alpha"].min())}
        row |= {"top": "" if betas.empty or tied else betas.index[0]}
        row |= {"top_beta": float(betas.iloc[0]) if len(betas) else np.nan}
        rows.append(row | {f"beta:{name}": float(value) for name, value in betas.items()})
    columns = [*CONDITION_KEYS, "trial", "min_alpha", "top", "top_beta"]
    return pd.DataFrame(rows, columns=None if rows else columns)


def _assisting(outcomes, target_of, *, epsilon: float, claim: str, what: str) -> dict:
    """C1 and C4: the intended intent is the most confident at the end, and assists."""
    criterion = (
        f"holds: in >= {HOLDS_SHARE:.0%} of {what} the intended intent has the highest "
        f"beta_hat at the last tick, above epsilon = {epsilon:g}, and alpha's minimum is "
        f"< {ALPHA_TAKEN}; partly: >= {PARTLY_SHARE:.0%}; differs: fewer"
    )
    if outcomes.empty:
        return _row(claim, criterion, f"no {what} in steps.csv", np.nan, "not testable")
    targets = outcomes["task"].map(target_of)
    hits = (outcomes["top"] == targets) & (outcomes["top_beta"] > epsilon)
    hits &= outcomes["min_alpha"] < ALPHA_TAKEN
    target_beta = [
        row.get(f"beta:{target}", np.nan)
        for target, (_, row) in zip(targets, outcomes.iterrows(), strict=True)
    ]
    measured = (
        f"{int(hits.sum())} of {len(hits)} trials; the intended intent's final beta_hat "
        f"{_range(np.nan_to_num(target_beta))}; lowest alpha {_range(outcomes['min_alpha'])}"
    )
    share = float(hits.mean())
    return _row(claim, criterion, measured, share, _share_verdict(int(hits.sum()), len(hits)))


def _of(outcomes, method, phases, tasks) -> pd.DataFrame:
    chosen = outcomes["method"].eq(method) & outcomes["phase"].isin(phases)
    return outcomes[chosen & outcomes["task"].isin(tasks)]


def _claim_c1(outcomes: pd.DataFrame, *, epsilon: float) -> dict:
    """C1 from :func:`trial_outcomes`: the true goal gains confidence, alpha falls."""
    casa = _of(outcomes, "CASA", ["no_misspecification"], [KNOWN_TASK])
    return _assisting(casa, TRUE_GOAL, epsilon=epsilon, claim="C1", what="CASA Known Goal trials")


def _claim_c4(outcomes: pd.DataFrame, *, epsilon: float) -> dict:
    """C4 from :func:`trial_outcomes`: after learning, the learned intent is assisted."""
    casa = _of(outcomes, "CASA", ["after_learning"], list(UNKNOWN_TASKS))
    return _assisting(
        casa, LEARNED_NAMES, epsilon=epsilon, claim="C4", what="CASA after-learning trials"
    )


def _claim_c2(outcomes: pd.DataFrame) -> dict:
    """C2 from :func:`trial_outcomes`: before learning CASA leaves control, PBA takes it."""
    criterion = (
        f"holds: for >= {HOLDS_SHARE:.0%} of participant-tasks (Unknown Goal, Unknown "
        f"Skill) alpha stays >= {ALPHA_IN_CONTROL} in the CASA trial before learning and "
        f"falls below {ALPHA_TAKEN} in the PBA trial; partly: >= {PARTLY_SHARE:.0%}; "
        "differs: fewer"
    )
    tasks = list(UNKNOWN_TASKS)
    casa = _of(outcomes, "CASA", ["before_learning"], tasks)
    pba = _of(outcomes, "PBA", ["before_learning"], tasks)
    keys = ["participant", "task"]
    pairs = (
        casa.groupby(keys)["min_alpha"]
        .min()
        .to_frame("casa")
        .join(pba.groupby(keys)["min_alpha"].min().rename("pba"), how="inner")
    )
    if pairs.empty:
        measured = "no participant-task with both a CASA and a PBA trial before learning"
        return _row("C2", criterion, measured, np.nan, "not testable")
    kept = pairs["casa"] >= ALPHA_IN_CONTROL
    taken = pairs["pba"] < ALPHA_TAKEN
    both = int((kept & taken).sum())
    measured = (
        f"{both} of {len(pairs)} participant-tasks; CASA kept alpha >= {ALPHA_IN_CONTROL} in "
        f"{int(kept.sum())} (lowest alpha {_range(pairs['casa'])}); PBA took it below "
        f"{ALPHA_TAKEN} in {int(taken.sum())} (lowest alpha {_range(pairs['pba'])})"
    )
    return _row("C2", criterion, measured, both / len(pairs), _share_verdict(both, len(pairs)))


def _claim_c3(arbitration: pd.DataFrame | None, *, epsilon: float) -> dict:
    """C3 from the arbitration comparison (``case_study/arbitration.csv``)."""
    criterion = (
        f"three conditions: belief arbitration's alpha falls below {ALPHA_TAKEN}; every "
        f"beta_hat stays <= epsilon = {epsilon:g}; confidence arbitration keeps alpha >= "
        f"{ALPHA_IN_CONTROL}. holds: all three; partly: two; differs: fewer"
    )
    if arbitration is None:
        measured = (
            "no arbitration comparison for this dataset (it is run along the simulated "
            "study's scene: data/processed/case_study/arbitration.csv)"
        )
        return _row("C3", criterion, measured, np.nan, "not testable")
    columns = ["beta", "alpha_belief", "alpha_confidence"]
    require_columns(arbitration, ["t", "intent", *columns], "arbitration table")
    frame = numeric_columns(arbitration, columns, "arbitration table")
    if frame.empty:
        return _row("C3", criterion, "the arbitration table is empty", np.nan, "not testable")
    lowest_belief = float(frame["alpha_belief"].min())
    highest_beta = float(frame["beta"].max())
    lowest_confidence = float(frame["alpha_confidence"].min())
    met = [
        lowest_belief < ALPHA_TAKEN,
        highest_beta <= epsilon,
        lowest_confidence >= ALPHA_IN_CONTROL,
    ]
    top = frame.loc[frame["beta"].idxmax(), "intent"]
    measured = (
        f"{sum(met)} of 3; lowest alpha under belief arbitration {lowest_belief:.3g}; "
        f"highest beta_hat {highest_beta:.3g} ({top}); lowest alpha under confidence "
        f"arbitration {lowest_confidence:.3g}"
    )
    verdict = {3: "holds", 2: "partly"}.get(sum(met), "differs")
    return _row("C3", criterion, measured, sum(met) / 3, verdict)


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


def _hypothesis(claim: str, checks: list[tests.Check]) -> dict:
    """H1-H3: every check of both forms passes (holds), at least half do (partly)."""
    criterion = (
        f"{_requirements(checks)}holds: every check below testable and passed; partly: at least "
        f"{PARTLY_SHARE:.0%} of the checks passed; differs: fewer; not testable: too few "
        "participants when a check's test was not computed for want of participants"
    )
    details = "\n".join(check.text for check in checks)
    share, verdict = _verdict(checks)
    if verdict == "not testable":
        measured = "no check could be decided" if checks else "no checks"
    else:
        testable = sum(check.passed is not None for check in checks)
        passed = sum(bool(check.passed) for check in checks)
        measured = f"{passed} of {len(checks)} checks passed ({testable} decided)"
    why = _not_passed(checks)
    measured += f"; {why}" if why else ""
    row = _row(claim, criterion, measured, share, verdict, details)
    forms = {form: [check for check in checks if check.form == form] for form in FORM_NAMES}
    if all(forms.values()):
        row["by_form"] = "; ".join(
            f"{FORM_NAMES[form]}: {_verdict(mine)[1]}" for form, mine in forms.items()
        )
    return row


#: The names of the two forms of the checks of H1-H3 (:data:`_claim_tests.FORMS`).
FORM_NAMES = dict(zip(tests.FORMS, ("paper form", "within subjects"), strict=True))


def _verdict(checks: list[tests.Check]) -> tuple[float, str]:
    """The share of checks passed and the verdict: holds when all pass, partly when at
    least :data:`PARTLY_SHARE` do; not testable when none is decided, and
    :func:`too_few` when a check is undecided because a test it needs was not computed
    for too few participants (holds asks every check to be decided, so the verdict
    waits for the participants the test needs)."""
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


def _claim_h4(stats: pd.DataFrame, likert: pd.DataFrame | None) -> dict:
    """H4 from the Likert table and its tests; never tested on a model's answers."""
    criterion = (
        "for each misspecified task and question: CASA after learning has the highest mean "
        f"score (paper's form), and Friedman's test and every Holm-corrected Wilcoxon test "
        f"of CASA after learning against another condition give p < {tests.SIGNIFICANCE} "
        "with CASA after learning rated above that condition (within subjects); a test "
        "significant the other way round fails; holds: every check passed; "
        f"partly: at least {PARTLY_SHARE:.0%}; differs: fewer. Only people's answers count"
    )
    if likert is None or likert.empty:
        return _row("H4", criterion, "no Likert answers", np.nan, "not testable")
    checks = tests.likert_checks(stats, likert)
    row = _hypothesis("H4", checks)
    row["criterion"] = criterion
    if answered_by_model(likert):
        row["measured"] = "answers are model output (simulated participants); " + row["measured"]
        row["verdict"], row["value"] = MODEL_OUTPUT, np.nan
    return row


def evaluate_claims(tables: Mapping[str, pd.DataFrame | None], *, epsilon: float) -> pd.DataFrame:
    """Every claim of the paper on one dataset: criterion, measured numbers, verdict.

    Parameters
    ----------
    tables : mapping of str to DataFrame
        The dataset's processed tables, read with :func:`casa_core.io.read_table`:
        ``trials``, ``steps`` and ``stats`` (required); optional (None or absent when
        there is none): ``likert``, and the case study's ``arbitration`` (the
        arbitration comparison, for C3) and ``case_steps`` (its expert's runs, which add
        the rows ``C1 expert``, ``C2 expert`` and ``C4 expert``).
    epsilon : float
        The misspecification threshold on beta_hat the trials were run with.

    Returns
    -------
    pandas.DataFrame
        Columns :data:`CLAIM_COLUMNS` and ``by_form``, one row per claim C1-C4 (and
        expert), H1-H4; ``by_form`` gives H1-H3's verdict on the checks of each form
        alone (``paper form: differs; within subjects: partly``), empty for the others.
        ``value`` is the
        number behind the verdict (the share of trials or checks that meet the criterion;
        NaN when not testable); ``verdict`` is one of :data:`VERDICTS`
        (:data:`MODEL_OUTPUT` for H4 on a model's answers); ``details`` lists a
        hypothesis' checks, one a line.

    Raises
    ------
    ValueError
        Naming the table and column a required table lacks.

    Examples
    --------
    One Known Goal CASA trial whose true goal ends confident and assisted:

    >>> steps = pd.DataFrame({"participant": "p1", "task": "known_goal", "method": "CASA",
    ...     "phase": "no_misspecification", "t": [0.0, 0.0, 5.0, 5.0],
    ...     "alpha": [1.0, 1.0, 0.3, 0.3], "intent": ["green", "purple"] * 2,
    ...     "beta": [0.0, 0.0, 2.5, 0.3]})
    >>> trials = steps.iloc[:1][["participant", "task", "method", "phase"]].assign(
    ...     error=0.1, efficiency=0.2, relative_effort=1.0)
    >>> from casa_core.stats import STATS_COLUMNS
    >>> tables = {"trials": trials, "steps": steps, "stats": pd.DataFrame(columns=STATS_COLUMNS)}
    >>> claims = evaluate_claims(tables, epsilon=1.0)
    >>> claims[["claim", "value", "verdict"]].head(2)
      claim  value       verdict
    0    C1    1.0         holds
    1    C2    NaN  not testable
    """
    for name in ("trials", "steps", "stats"):
        if tables.get(name) is None:
            raise ValueError(f"evaluate_claims: the {name!r} table is required")
    outcomes = trial_outcomes(tables["steps"])
    stats, trials = tables["stats"], tables["trials"]
    likert = tables.get("likert")
    case_steps = tables.get("case_steps")
    expert = trial_outcomes(case_steps) if case_steps is not None else None
    observed = {
        "C1": lambda trials: _claim_c1(trials, epsilon=epsilon),
        "C2": _claim_c2,
        "C3": None,
        "C4": lambda trials: _claim_c4(trials, epsilon=epsilon),
    }
    rows = []
    for claim, judge in observed.items():
        if judge is None:
            rows.append(_claim_c3(tables.get("arbitration"), epsilon=epsilon))
            continue
        rows.append(judge(outcomes))
        if expert is not None:
            # The paper saw C1, C2 and C4 in its expert's runs: judged on the case study too.
            rows.append(judge(expert) | {"claim": f"{claim} expert"})
    rows += [
        _hypothesis("H1", tests.h1_checks(stats, trials)),
        _hypothesis("H2", tests.h2_checks(stats, trials)),
        _hypothesis("H3", tests.h3_checks(stats, trials)),
        _claim_h4(stats, likert),
    ]
    table = pd.DataFrame(rows, columns=[*CLAIM_COLUMNS, "by_form"])
    table["by_form"] = table["by_form"].fillna("")
    return table


__all__ = [
    "CLAIM_COLUMNS",
    "MODEL_OUTPUT",
    "TOO_FEW",
    "VERDICTS",
    "answered_by_model",
    "evaluate_claims",
    "too_few",
    "trial_outcomes",
    "verdict_kind",
]
