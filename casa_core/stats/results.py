"""``results.md``: the paper's claims on one dataset, as :mod:`casa_core.stats.claims` judges them.

It opens with the configuration that built it (when the workflow names it), what the data
are (the dataset, how many participants, whether they are simulated, the inference
settings of the trials), then a table of verdicts, then per
claim the paper's words, the criterion, the numbers measured and the verdict, saying
plainly where it differs from the paper. Every number is read from the tables.
"""

from __future__ import annotations

from collections.abc import Mapping

import pandas as pd

from casa_core.io.tables import require_columns
from casa_core.stats import _claim_tests as tests
from casa_core.stats.claims import (
    CLAIM_COLUMNS,
    MODEL_OUTPUT,
    TOO_FEW,
    answered_by_model,
    verdict_kind,
)
from casa_core.stats.power import PAPER_N

#: What each verdict means next to the paper, said under the claim.
VERDICT_WORDS = {
    "holds": "as the paper reports.",
    "partly": "only in part: the paper reports it in full, these data show it only in part.",
    "differs": "this differs from the paper: the paper reports it, these data do not show it.",
    "not testable": "these data cannot decide it (see the numbers above).",
    MODEL_OUTPUT: (
        "the Likert answers of this dataset are the output of a model of simulated "
        "participants (casa_core/study/likert.py), not ratings by people, so they cannot "
        "test what people believe: H4 is not reproduced here."
    ),
    TOO_FEW: (
        "these data cannot decide it: a test it needs is computed only with more "
        "participants than these (the checks below say which; stats.csv's note says why)."
    ),
}


def _values(frame: pd.DataFrame | None, column: str) -> list[str]:
    if frame is None or column not in frame.columns:
        return []
    return sorted({str(v) for v in frame[column].dropna() if str(v)})


def facts(tables: Mapping[str, pd.DataFrame | None]) -> list[str]:
    """Sentences on what the data are: participants, source, inference settings, answers.

    Examples
    --------
    >>> trials = pd.DataFrame({"participant": ["p1", "p2"], "source": "simulated",
    ...                        "preset": "casa", "evidence": "commanded"})
    >>> for line in facts({"trials": trials}):
    ...     print(line)
    Participants: 2 (in trials.csv).
    Source: simulated (the participants are a model, not people).
    Inference preset: casa; evidence: commanded.
    """
    trials = tables["trials"]
    assert trials is not None  # the trials are always given; the other tables may be None
    n = trials["participant"].nunique() if "participant" in trials.columns else 0
    lines = [f"Participants: {n} (in trials.csv)."]
    sources = _values(trials, "source")
    if sources == ["simulated"]:
        lines.append("Source: simulated (the participants are a model, not people).")
    elif "simulated" in sources:
        lines.append(f"Source: {', '.join(sources)} (some participants are a model).")
    else:
        lines.append(f"Source: {', '.join(sources) or 'not recorded'}.")
    presets, evidence = _values(trials, "preset"), _values(trials, "evidence")
    lines.append(
        f"Inference preset: {', '.join(presets) or 'not recorded in the logs'}; "
        f"evidence: {', '.join(evidence) or 'not recorded in the logs'}."
    )
    likert = tables.get("likert")
    if answered_by_model(likert):
        lines.append("Likert answers: model output (simulated participants), not people's.")
    return lines


def design_note(trials: pd.DataFrame) -> str:
    """A sentence when the dataset has fewer participants than the paper's study, else "".

    Examples
    --------
    >>> print(design_note(pd.DataFrame({"participant": ["p1", "p2"]})).split(" (")[0])
    Fewer participants than the paper's design: 2 here, 11 in the paper's study
    >>> design_note(pd.DataFrame({"participant": [f"p{i}" for i in range(11)]}))
    ''
    """
    n = trials["participant"].nunique() if "participant" in trials.columns else 0
    if n >= PAPER_N:
        return ""
    return (
        f"Fewer participants than the paper's design: {n} here, {PAPER_N} in the paper's "
        "study (Sec. V-A). A test that needs more participants is not computed, and a "
        'hypothesis that needs one reads "not testable: too few participants"; the tests '
        "that are computed have less power than the paper's."
    )


