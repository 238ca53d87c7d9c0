"""The robustness target: variants in the config, their own jobs, the merged claims table.

The target itself (the simulated study under each variant) runs in CI (.ci/run); here
the config, the DAG (a dry run), the claims command and the merge run on small tables.
"""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest
import yaml

from casa_core import cli
from casa_core.config import ConfigError, load_config
from casa_core.experiments import progress
from casa_core.experiments import robustness as variants
from casa_core.figures.robustness import VERDICT_COLOURS, robustness_figure, verdict_grid
from casa_core.stats import STATS_COLUMNS
from casa_core.stats.claims import VERDICTS
from casa_core.stats.robustness import ROBUSTNESS_COLUMNS, merge_variants
from casa_core.vocabulary import UNKNOWN_TASKS
from tests.io.test_logs_synthetic import ROOT
from tests.test_config import CI_LAYERS, write_effective_config
from tests.workflow.test_workflow import copy_workflow, snakemake

CONFIG = ROOT / "config" / "config.yaml"
CI = ROOT / "config" / "ci.yaml"


def _overlay(tmp_path, data) -> str:
    path = tmp_path / "overlay.yaml"
    path.write_text(yaml.safe_dump(data))
    return str(path)


@pytest.mark.parametrize(
    "variant, message",
    [
        (
            {"mine": {"statistics": {"alpha": 0.1}}},
            "robustness.variants.mine.statistics: unknown key (allowed: scene, teleop, inference, "
            "simulation)",
        ),
        ({"mine": {"scene": ""}}, "robustness.variants.mine.scene: must not be empty"),
        (
            {"mine": {"teleop": {"mode": "joystick"}}},
            "robustness.variants.mine.teleop.mode: must be one of None, held, original",
        ),
        ({"mine": {"simulation": {"seed": 3}}}, "robustness.variants.mine.simulation.seed: "),
        (
            {"mine": {"inference": {"preset": "orignal"}}},
            "robustness.variants.mine.inference.preset: must be one of casa, original, paper, "
            "got 'orignal'",
        ),
        (
            {"mine": {"inference": {"evidence": "felt"}}},
            "robustness.variants.mine.inference.evidence: must be one of commanded",
        ),
        (
            {"mine": {"simulation": {"operator": "psychic"}}},
            "robustness.variants.mine.simulation.operator: must be one of lookahead, predictive",
        ),
        (
            {"default": {"inference": {"preset": "paper"}}},
            "robustness.variants.default: must overlay nothing",
        ),
    ],
)
def test_a_bad_variant_is_refused_naming_it_and_the_key(tmp_path, variant, message):
    overlay = _overlay(tmp_path, {"robustness": {"variants": variant}})
    with pytest.raises(ConfigError, match="overlay.yaml") as error:
        load_config(CONFIG, overlay)
    assert message in str(error.value)


def test_the_variants_to_run_must_be_defined(tmp_path):
    overlay = _overlay(tmp_path, {"robustness": {"run": ["default", "orignal"]}})
    with pytest.raises(ConfigError, match=r"robustness.run: orignal is not a variant"):
        load_config(CONFIG, overlay)


def test_a_variant_changes_only_its_overlay_and_keeps_the_seeds():
    study = load_config(CONFIG)
    names = variants.variant_names(study)
    assert names == [
        "default",
        "original",
        "paper",
        "executed",
        "lookahead",
        "authors",
        "authors_via_green",
    ]
    for name in names:
        built = variants.variant_config(study, name)
        overlay = study["robustness"]["variants"][name]
        # Undo the overlay and the participant count: what is left is the study's config.
        undone = {**built, "inference": study["inference"]}
        undone.update(scene=study["scene"], teleop=study["teleop"])
        undone["simulation"] = {**built["simulation"], "operator": study["simulation"]["operator"]}
        undone["simulation"]["participants"] = study["simulation"]["participants"]
        expected = {k: v for k, v in study.items() if k not in variants.RUNNING_BLOCKS}
        assert undone == expected, name
        assert built["simulation"]["seed"] == study["simulation"]["seed"]
        assert built["inference"] == {**study["inference"], **overlay.get("inference", {})}
    assert variants.variant_config(study, "default")["inference"] == study["inference"]
    # The authors' setup: their layout, whose scene file says how its keys move the arm.
    authors = variants.variant_config(study, "authors")
    assert authors["scene"] == "config/scene-original.yaml" and authors["teleop"]["mode"] is None
    assert variants.settings_text(authors).startswith("scene scene-original.yaml (teleop original)")
    assert variants.settings_text(study).startswith("scene scene.yaml (teleop held)")
    with pytest.raises(KeyError, match="no variant 'nope'"):
        variants.variant_config(study, "nope")


