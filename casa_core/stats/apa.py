"""APA-style formatting of test results ("F(2, 30) = 104.93, p < .001")."""

from __future__ import annotations

import math


def _number(value: float, digits: int = 2) -> str:
    return f"{value:.{digits}f}"


def _df(value: float) -> str:
    """Degrees of freedom: integers as integers, corrected ones with two decimals."""
    return str(int(round(value))) if abs(value - round(value)) < 1e-9 else f"{value:.2f}"


def _no_leading_zero(text: str) -> str:
    """APA drops the leading zero of quantities that cannot exceed 1 (p, eta squared, r)."""
    return text.replace("0.", ".", 1) if text.lstrip("-").startswith("0.") else text


def p_value(p: float) -> str:
    """``p < .001`` below one in a thousand, else ``p = .xxx``."""
    if not math.isfinite(p):
        return "p = n/a"
    if p < 0.001:
        return "p < .001"
    return "p = " + _no_leading_zero(f"{p:.3f}")


def proportion(value: float) -> str:
    """A bounded quantity (effect size) with APA's missing leading zero, two decimals."""
    return _no_leading_zero(_number(value))


def f_test(f: float, df1: float, df2: float, p: float) -> str:
    """``F(df1, df2) = f, p ...``."""
    return f"F({_df(df1)}, {_df(df2)}) = {_number(f)}, {p_value(p)}"


def chi2_test(chi2: float, df: float, p: float) -> str:
    """``χ²(df) = chi2, p ...``."""
    return f"χ²({_df(df)}) = {_number(chi2)}, {p_value(p)}"
