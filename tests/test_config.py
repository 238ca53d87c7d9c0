"""The workflow config: one schema, one loader, errors naming the file and the key."""

from __future__ import annotations

import hashlib
import inspect
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

import casa_core
from casa_core import defaults
from casa_core.assist import assistant, presets
from casa_core.config import (
    DEFAULT_CONFIG,
    SCHEMA_PATH,
    TARGET_KEYS,
    ConfigError,
    Provenance,
    config_digest,
    config_text,
    default,
    load_config,
    merge,
    schema,
    validate_config,
)
from casa_core.scene import DEFAULT_SCENE, load_scene
from casa_core.vocabulary import INTERMITTENT_PARAMETERS
from tests.io.test_logs_synthetic import ROOT, write_dataset
from tests.workflow.test_workflow import ENV, copy_workflow, snakemake

CONFIG = ROOT / "config" / "config.yaml"
CI = ROOT / "config" / "ci.yaml"
CASA = str(Path(sys.executable).parent / "casa")
#: The CI configuration's files, named as the workflow's config_layers() names them.
CI_LAYERS = ["config/config.yaml", "config/ci.yaml"]


def write_effective_config(folder: Path) -> tuple[Path, str]:
    """The CI configuration's effective config, written as the workflow writes it, and
    its digest by hand: the first 12 hex digits of the sha256 of the file's bytes."""
    path = folder / "effective.yaml"
    path.write_text(config_text(load_config(CONFIG, CI)), encoding="utf-8")
    return path, hashlib.sha256(path.read_bytes()).hexdigest()[:12]


def _objects(node: dict, key: str = ""):
    """Every object node of the schema with its dotted key."""
    if node.get("type") == "object":
        yield key, node
        for name, sub in node.get("properties", {}).items():
            yield from _objects(sub, f"{key}.{name}" if key else name)


def _keys(node) -> set[str]:
    """Every key of a nested mapping, at any depth."""
    if not isinstance(node, dict):
        return set()
    return set(node).union(*(_keys(value) for value in node.values()))


def test_the_schema_closes_every_level_and_every_key_is_required_or_defaulted():
    objects = dict(_objects(schema()))
    assert {"", "simulation", "simulation.population", "case_study"} <= set(objects)
    assert "simulation.population.max_keys" in objects
    for key, node in objects.items():
        if key == "robustness.variants":
            # A mapping of variant names; each value an overlay, closed at every level and
            # without defaults (a default would override the study's own setting).
            overlay = node["additionalProperties"]
            assert overlay["additionalProperties"] is False
            assert overlay["properties"]["simulation"]["additionalProperties"] is False
            assert "default" not in _keys(overlay), overlay
            continue
        assert node["additionalProperties"] is False, key
        assert "required" in node, key
        for name, sub in node["properties"].items():
            if key == "simulation.population" and name in INTERMITTENT_PARAMETERS:
                # Optional without a default: absent, the config and its operators are
                # those of a config that predates them.
                assert "default" not in sub and name not in node["required"], name
                assert sub["description"].startswith("Optional."), name
                continue
            assert ("default" in sub) != (name in node["required"]), f"{key}.{name}"
            assert "type" in sub or "enum" in sub, f"{key}.{name}"


def test_the_schema_is_package_data():
    assert SCHEMA_PATH.parent == Path(casa_core.__file__).parent
    assert SCHEMA_PATH.suffix == ".yaml"  # pyproject's package-data takes **/*.yaml


def test_the_schema_defaults_are_the_models():
    parameters = inspect.signature(assistant.Assistant).parameters
    for section in ("simulation", "case_study"):
        assert default(f"{section}.epsilon") == defaults.EPSILON
    # The default preset's evidence is the assistant's default; the config overrides none.
    assert default("inference.preset") == presets.DEFAULT_PRESET
    chosen = presets.preset(default("inference.preset"))
    assert chosen.evidence == parameters["evidence"].default
    assert chosen.idle_is_evidence == parameters["idle_is_evidence"].default
    assert default("inference.evidence") is None
    assert default("simulation.demonstrations") == defaults.DEMONSTRATIONS