def _jobs(text: str) -> list[dict]:
    """The jobs of a dry run: rule, output paths, benchmark file and shell command of each."""
    jobs = []
    for block in re.split(r"\n(?=(?:local)?rule \w+:)", text):
        match = re.match(r"(?:local)?rule (\w+):", block)
        if not match:
            continue
        output = re.search(r"^\s+output: (.*)$", block, re.M)
        shell = re.search(r"^Shell command: (.*)$", block, re.M)
        benchmark = re.search(r"^\s+benchmark: (.*)$", block, re.M)
        jobs.append(
            {
                "rule": match.group(1),
                "output": output.group(1).split(", ") if output else [],
                "benchmark": benchmark.group(1) if benchmark else "",
                "shell": shell.group(1) if shell else "",
            }
        )
    return jobs


def dry_run(tmp_path, target: str):
    """A copy of the workflow, the jobs of a dry run of ``target`` on the CI config, and
    the count of each rule's jobs; no two jobs may write one path."""
    repo = copy_workflow(tmp_path / "wf")
    result = snakemake(repo, "--dry-run", target, "--configfile", "config/ci.yaml")
    assert result.returncode == 0, result.stdout + result.stderr
    jobs = _jobs(result.stdout)
    outputs = [path for job in jobs for path in job["output"]]
    assert len(outputs) == len(set(outputs)), "two jobs write one path"
    return repo, jobs, pd.Series([job["rule"] for job in jobs]).value_counts()


@pytest.mark.pipeline
def test_a_dry_run_gives_each_variant_its_own_jobs_config_and_files(tmp_path):
    repo, jobs, counts = dry_run(tmp_path, "robustness")
    # ci.yaml: 3 variants x 2 participants, one job per variant (their whole protocols).
    assert counts["robustness_participants"] == 3
    assert not {"robustness_participant", "robustness_before"} & set(counts.index)
    assert counts["robustness_process"] == counts["robustness_claims"] == 3
    assert counts["robustness_case_study"] == 3
    assert counts["robustness_table"] == 1
    assert counts["robustness_progress"] == 3  # a line after each variant
    # Each variant's tables measure against its own setup's scene.
    scenes = {
        job["output"][0].split("/")[3]: job["shell"].split("--scene ")[1].split()[0]
        for job in jobs
        if job["rule"] == "robustness_process"
    }
    assert scenes == {
        "default": "config/scene.yaml",
        "original": "config/scene.yaml",
        "authors": "config/scene-original.yaml",
    }
    for job in jobs:
        if job["rule"] == "robustness_participants":
            # Each participant's before and after logs, an intent library, a learning row
            # and a timing row per unknown task, all kept; {p} filled in by casa.
            assert "--participant 1 2 " in job["shell"], job
            assert len(job["output"]) == 2 * (2 + 3 * len(UNKNOWN_TASKS)), job
            for p in (1, 2):
                assert f"/raw/p{p}/after" in " ".join(job["output"]), job
                assert f"/learning/p{p}_unknown_goal.csv" in " ".join(job["output"]), job
            assert "/raw/p{p}/before" in job["shell"], job
        if job["rule"] == "robustness_table":
            continue
        for name in ("default", "original"):
            if f"/robustness/{name}/" in " ".join(job["output"]):
                # Everything a variant's job writes, and the config it reads, is its own.
                assert all(f"/robustness/{name}/" in path for path in job["output"]), job
                # The progress line counts every variant's jobs: it reads the whole config.
                if "--config" in job["shell"] and job["rule"] != "robustness_progress":
                    assert f"--config data/interim/robustness/{name}/config.yaml" in job["shell"]
                if job["rule"] == "robustness_claims":
                    # C3 and the expert rows from the variant's own case study.
                    case_study = f"data/processed/robustness/{name}/case_study"
                    assert f"--case-steps {case_study}/steps.csv" in job["shell"]
                    assert f"--arbitration {case_study}/arbitration.csv" in job["shell"]
    # casa progress counts a variant done when all its benchmarked jobs are.
    units = progress.target_units(load_config(CONFIG, CI), "robustness")
    for name, expected in units.items():
        folder = f"benchmarks/robustness/{name}/"
        benchmarks = {job["benchmark"] for job in jobs if job["benchmark"].startswith(folder)}
        assert benchmarks == {f"{folder}{job}.tsv" for job in expected}, name
    written = {
        name: yaml.safe_load((repo / f"data/interim/robustness/{name}/config.yaml").read_text())
        for name in ("default", "original")
    }
    assert written["default"]["inference"]["preset"] == "casa"
    assert written["original"]["inference"]["preset"] == "original"
    assert {config["simulation"]["participants"] for config in written.values()} == {2}
    assert {config["simulation"]["seed"] for config in written.values()} == {2021}
    # The default target includes the whole target, the same jobs; without the simulated
    # study (simulate=false) it includes none of them.
    default = snakemake(repo, "--dry-run", "--configfile", "config/ci.yaml")
    assert default.returncode == 0, default.stderr
    in_default = pd.Series([job["rule"] for job in _jobs(default.stdout)]).value_counts()
    own = counts.drop("robustness").to_dict()
    assert {rule: in_default.get(rule) for rule in own} == own
    assert "output: data/processed/robustness/claims.csv," in default.stdout
    without = snakemake(
        repo, "--dry-run", "--config", "simulate=false", "--configfile", "config/ci.yaml"
    )
    assert without.returncode == 0, without.stderr
    assert "robustness" not in without.stdout


