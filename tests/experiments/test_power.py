"""The power target: replicate seeds, detections, the power table, its figure, progress.

The target itself (simulated replicate studies) runs in CI (.ci/run, config/ci.yaml);
here the config, the DAG (a dry run) and every step after the simulation run on tables
whose outcome is known by construction.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pandas as pd
import pytest
import yaml
from scipy.stats import norm

from casa_core.cli import main
from casa_core.config import ConfigError, load_config
from casa_core.experiments import power, progress
from casa_core.figures.power import power_figure
from casa_core.io import read_table
from casa_core.io.atomic import write_csv
from casa_core.stats.margins import Margins
from casa_core.stats.power import (
    DETECTION_COLUMNS,
    METRICS,
    POWER_COLUMNS,
    first_participants,
    power_table,
    replicate_detections,
    wilson_interval,
)
from casa_core.vocabulary import CASA_AFTER_LEARNING, CASA_BEFORE_LEARNING, UNKNOWN_TASKS
from tests.experiments.test_robustness import CI, CONFIG, _overlay, dry_run
from tests.test_config import CI_LAYERS, write_effective_config
from tests.workflow.test_workflow import snakemake

# --- seeds and configs ---------------------------------------------------------------


def test_replicate_seeds_are_distinct_stable_and_from_the_documented_formula():
    seeds = power.replicate_seeds(2021, 200)
    assert len(set(seeds)) == 200
    # The documented derivation: the first 32-bit word of SeedSequence([seed, 7000001, r]).
    for r in (1, 2, 200):
        word = np.random.SeedSequence([2021, power.POWER_STREAM, r]).generate_state(1)[0]
        assert seeds[r - 1] == int(word)
    # Pinned: a change of the derivation changes every replicate study; say so if intended.
    assert seeds[0] == 2375554415
    assert power.replicate_seeds(2021, 200) == seeds
    # Another config seed, other replicates; none is the study's own seed.
    assert not set(power.replicate_seeds(2022, 200)) & set(seeds)
    assert 2021 not in seeds
    with pytest.raises(ValueError, match="1-based"):
        power.replicate_seed(2021, 0)


def test_each_replicate_config_differs_from_the_variants_in_its_seed_only():
    config = load_config(CONFIG)
    base = power.power_variant_config(config, "default")
    assert base["simulation"]["participants"] == 24  # the largest N of the default grid
    assert "power" not in base and "robustness" not in base
    first, second = (power.replicate_config(base, r) for r in (1, 2))
    assert first["simulation"]["seed"] == power.replicate_seed(2021, 1)
    assert second["simulation"]["seed"] == power.replicate_seed(2021, 2)
    assert {**first, "simulation": base["simulation"]} == base
    # Variants share replicate r's seed: they are compared on the same simulated people.
    other = power.replicate_config(power.power_variant_config(config, "paper"), 1)
    assert other["simulation"]["seed"] == first["simulation"]["seed"]
    assert base["simulation"]["seed"] == 2021, "the variant's config is left unchanged"


@pytest.mark.parametrize(
    "block, message",
    [
        ({"variants": ["nope"]}, "power.variants: nope is not a variant of robustness.variants"),
        ({"sizes": [1, 6]}, "power.sizes.0: must be >= 2"),
        ({"replicates": 0}, "power.replicates: must be >= 1"),
        ({"sizes": []}, "power.sizes: must not be empty"),
    ],
)
def test_a_bad_power_block_is_refused_naming_the_key(tmp_path, block, message):
    with pytest.raises(ConfigError, match=message.replace(".", r"\.")):
        load_config(CONFIG, _overlay(tmp_path, {"power": block}))


# --- detections ----------------------------------------------------------------------

#: Condition means of every metric (lower is better), chosen so that H1-H3 hold: CASA
#: far below NA and PBA on Known Goal; before learning CASA far below PBA and 0.1
#: below NA, so that even the independent-samples bound (participant offsets and noise
#: of sd 0.05: standard error about 0.035) stays below every margin (0.035 x NA's 3 =
#: 0.105 at the least); after learning far below NA.
STRONG = {
    "known_goal": {"NA": 3.0, "PBA": 2.0, "CASA": 1.0},
    "misspecified": {"NA": 3.0, "PBA": 4.0, CASA_BEFORE_LEARNING: 2.9, CASA_AFTER_LEARNING: 1.0},
}
METHOD_PHASE = {
    "NA": ("NA", None),
    "PBA": ("PBA", None),
    "CASA": ("CASA", None),
    CASA_BEFORE_LEARNING: ("CASA", "before_learning"),
    CASA_AFTER_LEARNING: ("CASA", "after_learning"),
}


def study_trials(n: int, means=STRONG, *, noise: float = 0.05, seed: int = 0) -> pd.DataFrame:
    """Trials of ``n`` participants: each condition's mean, a participant offset, noise."""
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(1, n + 1):
        offset = rng.normal(0, 0.05)
        for task in ("known_goal", "unknown_goal", "unknown_skill"):
            levels = means["known_goal" if task == "known_goal" else "misspecified"]
            for condition, mean in levels.items():
                method, phase = METHOD_PHASE[condition]
                phase = phase or (
                    "no_misspecification" if task == "known_goal" else "before_learning"
                )
                values = {m: mean + offset + rng.normal(0, noise) for m in METRICS}
                rows.append(dict(participant=f"p{i:02d}", task=task, method=method, phase=phase,
                                 **values))  # fmt: skip
    return pd.DataFrame(rows)


