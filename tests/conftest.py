"""Fixtures shared by the test folders."""

# casa_core first: it sets the libraries' CPU switches before numpy loads (numerics.py).
import casa_core  # noqa: F401  isort: skip

import pytest

from casa_core.scene import load_scene


@pytest.fixture(scope="module")
def scene():
    return load_scene()


@pytest.fixture(scope="module")
def sim():
    # Imported here: pybullet is loaded only by the tests that use the simulation.
    from casa_core.robot.sim import ArmSimulation

    with ArmSimulation(load_scene()) as arm:
        yield arm