def _claims_rows(variant: str, verdicts: dict[str, str]) -> pd.DataFrame:
    rows = [
        {
            "claim": claim,
            "variant": variant,
            "verdict": verdict,
            "value": {"holds": 1.0, "partly": 0.6, "differs": 0.1}.get(verdict, np.nan),
            "settings": f"preset {variant}",
            "criterion": f"criterion of {claim}",
            "measured": f"{claim} under {variant}",
        }
        for claim, verdict in verdicts.items()
    ]
    return pd.DataFrame(rows, columns=ROBUSTNESS_COLUMNS)


def test_the_merge_writes_the_table_results_and_figure(tmp_path):
    paper = _claims_rows("paper", {"C1": "differs", "H1": "partly"})
    default = _claims_rows("default", {"C1": "holds", "H1": "not testable"})
    paths = []
    for frame in (paper, default):
        paths.append(tmp_path / f"{frame['variant'][0]}.csv")
        frame.to_csv(paths[-1], index=False)
    out = tmp_path / "out"
    argv = ["report", "robustness", "--claims", *map(str, paths), "--out-csv"]
    argv += [str(out / "claims.csv"), "--out-md", str(out / "results.md")]
    assert cli.main([*argv, "--figure", str(out / "robustness")]) == 0
    merged = pd.read_csv(out / "claims.csv")
    # Claims in their order, the default variant first within each.
    assert list(zip(merged["claim"], merged["variant"], strict=True)) == [
        ("C1", "default"),
        ("C1", "paper"),
        ("H1", "default"),
        ("H1", "paper"),
    ]
    assert merged["verdict"].tolist() == ["holds", "differs", "not testable", "partly"]
    text = (out / "results.md").read_text()
    assert "| C1 | holds (1.00) | differs (0.10) |" in text
    assert "| H1 | not testable | partly (0.60) |" in text
    assert "- `default` (default): preset default" in text and "- `paper`: preset paper" in text
    for suffix in ("pdf", "png"):
        assert (out / f"robustness.{suffix}").stat().st_size > 0
    # The same variant twice is refused, naming the claim and the variant.
    with pytest.raises(ValueError, match="claim C1 of variant paper is given twice"):
        merge_variants([paper, paper])