def form_lines(claims: pd.DataFrame, stats: pd.DataFrame | None = None) -> list[str]:
    """Per hypothesis, the verdict of the paper-form checks beside the within-subjects
    ones (``by_form`` of :func:`casa_core.stats.claims.evaluate_claims`), and the level
    of the non-inferiority tests.

    Examples
    --------
    >>> claims = pd.DataFrame({"claim": ["H1"], "verdict": ["partly"],
    ...                        "by_form": ["paper form: differs; within subjects: holds"]})
    >>> print("\\n".join(form_lines(claims)))
    <BLANKLINE>
    | Hypothesis | Verdict | Paper form | Within subjects |
    | --- | --- | --- | --- |
    | H1 | partly | differs | holds |
    """
    if "by_form" not in claims.columns:
        return []
    lines = []
    for row in claims.itertuples():
        forms = dict(part.split(": ", 1) for part in str(row.by_form).split("; ") if ": " in part)
        if forms:
            lines.append(
                f"| {row.claim} | {row.verdict} | {forms.get('paper form', '')} | "
                f"{forms.get('within subjects', '')} |"
            )
    if not lines:
        return []
    head = [
        "",
        "| Hypothesis | Verdict | Paper form | Within subjects |",
        "| --- | --- | --- | --- |",
    ]
    tail = []
    if stats is not None and "analysis" in stats.columns:
        tail = [
            "",
            "Paper form: each participant-condition an independent observation, as the paper "
            "ran it; within subjects: the repeated-measures ANOVA and paired non-inferiority "
            "(a ratio test where the margin is a fraction of the reference mean). Where the "
            "pooled tasks' method x task interaction is significant, H2's and H3's "
            "superiority is judged per task (the simple effects of method; the per-task rows "
            "of stats.csv). Non-inferiority is tested at the "
            f"{tests.level_words(stats)} level (statistics.noninferiority_alpha).",
        ]
    return head + lines + tail


def _cell(text) -> str:
    return str(text).replace("|", "/")


#: Where the claims are judged under other modelling choices, and the command that builds it.
ROBUSTNESS_NOTE = (
    "data/processed/robustness/results.md, built with the simulated study by the default "
    "target (alone: `snakemake --cores all robustness`), judges the same claims on the "
    "simulated study under the other modelling choices the paper leaves open (inference "
    "preset, evidence, operator model), with the same participants and seeds."
)


def modelling_note(
    trials: pd.DataFrame,
    *,
    operator: str | None = None,
    population: str | None = None,
    setup: str | None = None,
) -> str:
    """For a simulated dataset: its modelling choices and where the other choices are judged.

    ``setup`` names the layout and teleoperation it was simulated on, first. The
    robustness table judges the simulated study this config builds, which alone is
    given an ``operator`` (the workflow's); another dataset of simulated participants
    (say, logs copied from it) is told the table is not about it.

    Examples
    --------
    >>> trials = pd.DataFrame({"source": ["simulated"], "preset": ["casa"],
    ...                        "evidence": ["commanded"]})
    >>> print(modelling_note(trials, operator="lookahead").split(". ")[0].split(": ")[1])
    preset casa, evidence commanded, operator model lookahead
    >>> modelling_note(trials.assign(source="human"))
    ''
    """
    if "simulated" not in _values(trials, "source"):
        return ""
    choices = [setup] if setup else []
    choices += [
        f"preset {', '.join(_values(trials, 'preset')) or 'not recorded'}",
        f"evidence {', '.join(_values(trials, 'evidence')) or 'not recorded'}",
    ]
    if not operator:
        return (
            f"Modelling choices in its trials: {', '.join(choices)}. This dataset is not the "
            "simulated study the config builds: data/processed/robustness/results.md judges "
            "the simulated study under other modelling choices, not this dataset."
        )
    choices.append(f"operator model {operator}")
    if population:
        choices.append(f"operator population {population}")
    return f"Modelling choices (the config's defaults): {', '.join(choices)}. {ROBUSTNESS_NOTE}"