def test_the_study_config_is_complete_and_ci_only_overlays_it():
    study = load_config(CONFIG)
    assert study == load_config(DEFAULT_CONFIG)
    ci = load_config(CONFIG, CI)
    assert ci["simulation"]["participants"] == 3
    # The robustness target in CI: 2 participants under the default and original variants,
    # and the authors' setup.
    assert ci["robustness"]["participants"] == 2
    assert ci["robustness"]["run"] == ["default", "original", "authors"]
    assert ci["robustness"]["variants"] == study["robustness"]["variants"]
    ci["simulation"]["participants"] = study["simulation"]["participants"]
    ci["robustness"] = study["robustness"]
    # The power target in CI: N of 2 and 3, 2 replicates, the default variant.
    assert ci["power"] == {**study["power"], "sizes": [2, 3], "replicates": 2}
    ci["power"] = study["power"]
    assert ci == study
    assert yaml.safe_load(CI.read_text()) == {
        "simulation": {"participants": 3},
        "robustness": {"participants": 2, "run": ["default", "original", "authors"]},
        "power": {"sizes": [2, 3], "replicates": 2},
    }


def test_defaults_are_filled_in_from_the_schema():
    data = yaml.safe_load(CONFIG.read_text())
    for key in ("allow_invalid", "simulate"):
        del data[key]
    del data["inference"]
    for key in ("max_duration", "demonstrations", "demonstrations_when", "epsilon"):
        del data["simulation"][key]
    config = validate_config(data)
    assert config == load_config(CONFIG)
    assert config["case_study"]["epsilon"] == 1.0 and config["simulation"]["max_duration"] == 40.0


@pytest.mark.parametrize(
    "overlay, message",
    [
        (
            {"simulation": {"max_duraton": 20.0}},
            "overlay.yaml: simulation.max_duraton: unknown key; did you mean max_duration?",
        ),
        (
            {"simulation": {"demonstrations_whn": "detected"}},
            "overlay.yaml: simulation.demonstrations_whn: unknown key",
        ),
        (
            {"simulation": {"populaton": {}}},
            "overlay.yaml: simulation.populaton: unknown key; did you mean population?",
        ),
        (
            {"simulation": {"population": {"deadband": {"median": 0.01, "sgima": 0.1}}}},
            "overlay.yaml: simulation.population.deadband.sgima: unknown key",
        ),
        ({"inference": {"evidence": "felt"}}, "inference.evidence: must be one of commanded"),
        ({"inference": {"preset": "orignal"}}, "inference.preset: must be one of casa, original"),
        ({"simulation": {"participants": 0}}, "simulation.participants: must be >= 1, got 0"),
        ({"simulation": {"epsilon": "high"}}, "simulation.epsilon: must be a number, got 'high'"),
        ({"simulation": 3}, "overlay.yaml: simulation: must be a mapping, got 3"),
        (
            {"simulation": {"population": {"max_keys": {"values": [1, 2]}}}},
            "simulation.population.max_keys.p: must have as many entries as values (2)",
        ),
        (
            {"simulation": {"population": {"max_keys": {"values": [1, 2], "p": [0.5, 0.4]}}}},
            "simulation.population.max_keys.p: must sum to 1, got 0.9",
        ),
    ],
)
def test_a_bad_overlay_is_refused_naming_the_file_and_the_key(tmp_path, overlay, message):
    path = tmp_path / "overlay.yaml"
    path.write_text(yaml.safe_dump(overlay))
    with pytest.raises(ConfigError, match="overlay.yaml") as error:
        load_config(CONFIG, path)
    assert message in str(error.value)


