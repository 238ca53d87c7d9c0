"""A hypothesis whose tests need more participants than a dataset has reads "not testable".

The tables come from :func:`casa_core.stats.analyze_study` on small synthetic trials
(tests/stats/test_stats_study.py), so the skip notes are the ones the analyses write; the
number of participants a test needs is checked against the analysis itself: the smallest
number with which it computes the test.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core.figures.robustness import verdict_grid
from casa_core.stats import analyze_study, claims
from casa_core.stats._tables import participants_shortfall
from casa_core.stats.results import results_markdown
from tests.stats.test_claims import EPSILON, known_goal_steps
from tests.stats.test_stats_study import make_trials


def _tables(n: int) -> dict:
    trials = make_trials(n_participants=n, seed=0)
    return {"trials": trials, "steps": known_goal_steps(1, 1), "stats": analyze_study(trials)}


@pytest.fixture(scope="module")
def two() -> dict:
    return _tables(2)


def _rm_anova_p(stats: pd.DataFrame, hypothesis: str) -> float:
    rows = stats[(stats["hypothesis"] == hypothesis) & (stats["analysis"] == "rm_anova")]
    return float(rows[(rows["metric"] == "error") & (rows["term"] == "method")]["p"].iloc[0])


def test_the_participants_needed_are_the_fewest_the_test_is_computed_with(two):
    # H1's repeated-measures ANOVA over 3 conditions: skipped with 2 participants and
    # computed with 3, so its note must say 2 and 3.
    stats = two["stats"]
    h1 = stats[(stats["hypothesis"] == "H1") & (stats["analysis"] == "rm_anova")]
    note = h1[h1["metric"] == "error"]["note"].iloc[0]
    assert np.isnan(_rm_anova_p(stats, "H1"))
    assert participants_shortfall(note) == (2, 3)
    assert np.isfinite(_rm_anova_p(_tables(3)["stats"], "H1"))


def test_a_one_participant_note_names_what_the_test_needs():
    # One participant: H3's 2 conditions need 2, H1's 3 conditions need 3 (as with 2
    # participants above), so the verdict names the number that computes the test.
    one = _tables(1)
    stats = one["stats"]
    for hypothesis, needed in (("H3", 2), ("H1", 3)):
        rows = stats[(stats["hypothesis"] == hypothesis) & (stats["analysis"] == "rm_anova")]
        assert participants_shortfall(rows["note"].iloc[0]) == (1, needed)
    judged = claims.evaluate_claims(one, epsilon=EPSILON).set_index("claim")
    assert judged.loc["H1", "verdict"] == "not testable: too few participants (1, needs 3)"


def test_h1_and_h2_with_two_participants_are_not_testable_h3_is_judged(two):
    judged = claims.evaluate_claims(two, epsilon=EPSILON).set_index("claim")
    needs = "not testable: too few participants (2, needs 3)"
    assert judged.loc["H1", "verdict"] == needs
    assert judged.loc["H2", "verdict"] == needs
    assert np.isnan(judged.loc["H1", "value"])
    assert "too few participants" in judged.loc["H1", "measured"]
    # The paper form is computed with 2 participants; the within-subjects one is not.
    assert judged.loc["H1", "by_form"].endswith(f"within subjects: {needs}")
    # H3 compares 2 conditions: its tests are computed with 2 participants.
    assert judged.loc["H3", "verdict"] in ("holds", "partly", "differs")


def test_with_enough_participants_no_hypothesis_waits_for_more():
    judged = claims.evaluate_claims(_tables(3), epsilon=EPSILON).set_index("claim")
    for hypothesis in ("H1", "H2", "H3"):
        assert not judged.loc[hypothesis, "verdict"].startswith(claims.TOO_FEW)


def test_results_md_says_at_the_top_the_dataset_is_smaller_than_the_papers(two):
    judged = claims.evaluate_claims(two, epsilon=EPSILON)
    text = results_markdown(judged, two, dataset="mylab")
    first = text.split("\n\n")[1]
    assert first.startswith("Fewer participants than the paper's design: 2 here, 11 in")
    assert "| H1 | not testable: too few participants (2, needs 3) |" in text
    assert "## H1: not testable: too few participants (2, needs 3)" in text
    assert "computed only with more participants" in text  # the verdict's words
    eleven = {**two, "trials": make_trials(n_participants=11, seed=0)}
    assert "Fewer participants" not in results_markdown(judged, eleven, dataset="lab")


def test_the_robustness_figure_colours_a_verdict_with_its_numbers():
    table = pd.DataFrame({"claim": ["H1", "H2"], "variant": "default", "value": np.nan,
                          "verdict": [claims.too_few(2, 3), "differs"]})  # fmt: skip
    _, _, verdicts, _ = verdict_grid(table)
    assert verdicts[:, 0].tolist() == [claims.VERDICTS.index(claims.TOO_FEW), 2]
    with pytest.raises(ValueError, match="unknown verdict 'not testable: too many'"):
        verdict_grid(table.assign(verdict="not testable: too many"))
