"""Non-inferiority margins: the config's statistics section, casa stats' options, the tests."""

from __future__ import annotations

import pandas as pd
import pytest

from casa_core import cli
from casa_core.config import load_config
from casa_core.stats import analyze_study
from casa_core.stats.margins import Margins, parse_margin
from tests.stats.test_stats_study import make_trials

CONFIG = "config/config.yaml"


@pytest.fixture(scope="module")
def known() -> pd.DataFrame:
    trials = make_trials(n_participants=11, seed=0)
    return trials[trials["task"] == "known_goal"]


def test_default_margins_are_the_papers_bounds():
    # The paper (Sec. V-B) reports relative-effort bounds 0.065 (Known Goal), 0.035 (Unknown
    # Goal), 0.03 (Unknown Skill); the defaults take them as margins, and the same
    # fractions of the reference's mean for error and efficiency (config.schema.yaml).
    statistics = load_config(CONFIG)["statistics"]
    paper = {"known_goal": 0.065, "unknown_goal": 0.035, "unknown_skill": 0.03}
    absolute, fractions = (
        statistics[k] for k in ("noninferiority_margins", "noninferiority_fractions")
    )
    assert {k: v for k, v in absolute.items() if v is not None} == {"relative_effort": paper}
    assert {k: v for k, v in fractions.items() if v is not None} == {
        "error": paper,
        "efficiency": paper,
    }
    margins = Margins.from_config(statistics)
    assert margins.absolute_for("unknown_skill", "relative_effort") == 0.03
    assert margins.fraction_for("known_goal", "error") == 0.065
    assert margins.absolute_for("known_goal", "error") is None


def test_config_margins_are_checked():
    from casa_core.config import ConfigError

    bad = {"statistics": {"noninferiority_margins": {"error": "x"}}}
    with pytest.raises(ConfigError, match="error: must be a number or a mapping or null"):
        load_config(CONFIG, overrides=bad)
    bad = {"statistics": {"noninferiority_margins": {"error": {"known": 1.0}}}}
    with pytest.raises(ConfigError, match="did you mean known_goal"):
        load_config(CONFIG, overrides=bad)
    # One metric overridden: the others keep their defaults.
    ok = {"statistics": {"noninferiority_margins": {"error": 0.5}}}
    margins = Margins.from_config(load_config(CONFIG, overrides=ok)["statistics"])
    assert margins.absolute_for("unknown_goal", "error") == 0.5
    assert margins.absolute_for("unknown_goal", "relative_effort") == 0.035


def test_margins_reject_bad_values():
    with pytest.raises(ValueError, match="error: a margin must be a positive number"):
        Margins.from_config({"noninferiority_margins": {"error": -1.0}})
    with pytest.raises(ValueError, match="known_goal:error: 'x' is not a number"):
        Margins.from_config({"noninferiority_margins": {"error": {"known_goal": "x"}}})
    with pytest.raises(ValueError, match="expected METRIC=VALUE"):
        parse_margin("error")
    with pytest.raises(ValueError, match="positive"):
        parse_margin("error=0")


def test_fraction_margin_is_the_fraction_of_the_reference_mean(known):
    # H1 compares CASA with PBA: margin = 0.1 x the mean of PBA's participant cells.
    margins = Margins(fractions={"error": 0.1})
    table = analyze_study(known, metrics=["error"], margins=margins)
    rows = table[(table["hypothesis"] == "H1") & (table["analysis"] == "noninferiority")]
    cells = known[known["method"] == "PBA"].groupby("participant")["error"].mean()
    # stats.csv holds 8 significant digits (stats._rows.DIGITS).
    assert rows["margin"].to_numpy() == pytest.approx([0.1 * cells.mean()] * 3, rel=1e-8)
    assert rows["note"].str.contains("margin 0.1 x mean\\(PBA\\)", regex=True).all()
    # The verdict is the test at that margin: non-inferior exactly when the bound is below.
    assert (rows["noninferior"] == (rows["ci_high"] < rows["margin"])).all()


def test_absolute_margin_wins_over_a_fraction(known):
    margins = Margins(absolute={"known_goal:error": 2.0}, fractions={"error": 0.1})
    table = analyze_study(known, metrics=["error"], margins=margins)
    rows = table[(table["hypothesis"] == "H1") & (table["analysis"] == "noninferiority")]
    assert (rows["margin"] == 2.0).all()


def test_cli_margins(tmp_path, known, capsys):
    known.to_csv(tmp_path / "trials.csv", index=False)
    out_csv, out_md = tmp_path / "stats.csv", tmp_path / "stats.md"
    base = ["stats", "--trials", str(tmp_path / "trials.csv"), "--out-csv", str(out_csv)]
    base += ["--out-md", str(out_md)]
    options = Margins(absolute={"relative_effort": 0.065}, fractions={"error": 0.1}).options()
    code = cli.main(base + " ".join(options).split())
    assert code == 0
    written = pd.read_csv(out_csv, keep_default_na=False, na_values=[""])
    rows = written[(written["hypothesis"] == "H1") & (written["analysis"] == "noninferiority")]
    assert (rows.loc[rows["metric"] == "relative_effort", "margin"] == 0.065).all()
    assert rows.loc[rows["metric"] == "error", "noninferior"].notna().all()
    assert cli.main(base + ["--margin", "error=-2"]) == 2
    assert "--margin 'error=-2': a margin must be a positive number" in capsys.readouterr().err


def test_cli_without_margin_options_takes_the_configs_as_the_workflow_does(tmp_path, known):
    # `casa stats` as its --help shows it: the same margins as the workflow's stats.csv,
    # those of the config (default: the package's).
    from casa_core.config import DEFAULT_CONFIG

    known.to_csv(tmp_path / "trials.csv", index=False)
    by_hand, workflow = tmp_path / "hand.csv", tmp_path / "workflow.csv"
    base = ["stats", "--trials", str(tmp_path / "trials.csv"), "--out-md", str(tmp_path / "s.md")]
    assert cli.main([*base, "--out-csv", str(by_hand)]) == 0
    options = Margins.from_config(load_config(DEFAULT_CONFIG)["statistics"]).options()
    assert cli.main([*base, "--out-csv", str(workflow), *" ".join(options).split()]) == 0
    assert by_hand.read_bytes() == workflow.read_bytes()
    written = pd.read_csv(by_hand, keep_default_na=False, na_values=[""])
    # The config gives margins for these three; effort (key-ticks) has none.
    metrics = ["error", "efficiency", "relative_effort"]
    rows = written[(written["analysis"] == "noninferiority") & written["estimate"].notna()]
    assert set(rows["metric"]) > set(metrics)
    assert rows.loc[rows["metric"].isin(metrics), "margin"].notna().all()
