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
from casa_core.stats import causes
from casa_core.stats._hypotheses import judge_checks
from casa_core.stats._likert_checks import likert_checks
from casa_core.stats.study import answered_by_model
from casa_core.stats.verdicts import (
    HOLDS_SHARE,
    MODEL_OUTPUT,
    PARTLY_SHARE,
    TOO_FEW,
    VERDICTS,
    share_verdict,
    too_few,
    verdict_kind,
)
from casa_core.vocabulary import KNOWN_TASK, LEARNED_NAMES, UNKNOWN_TASKS

CLAIM_COLUMNS = ["claim", "statement", "criterion", "measured", "value", "verdict", "details"]
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


def _row(claim, criterion, measured, value, verdict, details="", cause="") -> dict:
    return dict(
        claim=claim,
        statement=STATEMENTS[claim],
        criterion=criterion,
        measured=measured,
        value=value,
        verdict=verdict,
        details=details,
        cause=cause if verdict != "holds" else "",
    )


def _range(values) -> str:
    values = np.asarray(values, dtype=float)
    return f"median {np.median(values):.3g}, range {values.min():.3g} to {values.max():.3g}"


def _steps(steps: pd.DataFrame) -> pd.DataFrame:
    """``steps.csv`` checked, its numbers as numbers and a ``trial`` column."""
    require_columns(steps, [*CONDITION_KEYS, "t", "alpha", "intent", "beta"], "steps table")
    numbers = ["t", "alpha", "beta", *(["distance"] if "distance" in steps.columns else [])]
    frame = numeric_columns(steps, numbers, "steps table")
    return frame.assign(trial=causes.trial_key(frame))


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
    frame = _steps(steps)
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
    cause = causes.assisting_cause(
        outcomes[~hits], targets[~hits], epsilon=epsilon, taken=ALPHA_TAKEN
    )
    verdict = share_verdict(int(hits.sum()), len(hits))
    return _row(claim, criterion, measured, share, verdict, cause=cause)


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


def _claim_c2(outcomes: pd.DataFrame, steps: pd.DataFrame, *, epsilon: float) -> dict:
    """C2 from :func:`trial_outcomes`: before learning CASA leaves control, PBA takes it;
    ``steps`` (with a ``trial`` column) gives the cause where it does not."""
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
    judged = casa.set_index(keys).index.isin(pairs.index)
    lost = casa[judged & (casa["min_alpha"] < ALPHA_IN_CONTROL).to_numpy()]
    thresholds = (ALPHA_IN_CONTROL, ALPHA_TAKEN)
    cause = causes.c2_cause(
        steps, lost, int((~taken).sum()), epsilon=epsilon, thresholds=thresholds
    )
    verdict = share_verdict(both, len(pairs))
    return _row("C2", criterion, measured, both / len(pairs), verdict, cause=cause)


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
    met = {
        "belief": lowest_belief < ALPHA_TAKEN,
        "beta": highest_beta <= epsilon,
        "confidence": lowest_confidence >= ALPHA_IN_CONTROL,
    }
    top = frame.loc[frame["beta"].idxmax(), "intent"]
    measured = (
        f"{_met_words(met, epsilon)}; lowest alpha under belief arbitration "
        f"{lowest_belief:.3g}; highest beta_hat {highest_beta:.3g} ({top}); lowest alpha "
        f"under confidence arbitration {lowest_confidence:.3g}"
    )
    count = sum(met.values())
    verdict = {3: "holds", 2: "partly"}.get(count, "differs")
    cause = causes.c3_cause(frame, met, epsilon=epsilon)
    return _row("C3", criterion, measured, count / 3, verdict, cause=cause)


def _met_words(met: Mapping[str, bool], epsilon: float) -> str:
    """C3's conditions by name: ``1 of 3 met (belief arbitration's alpha below 0.5); ...``."""
    words = {
        "belief": f"belief arbitration's alpha below {ALPHA_TAKEN}",
        "beta": f"every beta_hat <= epsilon = {epsilon:g}",
        "confidence": f"confidence arbitration's alpha >= {ALPHA_IN_CONTROL}",
    }
    said = [f"{sum(met.values())} of 3 met"]
    for outcome, name in ((True, "met"), (False, "not met")):
        chosen = [words[key] for key, value in met.items() if value is outcome]
        if chosen:
            said.append(f"{name}: {' and '.join(chosen)}")
    return "; ".join(said)


def _hypothesis(claim: str, checks: list[tests.Check], participants: int) -> dict:
    """H1-H4's row from its checks (:func:`casa_core.stats._hypotheses.judge_checks`)."""
    return {"claim": claim, "statement": STATEMENTS[claim]} | judge_checks(checks, participants)


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
    checks = likert_checks(stats, likert)
    row = _hypothesis("H4", checks, likert["participant"].nunique())
    row["criterion"] = criterion
    if answered_by_model(likert):
        row["measured"] = "answers are model output (simulated participants); " + row["measured"]
        row["verdict"], row["value"], row["cause"] = MODEL_OUTPUT, np.nan, ""
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
        Columns :data:`CLAIM_COLUMNS`, ``by_form`` and ``cause``, one row per claim C1-C4
        (and expert), H1-H4; ``by_form`` gives H1-H3's verdict on the checks of each form
        alone (``paper form: differs; within subjects: partly``), empty for the others;
        ``cause`` is a sentence on why a verdict other than holds came about, computed
        from the tables, with a link to the docs (:mod:`casa_core.stats.causes`).
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
    steps = _steps(tables["steps"])
    stats, trials = tables["stats"], tables["trials"]
    assert stats is not None and trials is not None  # required, checked above
    likert = tables.get("likert")
    case_steps = tables.get("case_steps")
    runs = [("", steps)]
    if case_steps is not None:
        runs.append((" expert", _steps(case_steps)))
    observed = {
        "C1": lambda outcomes, _: _claim_c1(outcomes, epsilon=epsilon),
        "C2": lambda outcomes, steps: _claim_c2(outcomes, steps, epsilon=epsilon),
        "C3": None,
        "C4": lambda outcomes, _: _claim_c4(outcomes, epsilon=epsilon),
    }
    outcomes = {suffix: trial_outcomes(frame) for suffix, frame in runs}
    rows = []
    for claim, judge in observed.items():
        if judge is None:
            rows.append(_claim_c3(tables.get("arbitration"), epsilon=epsilon))
            continue
        # The paper saw C1, C2 and C4 in its expert's runs: judged on the case study too.
        for suffix, frame in runs:
            rows.append(judge(outcomes[suffix], frame) | {"claim": f"{claim}{suffix}"})
    n = trials["participant"].nunique() if "participant" in trials.columns else 0
    rows += [
        _hypothesis("H1", tests.h1_checks(stats, trials), n),
        _hypothesis("H2", tests.h2_checks(stats, trials), n),
        _hypothesis("H3", tests.h3_checks(stats, trials), n),
        _claim_h4(stats, likert),
    ]
    table = pd.DataFrame(rows, columns=[*CLAIM_COLUMNS, "by_form", "cause"])
    table[["by_form", "cause"]] = table[["by_form", "cause"]].fillna("")
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