def margins() -> Margins:
    return Margins.from_config(load_config(CONFIG)["statistics"])


def test_a_strong_effect_is_detected_and_no_difference_is_not():
    strong = replicate_detections(
        study_trials(8), sizes=[8], variant="v", replicate=1, margins=margins()
    )
    assert list(strong.columns) == DETECTION_COLUMNS
    # 3 hypotheses x 3 metrics x 2 forms at one N.
    assert len(strong) == 18
    assert strong["detected"].all(), strong[~strong["detected"]]
    # Every condition the same value for a participant: no difference, in any direction.
    flat = {group: dict.fromkeys(levels, 2.0) for group, levels in STRONG.items()}
    null = replicate_detections(
        study_trials(8, flat, noise=0.0), sizes=[8], variant="v", replicate=1, margins=margins()
    )
    assert not null["detected"].any()


def test_the_wrong_direction_is_not_a_detection():
    # H3 with CASA after learning far *above* NA: significant, but not what the paper claims.
    reversed_ = {**STRONG, "misspecified": {**STRONG["misspecified"], CASA_AFTER_LEARNING: 5.0}}
    table = replicate_detections(
        study_trials(8, reversed_), sizes=[8], variant="v", replicate=1, margins=margins()
    )
    h3 = table[table["hypothesis"] == "H3"]
    assert not h3["detected"].any()
    assert table[table["hypothesis"] == "H1"]["detected"].all()


def test_the_detections_read_no_mixed_model_so_skipping_them_changes_none():
    # The detections analyse without the mixed models (most of their time): the table is
    # the full one less its mixedlm rows, and every hypothesis's checks are the same on
    # both, on a study whose noise leaves some checks passed and some not.
    from casa_core.stats import _claim_tests as checks
    from casa_core.stats.study import analyze_study

    study = study_trials(6, noise=0.6, seed=3)
    full = analyze_study(study, margins=margins(), metrics=list(METRICS))
    lean = analyze_study(study, margins=margins(), metrics=list(METRICS), mixed_models=False)
    mixed = full["analysis"].isin(["mixedlm", "mixedlm_lrt"])
    assert mixed.sum() > 0 and not lean["analysis"].isin(["mixedlm", "mixedlm_lrt"]).any()
    pd.testing.assert_frame_equal(lean, full[~mixed].reset_index(drop=True))
    outcomes = set()
    for judge in (checks.h1_checks, checks.h2_checks, checks.h3_checks):
        assert judge(lean, study) == judge(full, study)
        outcomes |= {check.passed for check in judge(full, study)}
    assert outcomes == {True, False}


def test_the_study_of_n_is_the_first_n_participants():
    trials = study_trials(12)
    chosen = first_participants(trials, 10)
    assert sorted(chosen["participant"].unique()) == [f"p{i:02d}" for i in range(1, 11)]
    with pytest.raises(ValueError, match="12 participant"):
        first_participants(trials, 13)


# --- the power table -----------------------------------------------------------------