def test_the_merge_names_the_configuration_that_built_it(tmp_path):
    effective, digest = write_effective_config(tmp_path)
    paths = []
    for frame in (
        _claims_rows("default", {"C1": "holds"}),
        _claims_rows("paper", {"C1": "partly"}),
    ):
        paths.append(tmp_path / f"{frame['variant'][0]}.csv")
        frame.to_csv(paths[-1], index=False)
    out = tmp_path / "out"
    argv = ["report", "robustness", "--claims", *map(str, paths), "--out-csv"]
    argv += [str(out / "claims.csv"), "--out-md", str(out / "results.md")]
    argv += ["--figure", str(out / "robustness"), "--config-files", *CI_LAYERS]
    argv += ["--effective-config", str(effective)]
    assert cli.main(argv) == 0
    line = f"Built from config/config.yaml + config/ci.yaml (effective config sha256 {digest})."
    assert (out / "results.md").read_text().splitlines()[:3] == [
        "# Claims of the paper under each modelling variant",
        "",
        line,
    ]
    merged = pd.read_csv(out / "claims.csv")
    assert list(merged.columns) == [*ROBUSTNESS_COLUMNS, "config"]
    # A constant column, the line's words.
    assert set(merged["config"]) == {line.removeprefix("Built from ").removesuffix(".")}
    first = {name: (out / name).read_bytes() for name in ("claims.csv", "results.md")}
    assert cli.main(argv) == 0
    assert {name: (out / name).read_bytes() for name in first} == first


def test_the_figure_colours_each_cell_by_its_verdict_and_frames_the_default():
    claims = pd.concat(
        [
            _claims_rows("default", {"C1": "holds", "H4": "not testable: model output"}),
            _claims_rows("original", {"C1": "differs"}),
        ]
    )
    rows, cols, verdicts, _ = verdict_grid(claims)
    assert rows == ["C1", "H4"] and cols == ["default", "original"]
    # Indices into VERDICTS; -1 where a variant has no row for the claim.
    assert verdicts.tolist() == [[0, 2], [4, -1]]
    fig = robustness_figure(claims)
    ax = fig.axes_by_name["grid"]
    image = ax.get_images()[0]
    colour = image.cmap(image.norm(image.get_array()[0, 0]))
    assert np.allclose(colour[:3], _rgb(VERDICT_COLOURS["holds"]))
    frames = [p for p in ax.patches if not p.get_fill()]
    assert len(frames) == 1 and frames[0].get_x() == -0.5  # around the first column
    assert [t.get_text() for t in ax.get_xticklabels()] == ["default\n(default)", "original"]
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == [v for v in VERDICTS if v in ("holds", "differs", VERDICTS[4])]
    with pytest.raises(ValueError, match="unknown verdict 'fine'"):
        verdict_grid(claims.assign(verdict="fine"))


def _rgb(hex_colour: str) -> tuple[float, ...]:
    return tuple(int(hex_colour[i : i + 2], 16) / 255 for i in (1, 3, 5))


def _small_tables(folder):
    """One Known Goal CASA trial whose true goal ends confident and assisted."""
    steps = pd.DataFrame(
        {
            "participant": "p1",
            "task": "known_goal",
            "method": "CASA",
            "phase": "no_misspecification",
            "t": [0.0, 0.0, 5.0, 5.0],
            "alpha": [1.0, 1.0, 0.3, 0.3],
            "intent": ["green", "purple"] * 2,
            "beta": [0.0, 0.0, 2.5, 0.3],
        }
    )
    trials = steps.iloc[:1][["participant", "task", "method", "phase"]]
    trials = trials.assign(error=0.1, efficiency=0.2, relative_effort=1.0)
    paths = {}
    for name, frame in (
        ("trials", trials),
        ("steps", steps),
        ("stats", pd.DataFrame(columns=STATS_COLUMNS)),
    ):
        paths[name] = folder / f"{name}.csv"
        frame.to_csv(paths[name], index=False)
    return paths


