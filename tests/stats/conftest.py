"""Fixtures shared by the statistics tests."""

from pathlib import Path

import pandas as pd
import pytest

REF = Path(__file__).parents[1] / "reference" / "stats"


@pytest.fixture(scope="module")
def sleep() -> pd.DataFrame:
    return pd.read_csv(REF / "sleep.csv", dtype={"group": str})