def test_the_wilson_interval_is_the_closed_form():
    # Wilson (1927): (p + z^2/2n +- z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n), z = 1.96.
    z, k, n = norm.ppf(0.975), 8, 10
    p = k / n
    centre, half = p + z**2 / (2 * n), z * math.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    low, high = wilson_interval(k, n)
    assert low == pytest.approx((centre - half) / (1 + z**2 / n), abs=1e-12)
    assert high == pytest.approx((centre + half) / (1 + z**2 / n), abs=1e-12)
    assert (round(low, 4), round(high, 4)) == (0.4902, 0.9433)
    # 0 of 10: the interval starts at 0 (not the empty Wald interval).
    assert wilson_interval(0, 10)[0] == pytest.approx(0.0, abs=1e-12)


def detections(variant, n, hits, total) -> pd.DataFrame:
    key = dict(
        variant=variant,
        N=n,
        hypothesis="H1",
        metric="error",
        analysis="paper",
        noninferiority_alpha=0.05,
    )
    rows = [key | {"replicate": r, "detected": r <= hits} for r in range(1, total + 1)]
    return pd.DataFrame(rows)


def test_power_is_the_share_of_replicates_that_detect():
    parts = [detections("paper", 6, 3, 4), detections("default", 8, 4, 4)]
    parts.append(detections("default", 6, 1, 4))
    table = power_table(parts)
    assert list(table.columns) == POWER_COLUMNS
    # Variants in the order given, then N.
    assert table[["variant", "N", "power", "replicates"]].values.tolist() == [
        ["paper", 6, 0.75, 4],
        ["default", 6, 0.25, 4],
        ["default", 8, 1.0, 4],
    ]
    assert tuple(table.loc[0, ["ci_low", "ci_high"]]) == pytest.approx(wilson_interval(3, 4))
    with pytest.raises(ValueError, match="replicate 1 of variant paper, N = 6 appears twice"):
        power_table([parts[0], parts[0]])


def test_the_commands_write_the_same_bytes_whatever_the_order(tmp_path):
    trials = [study_trials(3, seed=s) for s in (1, 2)]
    written = []
    for r, table in enumerate(trials, start=1):
        write_csv(tmp_path / f"r{r}" / "trials.csv", table)
        out = tmp_path / f"r{r}" / "detections.csv"
        args = ["power", "detect", "--config", str(CONFIG), "--trials"]
        args += [str(tmp_path / f"r{r}" / "trials.csv"), "--variant", "default"]
        args += ["--replicate", str(r), "--sizes", "3", "2", "--out", str(out)]
        assert main(args) == 0
        written.append(str(out))
    for order, name in ((written, "a.csv"), (written[::-1], "b.csv")):
        assert main(["power", "table", "--detections", *order, "--out", str(tmp_path / name)]) == 0
    first = (tmp_path / "a.csv").read_bytes()
    assert first == (tmp_path / "b.csv").read_bytes()
    table = read_table(tmp_path / "a.csv")
    # 2 Ns x 3 hypotheses x 3 metrics x 2 forms, each from 2 replicates.
    assert len(table) == 36 and set(table["replicates"]) == {2}
    assert set(table["population"]) == {"simulation.population of the config"}
    fitted = ["--population", "lab.json, fitted by casa calibrate to dataset lab"]
    assert main(["power", "table", "--detections", *written, *fitted, "--out",
                 str(tmp_path / "c.csv")]) == 0  # fmt: skip
    assert set(read_table(tmp_path / "c.csv")["population"]) == {fitted[1]}
    assert main(["power", "figure", "--power", str(tmp_path / "a.csv"), "--out",
                 str(tmp_path / "power")]) == 0  # fmt: skip
    assert (tmp_path / "power.png").stat().st_size > 0
    assert (tmp_path / "power.pdf").read_bytes().startswith(b"%PDF")


def test_a_detections_table_without_a_column_is_named(tmp_path, capsys):
    write_csv(tmp_path / "d.csv", pd.DataFrame({"variant": ["v"]}))
    assert main(["power", "table", "--detections", str(tmp_path / "d.csv"), "--out",
                 str(tmp_path / "p.csv")]) == 2  # fmt: skip
    assert "detections table" in capsys.readouterr().err


def test_a_detections_file_that_cannot_be_read_exits_1(tmp_path, capsys):
    # A file that cannot be read is 1, a table that cannot be used 2 (casa_core/cli/_errors.py).
    missing = str(tmp_path / "none.csv")
    assert main(["power", "table", "--detections", missing, "--out", str(tmp_path / "p.csv")]) == 1
    error = capsys.readouterr().err
    assert error.startswith("casa power table: ") and "none.csv" in error, error


