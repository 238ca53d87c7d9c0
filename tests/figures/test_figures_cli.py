"""Tests of ``casa figure ...`` (tables on disk in, PDF + PNG out) and the scene render."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from casa_core.cli import main
from casa_core.figures.scene import TASK_PATHS, crop_background, crop_box, scene_figure
from casa_core.robot.render import render_scene, scene_landmarks
from casa_core.scene import Scene, load_scene
from tests.figures.test_figures import (
    likert_stats,
    make_arbitration,
    make_likert,
    make_steps,
    make_trials,
    tukey,
)

SCENE = Path(__file__).resolve().parents[2] / "config" / "scene.yaml"


@pytest.fixture(scope="module")
def scene() -> Scene:
    return load_scene(SCENE)


def write(frame, path: Path) -> str:
    frame.to_csv(path, index=False)
    return str(path)


def test_cli_writes_each_table_figure(tmp_path, capsys):
    import pandas as pd

    trials = write(make_trials(), tmp_path / "trials.csv")
    stats = write(
        pd.DataFrame([tukey("known_goal", "error", "CASA vs NA", 0.001)]), tmp_path / "stats.csv"
    )
    runs = {
        "objective": ["--trials", trials, "--stats", stats],
        "likert": [
            "--likert",
            write(make_likert(), tmp_path / "likert.csv"),
            "--stats",
            write(likert_stats(), tmp_path / "likert_stats.csv"),
        ],
        "arbitration": ["--arbitration", write(make_arbitration(), tmp_path / "arb.csv")],
        "case_study": ["--steps", write(make_steps(), tmp_path / "steps.csv"), "--epsilon", "1"],
    }
    for name, arguments in runs.items():
        out = tmp_path / "figures" / name
        setup = ["--setup", "scene scene.yaml (teleop held)"]
        assert main(["figure", name, *arguments, *setup, "--out", str(out)]) == 0
        assert out.with_suffix(".pdf").stat().st_size > 0
        assert out.with_suffix(".png").stat().st_size > 0
        assert f"casa figure {name}:" in capsys.readouterr().out


def test_cli_keeps_the_method_na(tmp_path):
    # pandas' default reader would turn the method "NA" into a missing value; the figure
    # would then fail on an unknown method. The CLI reads tables with their values intact.
    trials = write(make_trials(), tmp_path / "trials.csv")
    assert main(["figure", "objective", "--trials", trials, "--out", str(tmp_path / "o")]) == 0


def test_cli_reports_bad_input_and_fails(tmp_path, capsys):
    trials = write(make_trials().drop(columns="error"), tmp_path / "trials.csv")
    code = main(["figure", "objective", "--trials", trials, "--out", str(tmp_path / "o")])
    assert code == 1
    assert "casa figure objective: trials: missing column(s) 'error'" in capsys.readouterr().err
    assert not (tmp_path / "o.pdf").exists()
    missing = str(tmp_path / "nope.csv")
    assert main(["figure", "likert", "--likert", missing, "--out", str(tmp_path / "l")]) == 1


def test_scene_render_shows_goals_and_paths(scene):
    image = render_scene(scene, TASK_PATHS, width=320, height=240)
    assert image.shape == (240, 320, 3) and image.dtype == np.uint8
    r, g, b = (image[:, :, i].astype(int) for i in range(3))
    # The goals are spheres in the paper's colours: some pixels must be clearly green,
    # red and purple (not a blank or single-colour image).
    assert np.count_nonzero((g > 120) & (r < 90) & (b < 110)) > 10
    assert np.count_nonzero((r > 150) & (g < 60) & (b < 60)) > 10
    assert np.count_nonzero((r > 80) & (b > 120) & (g < 80)) > 5
    # The cup is drawn in a saturated blue nothing else in the scene has.
    assert np.count_nonzero((b > 180) & (r < 60) & (g < 140)) > 20
    cropped = crop_background(image)
    assert cropped.shape[0] <= 240 and cropped.shape[1] <= 320


def test_scene_landmarks_put_the_pouring_pose_above_the_bowl(scene):
    landmarks = scene_landmarks(scene, width=320, height=240)
    assert set(landmarks) == {"cup", "pouring pose", "bowl"}
    for column, row in landmarks.values():
        assert 0 <= column < 320 and 0 <= row < 240
    # config/scene.yaml: the pouring pose is 28 cm straight above the bowl's centre, so
    # in the image it lies higher (a smaller row) than the bowl's rim.
    assert landmarks["pouring pose"][1] < landmarks["bowl"][1]
    # The plumb line between them is drawn: dark pixels on the segment's middle.
    image = render_scene(scene, width=320, height=240)
    (c0, r0), r1 = landmarks["pouring pose"], landmarks["bowl"][1]
    middle = image[int((r0 + r1) / 2) - 6 : int((r0 + r1) / 2) + 6, int(c0) - 40 : int(c0) + 10]
    assert np.count_nonzero(middle.max(axis=2) < 70) > 0


def test_scene_figure_labels_landmarks_in_the_cropped_image():
    image = np.full((60, 80, 3), 255, dtype=np.uint8)
    image[20:40, 30:50] = (10, 200, 30)
    top, _, left, _ = crop_box(image)
    fig = scene_figure(image, {"cup": (35.0, 25.0), "bowl": (45.0, 35.0)})
    annotations = {t.get_text(): t.xy for t in fig.axes[0].texts}
    assert annotations["cup, held at the start"] == (35.0 - left, 25.0 - top)
    assert annotations["bowl"] == (45.0 - left, 35.0 - top)
    with pytest.raises(ValueError, match="scene landmarks: unknown name"):
        scene_figure(image, {"lid": (1.0, 1.0)})


def test_scene_figure_legend_and_cli(tmp_path):
    image = np.full((60, 80, 3), 255, dtype=np.uint8)
    image[20:40, 30:50] = (10, 200, 30)
    fig = scene_figure(image)
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "red goal (unknown)" in labels and "cup" in labels
    assert len(labels) == 3 + len(TASK_PATHS) + 2
    out = tmp_path / "scene.png"
    assert main(["figure", "scene", "--scene", str(SCENE), "--out", str(out)]) == 0
    assert out.exists() and not (tmp_path / "scene.pdf").exists()


def test_cli_scene_error_names_the_key(tmp_path, capsys):
    bad = tmp_path / "scene.yaml"
    bad.write_text(SCENE.read_text(encoding="utf-8").replace("teleop:", "teleoperation:"))
    assert main(["figure", "scene", "--scene", str(bad), "--out", str(tmp_path / "s.png")]) == 1
    assert "teleop" in capsys.readouterr().err
    assert not (tmp_path / "s.png").exists()