def test_a_missing_required_key_is_named(tmp_path):
    # Every section has its defaults; a parameter given as a mapping needs all of its keys.
    data = yaml.safe_load(CONFIG.read_text())
    population = data["simulation"]["population"]
    del population["reaction_time"]["sigma"]
    del population["max_keys"]["p"]
    path = tmp_path / "partial.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError) as error:
        load_config(path)
    where = f"{path}: simulation.population"
    assert str(error.value).splitlines() == [
        f"{where}.max_keys.p: missing (required)",
        f"{where}.reaction_time.sigma: missing (required)",
    ]


def test_no_file_gives_the_repositorys_config_from_any_folder(tmp_path, monkeypatch):
    # The commands fall back on the schema's defaults when no --config is given: they must
    # be the study's settings, config/config.yaml's, or the two would drift apart.
    monkeypatch.chdir(tmp_path)
    package = load_config()
    study = load_config(CONFIG)
    assert {**package, "scene": study["scene"]} == study
    # The scene: null, the package's own, the file config/config.yaml names.
    assert package["scene"] is None
    assert load_scene(package["scene"]) == load_scene(ROOT / study["scene"])
    assert (ROOT / study["scene"]).resolve() == DEFAULT_SCENE
    # Overrides alone apply over the defaults.
    assert load_config(overrides={"simulation": {"participants": "3"}}) == merge(
        load_config(), {"simulation": {"participants": 3}}
    )


def test_command_line_strings_become_the_schemas_types():
    config = load_config(
        CONFIG, overrides={"allow_invalid": "true", "simulation": {"participants": "3"}}
    )
    assert config["allow_invalid"] is True and config["simulation"]["participants"] == 3
    with pytest.raises(ConfigError, match="--config: allow_invalid: must be a boolean"):
        load_config(CONFIG, overrides={"allow_invalid": "maybe"})
    # List items as Snakemake hands them over (strings), converted as single values are.
    config = load_config(CONFIG, overrides={"power": {"sizes": ["10", "12"], "replicates": "20"}})
    assert config["power"]["sizes"] == [10, 12] and config["power"]["replicates"] == 20
    with pytest.raises(ConfigError, match="--config: power.sizes.0: must be an integer"):
        load_config(CONFIG, overrides={"power": {"sizes": ["ten"]}})


@pytest.mark.pipeline
def test_snakemake_takes_list_values_on_the_command_line(workflow_copy):
    config = "power={sizes: [10, 12], replicates: 20}"
    result = snakemake(workflow_copy, "--dry-run", "power", "--config", config)
    assert result.returncode == 0, result.stdout + result.stderr
    seen = yaml.safe_load((workflow_copy / "data" / "interim" / "config.yaml").read_text())
    assert seen["power"]["sizes"] == [10, 12] and seen["power"]["replicates"] == 20


def test_unreadable_files_are_named(tmp_path):
    with pytest.raises(ConfigError, match="cannot read the config .*nowhere.yaml"):
        load_config(tmp_path / "nowhere.yaml")
    (tmp_path / "list.yaml").write_text("- 1\n")
    with pytest.raises(ConfigError, match="list.yaml: must be a mapping"):
        load_config(tmp_path / "list.yaml")


@pytest.fixture
def workflow_copy(tmp_path):
    return copy_workflow(tmp_path / "wf")


@pytest.mark.pipeline
@pytest.mark.parametrize(
    "where, old, new, message",
    [
        ("config/ci.yaml", "participants: 3", "max_duraton: 20.0", "simulation.max_duraton"),
        (
            "config/config.yaml",
            "demonstrations_when:",
            "demonstrations_whn:",
            "simulation.demonstrations_whn",
        ),
        ("config/config.yaml", "  population:", "  populaton:", "simulation.populaton"),
        # Every key has a default now; a value out of range is still refused.
        (
            "config/config.yaml",
            "  participants: 11\n",
            "  participants: 0\n",
            "simulation.participants: must be >= 1",
        ),
    ],
)
def test_snakemake_dry_run_refuses_a_bad_config_naming_the_key(
    workflow_copy, where, old, new, message
):
    path = workflow_copy / where
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new))
    overlay = ["--configfile", where] if where == "config/ci.yaml" else []
    result = snakemake(workflow_copy, "--dry-run", *overlay)
    assert result.returncode != 0
    text = result.stdout + result.stderr
    assert "ConfigError" in text and message in text, text[-2000:]
    if overlay:
        assert f"config/ci.yaml: {message}: unknown key" in text