def test_the_figure_has_a_panel_per_hypothesis_and_metric():
    rows = []
    for hypothesis in ("H1", "H2", "H3"):
        for metric in METRICS:
            for analysis in ("paper", "within"):
                for n in (6, 11):
                    rows.append(dict(variant="default", N=n, hypothesis=hypothesis,
                                     metric=metric, analysis=analysis,
                                     noninferiority_alpha=0.05, power=0.5,
                                     ci_low=0.3, ci_high=0.7, replicates=20))  # fmt: skip
    fig = power_figure(pd.DataFrame(rows))
    assert len(fig.axes_by_name) == 9
    panel = fig.axes_by_name["H2 efficiency"]
    # The 80 % line and the paper's N, then one line per analysis.
    assert any(list(line.get_ydata()) == [0.8, 0.8] for line in panel.get_lines())
    assert any(list(line.get_xdata()) == [11, 11] for line in panel.get_lines())
    assert sum(len(line.get_xdata()) == 2 and line.get_marker() == "o"
               for line in panel.get_lines()) == 2  # fmt: skip


def test_the_figure_command_names_the_configuration_that_built_the_table(tmp_path, monkeypatch):
    from casa_core.figures import style

    effective, digest = write_effective_config(tmp_path)
    rows = [dict(variant="default", N=n, hypothesis="H1", metric="error", analysis="paper",
                 noninferiority_alpha=0.05, power=0.5, ci_low=0.3, ci_high=0.7,
                 replicates=2) for n in (2, 3)]  # fmt: skip
    write_csv(tmp_path / "power.csv", pd.DataFrame(rows))
    drawn = []
    monkeypatch.setattr(style, "save_figure", lambda fig, prefix: drawn.append(fig) or [prefix])
    args = ["power", "figure", "--power", str(tmp_path / "power.csv"), "--out", "power"]
    assert main([*args, "--config-files", *CI_LAYERS, "--effective-config", str(effective)]) == 0
    # The caption ends with it, from a line of its own (wrapped to the figure's width).
    (fig,) = drawn
    (caption,) = [t.get_text() for t in fig.texts if "Share of simulated" in t.get_text()]
    line = f"Built from config/config.yaml + config/ci.yaml (effective config sha256 {digest})."
    assert "\nBuilt from " in caption
    assert " ".join(caption.split()).endswith(" " + line)


# --- progress ------------------------------------------------------------------------


def _benchmark(path, seconds: float, end: float) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"s\th:m:s\tmax_rss\tcpu_time\n{seconds}\t0:00:00\t1.0\t{seconds}\n")
    os.utime(path, (end, end))


def test_progress_counts_units_and_estimates_the_time_left(tmp_path):
    # Replicate r1 done (2 jobs of 10 s, one after the other, ending at t = 110 and 120);
    # r2 has one of its two jobs done, 10 s ending at t = 120: 30 s of job time in the
    # 20 s from t = 100 to 120, so 1.5 jobs at a time; 1 job of 10 s left -> 10 / 1.5 s.
    _benchmark(tmp_path / "v" / "r1" / "a.tsv", 10.0, 110.0)
    _benchmark(tmp_path / "v" / "r1" / "b.tsv", 10.0, 120.0)
    _benchmark(tmp_path / "v" / "r2" / "a.tsv", 10.0, 120.0)
    jobs = ("a", "b")
    done = progress.read_progress(tmp_path, {"v/r1": jobs, "v/r2": jobs})
    assert (done.units_done, done.units_total, done.jobs_done, done.jobs_total) == (1, 2, 3, 4)
    assert done.seconds_per_unit == 20.0
    assert done.elapsed == 20.0
    assert done.remaining == pytest.approx(10 / 1.5)
    assert done.line("power").startswith("power: 1/2 replicates done (3/4 jobs); 20 s")
    nothing = progress.read_progress(tmp_path / "none", {"v/r1": jobs})
    assert "about unknown left" in nothing.line("power")
    # r1's config rewritten at t = 115 (a new configuration): its job that ended at 110
    # is from the earlier one and not counted; its job at 120 and r2's are.
    config = tmp_path / "r1.yaml"
    config.write_text("")
    os.utime(config, (115.0, 115.0))
    fresh = progress.read_progress(tmp_path, {"v/r1": jobs, "v/r2": jobs}, configs={"v/r1": config})
    assert (fresh.units_done, fresh.jobs_done) == (0, 2)
    # A benchmark that is not one of the unit's jobs (left by another workflow version's
    # job) is not counted: r2 still has one of its two jobs done.
    _benchmark(tmp_path / "v" / "r2" / "p1_before.tsv", 10.0, 120.0)
    stale = progress.read_progress(tmp_path, {"v/r1": jobs, "v/r2": jobs})
    assert (stale.units_done, stale.jobs_done) == (1, 3)


