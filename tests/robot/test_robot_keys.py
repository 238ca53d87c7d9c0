"""The 8-key map: 0.05 m/s per Cartesian key, 0.5 rad/s per rotate key (the original's)."""

import numpy as np
import pytest

from casa_core.robot.keys import AXIS_KEYS, format_keys, keys_to_action, parse_keys
from casa_core.vocabulary import KEYS


@pytest.mark.parametrize(
    ("key", "expected"),
    [
        ("x+", [0.05, 0, 0, 0]),
        ("x-", [-0.05, 0, 0, 0]),
        ("y+", [0, 0.05, 0, 0]),
        ("y-", [0, -0.05, 0, 0]),
        ("z+", [0, 0, 0.05, 0]),
        ("z-", [0, 0, -0.05, 0]),
        ("rot+", [0, 0, 0, 0.5]),
        ("rot-", [0, 0, 0, -0.5]),
    ],
)
def test_each_key_moves_one_axis_at_the_key_speed(key, expected):
    np.testing.assert_allclose(keys_to_action([key]), expected)


def test_keys_add_up_and_opposite_keys_cancel():
    np.testing.assert_allclose(keys_to_action(["x+", "z-", "rot+"]), [0.05, 0, -0.05, 0.5])
    np.testing.assert_allclose(keys_to_action(["y+", "y-"]), np.zeros(4))
    np.testing.assert_allclose(keys_to_action([]), np.zeros(4))
    np.testing.assert_allclose(keys_to_action(["x+"], speed=0.1), [0.1, 0, 0, 0])


def test_unknown_key_is_named_in_the_error():
    with pytest.raises(ValueError, match="'q'"):
        keys_to_action(["x+", "q"])


def test_format_is_canonical_and_parse_inverts_it():
    assert format_keys({"rot-", "x+", "z+"}) == "x+ z+ rot-"
    assert format_keys([]) == ""
    assert parse_keys("x+ z+ rot-") == {"x+", "z+", "rot-"}
    assert parse_keys("") == frozenset()
    assert format_keys(KEYS) == " ".join(KEYS)


def test_axis_keys_pair_each_axis_plus_and_minus():
    assert AXIS_KEYS == (("x+", "x-"), ("y+", "y-"), ("z+", "z-"), ("rot+", "rot-"))
