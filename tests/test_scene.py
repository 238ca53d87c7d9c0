"""The scene's optional link-7 goals: read when given, refused with the key when wrong."""

from __future__ import annotations

import pytest
import yaml

from casa_core.scene import DEFAULT_SCENE, Scene, SceneError, load_scene


def scene_data(**changes):
    data = yaml.safe_load(DEFAULT_SCENE.read_text())
    data.update(changes)
    return data


def test_link7_goals_are_optional_and_read_when_given():
    assert dict(load_scene().link7_goals) == {}
    scene = Scene.from_dict(scene_data(link7={"green": [0.1, 0.2, 0.3]}))
    assert scene.goal("green", "link7").tolist() == [0.1, 0.2, 0.3]
    assert scene.goal("green").tolist() == list(scene.goals["green"])
    with pytest.raises(SceneError, match="scene: link7 has no 'purple'; it has green"):
        scene.goal("purple", "link7")


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
