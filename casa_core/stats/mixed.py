"""Linear mixed model with a random intercept per participant (statsmodels MixedLM).

With 11 participants a Wald chi-square of the fixed effects, which takes the estimated
covariance as known, rejects too often; each term is therefore tested by a likelihood
ratio between nested models fitted by maximum likelihood (REML likelihoods of models
with different fixed effects are not comparable). A random-intercept variance at the
boundary (estimated at 0 relative to the residual variance) is flagged in the note: the
model is then ordinary least squares and the participant effect is not estimable.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
import pandas as pd
import statsmodels.formula.api as smf
from scipy import stats

from casa_core.stats._tables import (
    Skipped,
    as_list,
    clean,
    levels,
    require_representable,
    skipped_row,
)

MIXED_COLUMNS = ["term", "chi2", "df1", "p", "n", "n_groups"]
#: Random-intercept variance over residual variance below which the fit is at the
#: boundary: scale-free, so the same for errors in metres and efforts in key presses.
BOUNDARY_RATIO = 1e-4


def _fit_ml(formula: str, frame: pd.DataFrame) -> tuple[float, bool, float]:
    """ML log-likelihood of ``formula`` with a random intercept, whether it is at the
    boundary, and the variance ratio.

    The model with zero participant variance is ordinary least squares, a member of the
    family: the likelihood is the larger of the two fits (statsmodels' optimiser can stop
    short of a boundary maximum, below the OLS likelihood), and the fit is at the
    boundary when OLS does at least as well or the variance ratio is below
    :data:`BOUNDARY_RATIO`. Both criteria are free of the data's scale.
    """
    try:
        fit = smf.mixedlm(formula, frame, groups=frame["g"]).fit(reml=False)
        ols = smf.ols(formula, frame).fit()
    except (np.linalg.LinAlgError, ValueError) as error:
        raise Skipped(f"the mixed model could not be fitted: {error}") from error
    if not np.isfinite(fit.llf):
        raise Skipped("the mixed model's likelihood is not finite")
    ratio = float(fit.cov_re.iloc[0, 0]) / float(fit.scale)
    boundary = ols.llf >= fit.llf - 1e-9 or not ratio >= BOUNDARY_RATIO
    return max(float(fit.llf), float(ols.llf)), boundary, ratio


def _coefficients(frame: pd.DataFrame, formula: str) -> int:
    """Estimable fixed effects of ``formula``: the rank of its design matrix."""
    import patsy

    return int(np.linalg.matrix_rank(np.asarray(patsy.dmatrix(formula, frame))))


def mixedlm(
    data: pd.DataFrame,
    dv: str,
    fixed: str | Sequence[str],
    subject: str,
    *,
    interaction: bool = True,
) -> pd.DataFrame:
    """Linear mixed model ``dv ~ fixed + (1 | subject)``, likelihood-ratio test per term.

    Each main effect is tested by the likelihood ratio of the additive model against the
    model without it; with two factors and ``interaction`` the interaction is tested by
    the factorial model against the additive one (R:
    ``anova(lmer(..., REML = FALSE), lmer(..., REML = FALSE))``). All fits are ML.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation (long format); repeated trials are used as they are.
    dv : str
        Column of the dependent variable.
    fixed : str or sequence of str
        One or two categorical fixed-effect columns (e.g. method, or method and task).
    subject : str
        Column identifying participants (random intercept).
    interaction : bool
        With two factors, also test their interaction (a row ``"A x B"``).

    Returns
    -------
    pandas.DataFrame
        One row per term, columns ``term, chi2, df1, p, n, n_groups, note``: the
        likelihood-ratio chi-square, its degrees of freedom (the number of coefficients
        dropped) and p; the note flags a fit at the boundary or not fully converged.

    Examples
    --------
    >>> y = [1.0, 1.5, 1.2, 1.1, 2.0, 2.2, 2.5, 1.9, 3.1, 2.9, 3.6, 3.0]
    >>> data = pd.DataFrame({"y": y, "condition": [c for c in "abc" for _ in range(4)]})
    >>> data["subject"] = [f"s{i % 4 + 1}" for i in range(12)]
    >>> mixedlm(data, "y", "condition", "subject")[["term", "chi2", "df1", "n"]].round(1)
            term  chi2  df1   n
    0  condition  31.8  2.0  12
    """
    factors = as_list(fixed)
    if not 1 <= len(factors) <= 2:
        raise ValueError(f"mixedlm: fixed must name 1 or 2 factors, got {factors}")
    terms = [*factors, *([" x ".join(factors)] if interaction and len(factors) == 2 else [])]
    frame = clean(data, dv, [*factors, subject], "mixedlm")
    try:
        for factor in factors:
            if len(levels(frame[factor])) < 2:
                raise Skipped(
                    f"needs at least 2 levels of {factor!r}, found {levels(frame[factor])}"
                )
        n_groups = frame[subject].nunique()
        if n_groups < 2:
            raise Skipped(f"needs at least 2 participants, got {n_groups}")
        require_representable(frame[dv], dv)
        if frame[dv].var() == 0.0:
            raise Skipped(f"zero variance: every value of {dv!r} is the same")
        names = {dv: "y", subject: "g"} | {f: f"f{i}" for i, f in enumerate(factors)}
        model_frame = frame.rename(columns=names)
        model_frame["g"] = model_frame["g"].astype(str)
        parts = [f"C(f{i})" for i in range(len(factors))]
        # Per term: (the model with it, the model without it).
        pairs = {
            factor: (" + ".join(parts), " + ".join(p for p in parts if p != part) or "1")
            for factor, part in zip(factors, parts, strict=True)
        }
        if len(terms) == 3:
            pairs[terms[2]] = (" * ".join(parts), " + ".join(parts))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            fits = {f: _fit_ml(f"y ~ {f}", model_frame) for pair in pairs.values() for f in pair}
        largest = max(fits, key=lambda f: _coefficients(model_frame, f))
    except Skipped as why:
        return pd.concat(
            [skipped_row(MIXED_COLUMNS, str(why), term=t) for t in terms], ignore_index=True
        )
    note = "likelihood ratio, ML fits, random intercept per participant"
    if any("converge" in str(w.message).lower() for w in caught):
        note += "; fit did not fully converge"
    _, boundary, ratio = fits[largest]
    if boundary:
        note += (
            "; boundary fit: the participant variance is estimated at 0 (ordinary least "
            f"squares fits as well; variance ratio {max(ratio, 0.0):.2g}), the model has "
            "no participant effect"
        )
    rows = []
    for term, (with_term, without) in pairs.items():
        df1 = float(_coefficients(model_frame, with_term) - _coefficients(model_frame, without))
        chi2 = max(0.0, 2.0 * (fits[with_term][0] - fits[without][0]))  # optimiser noise
        rows.append(
            {
                "term": term,
                "chi2": chi2,
                "df1": df1,
                "p": float(stats.chi2.sf(chi2, df1)),
                "n": len(model_frame),
                "n_groups": n_groups,
                "note": note,
            }
        )
    return pd.DataFrame(rows, columns=[*MIXED_COLUMNS, "note"])


__all__ = ["BOUNDARY_RATIO", "mixedlm"]