def test_the_claims_command_writes_one_variants_rows(tmp_path):
    paths = _small_tables(tmp_path)
    config = tmp_path / "config.yaml"
    study = load_config(CONFIG)
    config.write_text(yaml.safe_dump(variants.variant_config(study, "original")))
    out = tmp_path / "claims.csv"
    argv = ["report", "claims", *(f"--{name}={path}" for name, path in paths.items())]
    argv += ["--variant", "original", "--config", str(config), "--epsilon", "1.0"]
    assert cli.main([*argv, "--out", str(out)]) == 0
    claims = pd.read_csv(out, keep_default_na=False)
    assert list(claims.columns) == ROBUSTNESS_COLUMNS
    assert set(claims["variant"]) == {"original"}
    expected = (
        "scene scene.yaml (teleop held), preset original, evidence executed, operator predictive"
    )
    assert set(claims["settings"]) == {expected}
    # By construction: green ends the most confident (2.5 > epsilon 1) and alpha falls to
    # 0.3 < 0.5 in the one Known Goal trial, so C1 holds with a share of 1.
    c1 = claims.set_index("claim").loc["C1"]
    assert c1["verdict"] == "holds" and float(c1["value"]) == 1.0
    assert claims["claim"].tolist()[:4] == ["C1", "C2", "C3", "C4"]
    assert claims.set_index("claim").loc["C3", "verdict"] == "not testable"
    # With the variant's arbitration comparison C3 is judged: belief arbitration's alpha
    # falls to 0.2 < 0.5, beta_hat stays at 0.4 <= epsilon 1 and confidence arbitration's
    # alpha at 1 >= 0.95, so all three conditions hold.
    arbitration = pd.DataFrame(
        {"t": [0.0, 1.0], "intent": "green", "belief": [0.5, 0.9], "beta": [0.1, 0.4]}
        | {"alpha_distance": 1.0, "alpha_belief": [1.0, 0.2], "alpha_confidence": 1.0}
    )
    arbitration.to_csv(tmp_path / "arbitration.csv", index=False)
    assert (
        cli.main([*argv, "--arbitration", str(tmp_path / "arbitration.csv"), "--out", str(out)])
        == 0
    )
    c3 = pd.read_csv(out).set_index("claim").loc["C3"]
    assert c3["verdict"] == "holds" and c3["value"] == 1.0


def test_the_claims_command_names_a_table_that_lacks_a_column(tmp_path, capsys):
    paths = _small_tables(tmp_path)
    pd.read_csv(paths["steps"]).drop(columns="alpha").to_csv(paths["steps"], index=False)
    argv = ["report", "claims", *(f"--{name}={path}" for name, path in paths.items())]
    argv += ["--variant", "x", "--out", str(tmp_path / "claims.csv")]
    assert cli.main(argv) == 2
    error = capsys.readouterr().err
    assert "steps table" in error and "alpha" in error, error
    assert not (tmp_path / "claims.csv").exists()


def test_a_simulated_datasets_results_md_names_its_choices_and_points_to_the_table():
    from casa_core.stats.claims import evaluate_claims
    from casa_core.stats.results import ROBUSTNESS_NOTE, results_markdown

    steps = pd.DataFrame(
        {"participant": "p1", "task": "known_goal", "method": "CASA"}
        | {"phase": "no_misspecification", "t": [0.0, 5.0], "alpha": [1.0, 0.3]}
        | {"intent": "green", "beta": [0.0, 2.5]}
    )
    trials = steps.iloc[:1][["participant", "task", "method", "phase"]]
    trials = trials.assign(error=0.1, efficiency=0.2, relative_effort=1.0, preset="casa")
    trials = trials.assign(evidence="commanded")
    for source, shown in (("simulated", True), ("human", False)):
        tables = {
            "trials": trials.assign(source=source),
            "steps": steps,
            "stats": pd.DataFrame(columns=STATS_COLUMNS),
        }
        judged = evaluate_claims(tables, epsilon=1.0)
        text = results_markdown(judged, tables, dataset="d", operator="predictive")
        assert (ROBUSTNESS_NOTE in text) is shown
        assert ("preset casa, evidence commanded, operator model predictive" in text) is shown
        setup = "scene scene-original.yaml (teleop original)"
        text = results_markdown(judged, tables, dataset="d", operator="predictive", setup=setup)
        assert (f"defaults): {setup}, preset casa" in text) is shown
    assert "`snakemake --cores all robustness`" in ROBUSTNESS_NOTE
