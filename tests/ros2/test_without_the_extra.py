"""Without the ``ros2`` extra, the ROS 2 commands say how to install it and exit 2."""

from __future__ import annotations

import sys

import pytest

from casa_core.cli import main


@pytest.mark.parametrize(
    "argv",
    [
        ["ros2", "sim", "--duration", "1"],
        ["ros2", "assist", "--task", "known_goal", "--method", "CASA", "--participant", "P01"]
        + ["--out", "never"],
    ],
)
def test_the_nodes_say_how_to_install_the_extra(monkeypatch, capsys, argv, tmp_path):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(sys.modules, "rclpy", None)  # import rclpy raises ImportError
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"casa ros2 {argv[1]}: the ROS 2 packages are not installed" in err
    assert 'pip install -e ".[ros2]"' in err and "Traceback" not in err
    assert not (tmp_path / "never").exists()


def test_the_rosbag_import_says_how_to_install_the_extra(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "rosbags", None)
    assert main(["import", "rosbag", str(tmp_path), "--out", str(tmp_path / "raw")]) == 2
    err = capsys.readouterr().err
    assert "rosbags is not installed" in err and 'pip install -e ".[ros2]"' in err


def test_a_remap_must_be_from_to(capsys):
    assert main(["ros2", "sim", "--remap", "joint_states"]) == 2
    assert "is not FROM:=TO" in capsys.readouterr().err


def test_the_rest_of_casa_never_imports_rclpy():
    # Only casa_core.ros2.nodes (and the handlers of casa ros2) import it.
    import subprocess

    code = "import casa_core.cli, casa_core.ros2.loop, casa_core.ros2.bag, sys; "
    code += "print('rclpy' in sys.modules, 'rosbags' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.stdout.split() == ["False", "False"], result.stderr
