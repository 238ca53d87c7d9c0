"""The cameras of the window and the scene figure (:mod:`casa_core.robot.camera`).

Expected values come from a pinhole model written here from pybullet's documented orbit
camera (eye at ``distance`` from ``target`` opposite the view direction, z up) and from
the window itself: under Xvfb, pybullet's own matrices (``getDebugVisualizerCamera``) say
where each position is drawn.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import yaml

from casa_core.robot.camera import (
    DISTANCE_STEP,
    MARGIN,
    ROLES,
    Camera,
    fit_camera,
    scene_camera,
    scene_positions,
)
from casa_core.scene import Scene, SceneError, load_scene
from casa_core.vocabulary import VIEWS
from tests.display import start_xvfb

SCENES = ("config/scene.yaml", "config/scene-original.yaml", "config/scene-original-via-green.yaml")


def pinhole_forward(camera: Camera) -> np.ndarray:
    """The orbit camera's view direction: yaw about z from +y toward -x, pitch up."""
    yaw, pitch = math.radians(camera.yaw), math.radians(camera.pitch)
    return np.array(
        [-math.cos(pitch) * math.sin(yaw), math.cos(pitch) * math.cos(yaw), math.sin(pitch)]
    )


def pinhole(camera: Camera, points, aspect: float) -> np.ndarray:
    """Normalized image coordinates of ``points`` by a pinhole camera, independently of
    pybullet's matrices."""
    forward = pinhole_forward(camera)
    eye = np.asarray(camera.target) - camera.distance * forward
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    relative = np.asarray(points, dtype=float) - eye
    depth = relative @ forward
    scale = math.tan(math.radians(camera.fov) / 2)
    return np.c_[relative @ right / depth / (scale * aspect), relative @ up / depth / scale]


def test_the_projection_is_a_pinhole_camera_of_the_orbit():
    rng = np.random.default_rng(7)
    for _ in range(20):
        camera = Camera(
            tuple(rng.uniform(-0.5, 0.5, 3)),
            float(rng.uniform(0.5, 2.0)),
            float(rng.uniform(-180, 180)),
            float(rng.uniform(-80, -10)),
            float(rng.uniform(30, 90)),
        )
        points = np.asarray(camera.target) + rng.uniform(-0.3, 0.3, (5, 3))
        aspect = float(rng.uniform(1.0, 2.0))
        np.testing.assert_allclose(
            camera.normalized(points, aspect=aspect), pinhole(camera, points, aspect), atol=1e-5
        )


def test_a_point_behind_the_camera_is_never_in_the_image():
    camera = Camera((0.0, 0.0, 0.0), 1.0, -90.0, -50.0, 90.0)
    behind = np.asarray(camera.target) - 3.0 * pinhole_forward(camera)
    assert np.isinf(camera.normalized(behind, aspect=4 / 3)).all()


@pytest.mark.parametrize("path", SCENES)
@pytest.mark.parametrize("role", VIEWS)
def test_every_shipped_scene_is_seen_whole_in_both_views(path, role):
    scene = load_scene(path)
    camera = scene_camera(scene, role)
    assert (camera.yaw, camera.pitch, camera.fov) == ROLES[role]
    xy = camera.normalized(scene_positions(scene), aspect=4 / 3)
    assert np.all(np.abs(xy) < 1), (path, role, xy)


def test_our_layout_pins_the_views_a_person_and_the_figure_have_always_had():
    scene = load_scene()
    window, figure = scene_camera(scene, "window"), scene_camera(scene, "figure")
    assert (window.target, window.distance) == ((0.4, -0.05, 0.1), 1.25)
    assert (figure.target, figure.distance) == ((0.32, -0.02, 0.18), 1.05)


def test_a_fitted_camera_follows_its_rule_on_random_layouts():
    rng = np.random.default_rng(2021)
    for _ in range(30):
        points = rng.uniform([-0.7, -0.6, 0.0], [0.7, 0.6, 0.6], (6, 3))
        for role in ROLES:
            camera = fit_camera(points, role)
            np.testing.assert_allclose(camera.target, (points.min(0) + points.max(0)) / 2)
            inside = np.abs(camera.normalized(points, aspect=4 / 3))
            assert np.all(inside <= 1 - 2 * MARGIN)
            # The shortest such distance: one step nearer, a position leaves the frame.
            nearer = Camera(camera.target, camera.distance - DISTANCE_STEP, *ROLES[role])
            if camera.distance - DISTANCE_STEP >= 0.5 - 1e-9:
                assert np.any(np.abs(nearer.normalized(points, aspect=4 / 3)) > 1 - 2 * MARGIN)


def test_positions_no_distance_frames_are_refused_naming_the_role():
    far = np.array([[-30.0, -30.0, 0.0], [30.0, 30.0, 0.0]])  # 85 m apart
    with pytest.raises(ValueError, match="no window camera"):
        fit_camera(far, "window")


def scene_text(view: str) -> dict:
    data = yaml.safe_load(open("config/scene.yaml", encoding="utf-8"))
    data["view"] = yaml.safe_load(view)
    return data


@pytest.mark.parametrize(
    ("view", "message"),
    [
        ("{side: {target: [0, 0, 0], distance: 1, yaw: 0, pitch: 0}}", "view.side: unknown key"),
        ("{window: {target: [0, 0, 0], distance: 0, yaw: 0, pitch: 0}}", "view.window.distance"),
        ("{figure: {target: [0, 0], distance: 1, yaw: 0, pitch: 0}}", "view.figure.target"),
        ("{window: {target: [0, 0, 0], distance: 1, yaw: 0}}", "view.window.pitch: missing"),
    ],
)
def test_a_bad_view_names_its_key(view, message):
    with pytest.raises(SceneError, match=message):
        Scene.from_dict(scene_text(view), "my-scene.yaml")


WINDOW_SCRIPT = textwrap.dedent(
    """
    import json, sys
    from casa_core.robot.camera import scene_positions
    from casa_core.robot.screens import SessionWindow
    from casa_core.scene import load_scene

    scene = load_scene(sys.argv[1])
    window = SessionWindow(scene)
    pixels = [window.pixel(point) for point in scene_positions(scene)]
    print(json.dumps({"size": [window.width, window.height], "pixels": pixels}))
    window.close()
    """
)


@pytest.mark.skipif(shutil.which("Xvfb") is None, reason="Xvfb is not on PATH: no display")
def test_the_session_window_shows_every_position_of_the_authors_layout():
    server, display = start_xvfb()
    try:
        run = subprocess.run(
            [sys.executable, "-c", WINDOW_SCRIPT, "config/scene-original.yaml"],
            env={**os.environ, "DISPLAY": display},
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        server.terminate()
        server.wait(timeout=10)
    assert run.returncode == 0, run.stderr[-2000:]
    drawn = json.loads(next(line for line in run.stdout.splitlines() if line.startswith("{")))
    width, height = drawn["size"]
    pixels = np.array(drawn["pixels"])
    # pybullet's own matrices: every position (start, goals, pouring pose, bowl) on screen.
    assert np.all((pixels >= 0) & (pixels <= [width, height])), pixels