def test_the_units_of_each_target_and_their_jobs():
    ci = load_config(CONFIG, CI)
    # A replicate: 1 job for its 3 participants' protocols, its tables and its
    # detections; a robustness variant: 1 job for its 2 participants' protocols, its
    # tables, statistics, case study and claims.
    replicate = ("participants", "process", "detect")
    variant = ("participants", "process", "stats", "case_study", "claims")
    assert progress.target_units(ci, "power") == {"default/r1": replicate, "default/r2": replicate}
    assert progress.target_units(ci, "robustness") == {
        "default": variant,
        "original": variant,
        "authors": variant,
    }
    with pytest.raises(ValueError, match="no target 'all'"):
        progress.target_units(ci, "all")


def test_the_progress_command_prints_and_logs_a_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the units' configs are looked for below data/interim
    config = _overlay(tmp_path, {"power": {"sizes": [2], "replicates": 2}})
    # A replicate of 2 participants: 1 job for both, its tables, its detections (3 jobs).
    for i, job in enumerate(("participants", "process", "detect")):
        _benchmark(tmp_path / "b" / "power" / "default" / "r1" / f"{job}.tsv", 5.0, 1000.0 + i)
    log = tmp_path / "progress.log"
    args = ["progress", "power", "--config", str(CONFIG), "--config", config]
    args += ["--benchmarks", str(tmp_path / "b"), "--done", "default/r1", "--append", str(log)]
    assert main(args) == 0
    line = capsys.readouterr().out
    assert line.startswith("power: 1/2 replicates done (3/6 jobs); 15 s of job time")
    assert line.rstrip().endswith("(just done: default/r1)")
    assert log.read_text().split(" ", 1)[1] == line


# --- the workflow --------------------------------------------------------------------


@pytest.mark.pipeline
def test_a_dry_run_gives_each_replicate_its_jobs_seed_and_files(tmp_path):
    repo, jobs, counts = dry_run(tmp_path, "power")
    # ci.yaml: sizes 2, 3 and 2 replicates: 3 participants per replicate, one job for all.
    assert counts["power_participants"] == 2
    assert not {"power_participant", "power_before", "power_learn"} & set(counts.index)
    for job in jobs:
        if job["rule"] == "power_participants":
            # Each participant's before and after logs, an intent library, a learning row
            # and a timing row per unknown task: the robustness target's job's files.
            assert "--participant 1 2 3 " in job["shell"], job
            assert len(job["output"]) == 3 * (2 + 3 * len(UNKNOWN_TASKS)), job
            for p in (1, 2, 3):
                assert f"/raw/p{p}/before" in " ".join(job["output"]), job
                assert f"/learning/p{p}_unknown_skill_timing.csv" in " ".join(job["output"])
            assert "/raw/p{p}/before" in job["shell"], job  # filled in by casa
    assert counts["power_process"] == counts["power_detect"] == counts["power_progress"] == 2
    assert counts["power_table"] == counts["power_figure"] == 1
    for job in jobs:
        if "--config data/interim/power/" in job["shell"]:
            replicate = job["shell"].split("--config data/interim/power/")[1].split("/config")[0]
            assert all(f"power/{replicate}/" in path for path in job["output"]), job
    seeds = {
        r: yaml.safe_load((repo / f"data/interim/power/default/r{r}/config.yaml").read_text())
        for r in (1, 2)
    }
    assert [seeds[r]["simulation"]["seed"] for r in (1, 2)] == power.replicate_seeds(2021, 2)
    assert {s["simulation"]["participants"] for s in seeds.values()} == {3}
    default = snakemake(repo, "--dry-run", "--configfile", "config/ci.yaml")
    assert default.returncode == 0, default.stderr
    assert "power_" not in default.stdout