@pytest.mark.pipeline
@pytest.mark.parametrize(
    "args, message",
    [
        (["--config", "allow_invalid=maybe"], "--config: allow_invalid: must be a boolean"),
        (["--config", "alow_invalid=true"], "--config: alow_invalid: unknown key"),
    ],
)
def test_snakemake_refuses_bad_command_line_config_naming_the_key(workflow_copy, args, message):
    result = snakemake(workflow_copy, "--dry-run", *args)
    assert result.returncode != 0
    assert message in result.stdout + result.stderr


@pytest.mark.pipeline
def test_snakemake_merges_the_ci_overlay_over_the_config(workflow_copy):
    result = snakemake(
        workflow_copy, "--dry-run", "--configfile", "config/ci.yaml", "--config", "simulate=false"
    )
    assert result.returncode == 0, result.stdout + result.stderr
    effective = workflow_copy / "data" / "interim" / "config.yaml"
    seen = yaml.safe_load(effective.read_text())
    merged = load_config(CONFIG, CI, overrides={"simulate": "false"})
    # Less the keys that only choose the targets (no job reads them).
    assert seen == {key: value for key, value in merged.items() if key not in TARGET_KEYS}
    # The package commands read it back through the same loader.
    assert {k: v for k, v in load_config(effective).items() if k not in TARGET_KEYS} == seen


def _casa(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [CASA, *args], cwd=cwd, env=ENV, capture_output=True, text=True, timeout=120
    )


def test_the_commands_work_from_any_directory(tmp_path):
    write_dataset(tmp_path / "raw", participants=("p01",))
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    result = _casa(elsewhere, "validate", str(tmp_path / "raw"))
    assert result.returncode == 0, result.stderr
    assert "0 problem(s)" in result.stderr
    result = _casa(elsewhere, "teleop", "--help")
    assert result.returncode == 0 and "--epsilon" in result.stdout, result.stderr
    assert f"(default {defaults.EPSILON})" in " ".join(result.stdout.split())


def test_the_workflow_commands_refuse_a_bad_config_naming_the_key(tmp_path):
    overlay = tmp_path / "overlay.yaml"
    overlay.write_text("case_study: {sed: 1}\n")
    result = _casa(
        ROOT,
        "case-study",
        "--config",
        str(CONFIG),
        "--config",
        str(overlay),
        "--work",
        str(tmp_path / "work"),
        "--steps",
        str(tmp_path / "steps.csv"),
        "--arbitration",
        str(tmp_path / "arbitration.csv"),
    )
    assert result.returncode == 2
    assert f"casa case-study: {overlay}: case_study.sed: unknown key; did you mean seed?" in (
        result.stderr
    )
    assert not (tmp_path / "work").exists()


def test_the_digest_names_the_effective_config_and_the_line_its_files(tmp_path):
    path, digest = write_effective_config(tmp_path)
    assert config_digest(path) == digest and len(digest) == 12
    # Another configuration, another digest: the default one differs from CI's.
    other = tmp_path / "default.yaml"
    other.write_text(config_text(load_config(CONFIG)), encoding="utf-8")
    assert config_digest(other) != digest
    built = Provenance.of(CI_LAYERS, path)
    assert built.line() == (
        f"Built from config/config.yaml + config/ci.yaml (effective config sha256 {digest})"
    )
    with pytest.raises(OSError):
        config_digest(tmp_path / "missing.yaml")