def results_markdown(
    claims: pd.DataFrame,
    tables: Mapping[str, pd.DataFrame | None],
    *,
    dataset: str,
    operator: str | None = None,
    population: str | None = None,
    setup: str | None = None,
    provenance: str = "",
    left_out: str = "",
) -> str:
    """The Markdown of ``results.md`` from :func:`casa_core.stats.claims.evaluate_claims`.

    Parameters
    ----------
    claims : pandas.DataFrame
        The claims table (columns :data:`casa_core.stats.claims.CLAIM_COLUMNS`).
    tables : mapping
        The tables the claims were judged on (``trials``, optional ``likert``), for the
        opening sentences (:func:`facts`).
    dataset : str
        The dataset's name, for the title.
    operator : str, optional
        The simulated operator model (``simulation.operator``), named for a simulated
        dataset beside a pointer to the robustness table (:func:`modelling_note`).
    population : str, optional
        Whom the simulated participants were drawn from
        (:func:`casa_core.io.population.population_label`), named beside the operator.
    setup : str, optional
        The layout and teleoperation it was simulated on
        (:func:`casa_core.experiments.robustness.setup_text`), named first.
    provenance : str, optional
        The configuration that built it (:meth:`casa_core.config.Provenance.line`),
        written under the title.
    left_out : str, optional
        What the build left out (:func:`casa_core.stats.descriptives.left_out`), said
        near the top.

    Returns
    -------
    str
        A title, what the data are, a table of the verdicts, then a section per claim.

    Examples
    --------
    >>> claims = pd.DataFrame([{"claim": "C1", "statement": "goal confident",
    ...     "criterion": "holds: all", "measured": "1 of 1 trials", "value": 1.0,
    ...     "verdict": "holds", "details": ""}])
    >>> trials = pd.DataFrame({"participant": ["p1"], "source": ["human"]})
    >>> text = results_markdown(claims, {"trials": trials}, dataset="lab")
    >>> print(text.split("## ")[1])
    C1: holds
    <BLANKLINE>
    Paper: goal confident
    <BLANKLINE>
    Criterion: holds: all.
    <BLANKLINE>
    Measured: 1 of 1 trials.
    <BLANKLINE>
    Verdict: holds, as the paper reports.
    <BLANKLINE>
    """
    require_columns(claims, CLAIM_COLUMNS, "claims table")
    lines = [f"# Claims of the paper on dataset {dataset}", ""]
    lines += [f"{provenance}.", ""] if provenance else []
    few = design_note(tables["trials"])
    lines += [few, ""] if few else []
    lines += [left_out, ""] if left_out else []
    lines += [f"Dataset: `{dataset}`. " + " ".join(facts(tables)), ""]
    note = modelling_note(tables["trials"], operator=operator, population=population, setup=setup)
    lines += [note, ""] if note else []
    lines += [
        "Each claim of the paper (C1-C4: what it observed in its expert case study, Sec. "
        "IV, judged on this dataset's trials and, as \"expert\", on the case study's; "
        "H1-H4: the user study's hypotheses, Sec. V) with the criterion it is judged by, "
        "the numbers measured in this dataset's tables and a verdict: holds, partly, "
        "differs, or not testable. The thresholds are fixed in casa_core/stats/claims.py.",
        "",
        "| Claim | Verdict | Measured |",
        "| --- | --- | --- |",
    ]
    for row in claims.itertuples():
        lines.append(f"| {row.claim} | {row.verdict} | {_cell(row.measured)} |")
    lines += form_lines(claims, tables.get("stats"))
    for row in claims.itertuples():
        lines += [
            "",
            f"## {row.claim}: {row.verdict}",
            "",
            f"Paper: {row.statement}",
            "",
            f"Criterion: {row.criterion}.",
            "",
            f"Measured: {row.measured}.",
            "",
            f"Verdict: {row.verdict}, {VERDICT_WORDS.get(verdict_kind(row.verdict), '')}".rstrip(
                ", "
            ),
        ]
        cause = getattr(row, "cause", "")
        lines += ["", str(cause)] if isinstance(cause, str) and cause else []
        details = [] if pd.isna(row.details) else str(row.details).splitlines()
        details = [d for d in details if d]
        if details:
            lines += ["", "| Check | Outcome |", "| --- | --- |"]
            for detail in details:
                check, _, outcome = detail.rpartition(": ")
                lines.append(f"| {_cell(check)} | {outcome} |")
    return "\n".join(lines) + "\n"
