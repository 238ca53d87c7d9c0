"""The CSV text of a plain table is the text pandas writes, byte for byte.

``casa_core.io._csv_text.plain_csv_text`` stands in for
``DataFrame.to_csv(index=False, lineterminator="\\n")`` (``io.atomic.frame_to_csv_text``)
on tables of float, integer and plain-text columns. It is held to pandas' own text on
trial logs as ``write_trial`` hands them over and on the floats where formatting differs
(subnormal, huge, negative zero, infinities, missing values, 17 significant digits); on
any table pandas would write in its own way (quoted fields, one column, other types) it
gives None, and the writer asks pandas.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from casa_core.io._csv_text import plain_csv_text
from casa_core.io.atomic import frame_to_csv_text
from tests.io.test_logs_synthetic import trial_frame

EDGE_FLOATS = [0.0, -0.0, 5e-324, 2.2250738585072014e-308, 1e-5, 1e-4, 0.1, 1 / 3, 2 / 3,
               1e15, 1e16, 123456789012345678.0, 1.7976931348623157e308, np.inf, -np.inf,
               np.nan, 0.30000000000000004, -1.5, 100.0, 4.35]  # fmt: skip


def pandas_text(frame: pd.DataFrame) -> str:
    return frame.to_csv(index=False, lineterminator="\n")


@pytest.mark.parametrize("task", ["known_goal", "unknown_goal", "unknown_skill"])
def test_a_trial_log_is_the_text_pandas_writes(task):
    rng = np.random.default_rng(0)
    frame = trial_frame(task, intents=("green", "purple", "learned_red"), rng=rng)
    frame["y"] += rng.normal(0.0, 1e-3, size=len(frame))  # 17 significant digits
    frame["keys"] = frame["keys"].astype(object)  # as write_trial maps the keys cells
    text = plain_csv_text(frame)
    assert text is not None and text == pandas_text(frame)
    assert frame_to_csv_text(frame) == text


def test_edge_floats_integers_and_text_are_written_as_pandas_writes_them():
    rng = np.random.default_rng(1)
    floats = np.array(
        EDGE_FLOATS + list(rng.normal(0.0, 1.0, 80) * 10.0 ** rng.integers(-9, 9, 80))
    )
    n = len(floats)
    frame = pd.DataFrame(
        {
            "x": floats,
            "count": rng.integers(-(2**62), 2**62, n),
            "keys": rng.choice(["", "x+", "x+ rot-", "z-"], n).astype(object),
            "name": pd.array(rng.choice(["a", "b c", "d:e"], n), dtype="str"),
            "y": floats[::-1].copy(),
        }
    )
    text = plain_csv_text(frame)
    assert text is not None and text == pandas_text(frame)


def test_floats_of_every_magnitude_are_written_as_pandas_writes_them():
    # Random bit patterns (every exponent, subnormals, NaNs of any payload) and decimals
    # rounded to 0..16 places, the text of a float that reads back as itself.
    rng = np.random.default_rng(2)
    bits = rng.integers(0, 2**63, 20000, dtype=np.uint64).view(np.float64)
    decimals = [
        round(float(x), int(d))
        for x, d in zip(rng.normal(size=5000), rng.integers(0, 17, 5000), strict=True)
    ]
    values = np.concatenate([bits, -bits, decimals])
    frame = pd.DataFrame({"x": values, "y": values[::-1].copy()})
    assert plain_csv_text(frame) == pandas_text(frame)


@pytest.mark.parametrize(
    "frame",
    [
        pd.DataFrame({"t": [0.0], "keys": ["a,b"]}),  # quoted
        pd.DataFrame({"t": [0.0], "keys": ['say "x"']}),  # quoted, quotes doubled
        pd.DataFrame({"t": [0.0], "keys": [None]}),  # missing text
        pd.DataFrame({"t": [0.0, 1.0]}),  # one column: an empty field is quoted
        pd.DataFrame({"t": [0.0], "ok": [True]}),  # booleans
        pd.DataFrame({"t": np.array([0.5], dtype=np.float32), "u": [1.0]}),  # float32
        pd.DataFrame({"t": pd.array([0.5, None], dtype="Float64"), "u": [1.0, 2.0]}),
        pd.DataFrame({"t": [0.0], "a,b": [1.0]}),  # a name to quote
        pd.DataFrame({"t": [], "u": []}),  # no rows
    ],
)
def test_any_other_table_is_left_to_pandas(frame):
    assert plain_csv_text(frame) is None
    assert frame_to_csv_text(frame) == pandas_text(frame)
