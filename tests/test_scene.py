"""The scene's point and its goals at the other point: read when given, refused with the
key when wrong."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from casa_core.assist.tasks import intended_trajectory, task_waypoints
from casa_core.scene import DEFAULT_SCENE, Scene, SceneError, load_scene

CONFIG = DEFAULT_SCENE.parent


def scene_data(**changes):
    data = yaml.safe_load(DEFAULT_SCENE.read_text())
    data.update(changes)
    return data


def test_link7_goals_are_optional_and_read_when_given():
    assert load_scene().point == "tool" and dict(load_scene().goals_elsewhere) == {}
    scene = Scene.from_dict(scene_data(link7={"green": [0.1, 0.2, 0.3]}))
    assert scene.goal("green", "link7").tolist() == [0.1, 0.2, 0.3]
    assert scene.goal("green").tolist() == list(scene.goals["green"])
    assert scene.goal("green", "tool").tolist() == list(scene.goals["green"])
    with pytest.raises(SceneError, match="scene: link7 has no 'purple'; it has green"):
        scene.goal("purple", "link7")


def test_a_scene_at_link7_gives_its_goals_there_and_its_tool_goals_apart():
    joints = {"position": [0.4, 0.0, 0.4], "rot": 0.0, "joints": [180] * 7}
    data = scene_data(point="link7", start=joints, tool={"red": [0.5, 0.5, 0.5]})
    scene = Scene.from_dict(data)
    assert scene.point == "link7" and scene.goal("red").tolist() == list(scene.goals["red"])
    assert scene.goal("red", "link7").tolist() == list(scene.goals["red"])
    assert scene.goal("red", "tool").tolist() == [0.5, 0.5, 0.5]
    with pytest.raises(SceneError, match="scene: tool has no 'green'; it has red"):
        scene.goal("green", "tool")


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"point": "elbow"}, "x.yaml: point: must be one of tool, link7, got 'elbow'"),
        ({"tool": {}}, r"x.yaml: tool: the scene's own point \(tool\): its goals go in goals"),
        ({"point": "link7"}, "x.yaml: start.joints: required at point link7"),
    ],
)
def test_a_bad_point_is_named(changes, message):
    with pytest.raises(SceneError, match=message):
        Scene.from_dict(scene_data(**changes), "x.yaml")


@pytest.mark.parametrize(
    ("link7", "message"),
    [
        ({"blue": [0, 0, 0]}, "x.yaml: link7.blue: not a goal of the scene"),
        ({"green": [0, 0]}, "x.yaml: link7.green: must be 3 finite numbers"),
        ([1, 2, 3], "x.yaml: link7: must be a mapping"),
    ],
)
def test_bad_link7_goals_are_named(link7, message):
    with pytest.raises(SceneError, match=message):
        Scene.from_dict(scene_data(link7=link7), "x.yaml")


def test_an_unknown_top_key_names_the_known_ones():
    with pytest.raises(SceneError, match="x.yaml: links: unknown key; expected .*, link7"):
        Scene.from_dict(scene_data(links={}), "x.yaml")


def _closest_on_segment(a, b, point):
    """The point of segment ``a``-``b`` nearest to ``point``."""
    d = b - a
    return a + np.clip(np.dot(point - a, d) / np.dot(d, d), 0.0, 1.0) * d


def test_the_via_green_reading_passes_green_as_near_as_our_layout():
    # The rule in the file's header: the unknown tasks' paths pass green at the distance
    # at which our layout's straight paths pass it, toward the straight path's nearest point.
    ours, authors = load_scene(), load_scene(CONFIG / "scene-original.yaml")
    via_green = load_scene(CONFIG / "scene-original-via-green.yaml")

    def ends(scene):
        return {
            "unknown_goal": scene.goal("red"),
            "unknown_skill": np.array(scene.pouring.position),
        }

    for task in ("unknown_goal", "unknown_skill"):
        start, green = np.array(ours.start.position), ours.goal("green")
        near = np.linalg.norm(_closest_on_segment(start, ends(ours)[task], green) - green)
        start, green = np.array(authors.start.position), authors.goal("green")
        straight = _closest_on_segment(start, ends(authors)[task], green)
        expected = green + near * (straight - green) / np.linalg.norm(straight - green)
        (via,) = via_green.via[task]
        assert np.allclose(via, expected, atol=0.0005 + 1e-9), task  # rounded to 1 mm
        # The intended path goes through it, and ends where the straight one does.
        path = intended_trajectory(task, via_green)[:, 1:4]
        assert np.linalg.norm(path - np.array(via), axis=1).min() < 0.003
        assert np.allclose(path[-1], intended_trajectory(task, authors)[-1, 1:4])
    # Every other key is the authors' layout's.
    assert via_green == Scene(**{**vars(authors), "via": via_green.via})
    assert authors.via == {} and task_waypoints("known_goal", via_green).shape == (2, 4)


@pytest.mark.parametrize(
    ("via", "message"),
    [
        ({"unknown": [[0, 0, 0]]}, "x.yaml: via.unknown: unknown key"),
        ({"unknown_goal": []}, "x.yaml: via.unknown_goal: must be a list of positions"),
        ({"unknown_goal": [[1, 2]]}, "x.yaml: via.unknown_goal.0: must be 3 finite numbers"),
    ],
)
def test_bad_via_positions_are_named(via, message):
    with pytest.raises(SceneError, match=message):
        Scene.from_dict(scene_data(via=via), "x.yaml")


def test_a_fixed_trial_length_is_read_and_checked():
    # The authors' scenes run the original's 15 s protocol; ours ends trials when done.
    assert load_scene().trial_length is None
    for name in ("scene-original.yaml", "scene-original-via-green.yaml"):
        assert load_scene(CONFIG / name).trial_length == 15.0
    assert Scene.from_dict(scene_data(trial_length=20)).trial_length == 20.0
    for bad, rule in ((0, "must be positive"), ("15 s", "must be a finite number")):
        with pytest.raises(SceneError, match=f"x.yaml: trial_length: {rule}"):
            Scene.from_dict(scene_data(trial_length=bad), "x.yaml")
