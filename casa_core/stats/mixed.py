"""Linear mixed model of the within-subjects design, tested by Kenward-Roger F with the
likelihood ratio beside it.

Random effects: an intercept per participant and, with two factors (method and task),
an intercept per participant x method and per participant x task: the model
``y ~ method * task + (1 | participant) + (1 | participant:method) + (1 | participant:task)``
of R's lme4 (statsmodels' ``MixedLM`` with ``vc_formula`` specifies the same model).
With one value per participant and cell the residual is participant x method x task, so
the model has the error strata of the repeated-measures ANOVA: each term is tested against its own
participant interaction, not against one pooled residual.

The reported test is Kenward and Roger's (1997) F (:mod:`casa_core.stats.kenward_roger`),
the small-sample test R's pbkrtest and lmerTest compute, on the REML fit with sum-to-zero
contrasts (type III; on a balanced design the same as type II). It was chosen over
Satterthwaite's degrees of freedom, the other small-sample F, because on a balanced
design with positive variance components it is exactly the repeated-measures ANOVA F on
the stratum's degrees of freedom (a closed form the tests check), and over a parametric
bootstrap of the likelihood ratio because it is deterministic and closed-form: a
bootstrap would refit every model hundreds of times in each of the power target's
replicate studies. Neither statsmodels nor any well-kept Python package has it; it is
written out here from the paper's and pbkrtest's formulas and checked against pbkrtest.

Beside it, each term's likelihood ratio between nested models fitted by maximum
likelihood (REML likelihoods of models with different fixed effects are not comparable):
main effects in the additive model, the interaction against it. With 11 participants the
likelihood ratio's chi-square rejects too often; it is kept for comparison.

The fits maximise the likelihood profiled over the residual variance, over the square
roots of the variance ratios (lme4's theta; dense matrices: a study has tens of cells),
by Nelder-Mead in fixed-order arithmetic (:mod:`casa_core.stats._dense`), so the optimum
has the same bits on every machine. A component whose estimate is 0 is found at 0, where
statsmodels' optimiser stops short of
the boundary and reports non-convergence (on the simulated study's H3 error, its
estimates give a Kenward-Roger F of 6.10 against lme4's 6.15). A component at the
boundary (below :data:`BOUNDARY_RATIO` of the residual variance) is named in the note:
its stratum then merges with the residual and the F differs from the ANOVA's.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy import optimize, stats

from casa_core.stats import _dense
from casa_core.stats._tables import (
    Skipped,
    as_list,
    clean,
    levels,
    require_representable,
    skipped_row,
)
from casa_core.stats.kenward_roger import KR_COLUMNS, kenward_roger

MIXED_COLUMNS = ["term", "F", "df1", "df2", "p", "chi2", "lrt_df", "p_lrt", "n", "n_groups"]
#: A variance component over the residual variance below which the fit is at the
#: boundary: scale-free, so the same for errors in metres and efforts in key presses.
BOUNDARY_RATIO = 1e-4


class _Fit:
    """ML or REML fit of ``V = sigma^2 (I + sum_i gamma_i G_i)``, ``gamma_i >= 0``.

    The likelihood is profiled over ``sigma^2`` and the fixed effects and maximised over
    ``theta = sqrt(gamma)``, unbounded, so a component whose estimate is 0 is found at 0
    (lme4 does the same; statsmodels' optimiser stops short of it).
    """

    def __init__(self, X: np.ndarray, y: np.ndarray, structures: list[np.ndarray], reml: bool):
        n, p = X.shape
        if np.linalg.matrix_rank(X) < p:
            raise Skipped("a cell of the design is empty: the model is not estimable")
        # Scaled to unit SD: the ratios and the likelihood ratio do not depend on the scale.
        spread = float(np.std(y))
        z = (y - np.mean(y)) / spread
        if np.allclose(X @ np.linalg.lstsq(X, z, rcond=None)[0], z, rtol=0.0, atol=1e-12):
            raise Skipped("no error variance: the fixed effects fit every value exactly")
        df = n - p if reml else n

        Xt = np.ascontiguousarray(X.T)

        def profiled(gamma):
            H = np.eye(n) + sum((g * G for g, G in zip(gamma, structures, strict=True)), 0.0)
            low = _dense.cholesky(H)
            HiX, Hiz = _dense.cholesky_solve(low, X), _dense.cholesky_solve(low, z)
            XtHiX = _dense.matmul(Xt, HiX)
            inner = _dense.cholesky(XtHiX)
            beta = _dense.cholesky_solve(inner, _dense.matmul(Xt, Hiz))
            # r' H^-1 r with r = z - X beta: H^-1 r = H^-1 z - H^-1 X beta.
            residual = z - _dense.matmul(X, beta)
            quadratic = float(np.sum(residual * (Hiz - _dense.matmul(HiX, beta))))
            if not quadratic > 0.0:
                return np.inf, quadratic
            value = df * np.log(quadratic) + _dense.logdet(low)
            if reml:
                value += _dense.logdet(inner)
            return value, quadratic

        # Over theta = sqrt(gamma), as lme4 does: no bounds, and a component at 0 is an
        # interior point. Nelder-Mead, whose steps are elementwise (no BLAS), from two
        # starts; the criterion is in fixed order too, so the optimum has the same bits
        # on every machine.
        def criterion(theta: np.ndarray) -> float:
            try:
                return float(profiled(theta * theta)[0])
            except np.linalg.LinAlgError:  # ratios so far apart that rounding breaks H
                return np.inf

        options = {"xatol": 1e-10, "fatol": 1e-13, "maxiter": 20000, "maxfev": 20000}
        starts = [np.ones(len(structures)), np.full(len(structures), np.sqrt(0.1))]
        fits = [
            optimize.minimize(criterion, start, method="Nelder-Mead", options=options)  # type: ignore[call-overload]
            for start in starts
        ]
        best = min(fits, key=lambda fit: fit.fun)
        self.converged = bool(best.success)
        self.gamma = best.x * best.x
        try:
            value, quadratic = profiled(self.gamma)
        except np.linalg.LinAlgError as error:
            raise Skipped(f"the mixed model could not be fitted: {error}") from error
        sigma2 = quadratic / df
        self.scale = sigma2 * spread**2
        # -2 log-likelihood of the scaled data plus the Jacobian of the scaling.
        self.llf = -0.5 * (value + df * (1.0 + np.log(2.0 * np.pi / df))) - n * np.log(spread)
        self.variances = [float(g) * self.scale for g in self.gamma]
        self.at_boundary = [i for i, g in enumerate(self.gamma) if not g >= BOUNDARY_RATIO]


def _structures(frame: pd.DataFrame, factors: int) -> list[np.ndarray]:
    """``G_i = Z_i Z_i'`` of the participant intercept and, with two factors, of the
    participant x factor intercepts: 1 where two observations share them."""
    g = frame["g"].to_numpy()
    same = np.equal.outer(g, g)
    out = [same.astype(float)]
    if factors == 2:
        for column in ("f0", "f1"):
            level = frame[column].to_numpy()
            out.append((same & np.equal.outer(level, level)).astype(float))
    return out


def _design(formula: str, frame: pd.DataFrame):
    """The fixed-effects design of ``formula`` with sum-to-zero contrasts (patsy)."""
    import patsy

    coded = formula.replace("C(f0)", "C(f0, Sum)").replace("C(f1)", "C(f1, Sum)")
    return patsy.dmatrix(coded, frame)


def mixedlm(
    data: pd.DataFrame,
    dv: str,
    fixed: str | Sequence[str],
    subject: str,
    *,
    interaction: bool = True,
) -> pd.DataFrame:
    """Linear mixed model of one or two within-subject factors: Kenward-Roger F per term.

    One factor: ``dv ~ A + (1 | subject)``. Two: ``dv ~ A * B + (1 | subject) +
    (1 | subject:A) + (1 | subject:B)`` (``A + B`` without ``interaction``). Each term is
    tested by the Kenward-Roger F of the REML fit with sum-to-zero contrasts (R:
    ``anova(lmer(...), type = 3, ddf = "Kenward-Roger")`` with ``contr.sum``) and, beside
    it, by the likelihood ratio of ML fits (R: ``anova(lmer(..., REML = FALSE), ...)``):
    main effects in the additive model against the model without them, the interaction
    in the factorial model against the additive one.

    Parameters
    ----------
    data : pandas.DataFrame
        One row per observation (long format); repeated trials are used as they are.
    dv : str
        Column of the dependent variable.
    fixed : str or sequence of str
        One or two categorical fixed-effect columns (e.g. method, or method and task).
    subject : str
        Column identifying participants.
    interaction : bool
        With two factors, also fit and test their interaction (a row ``"A x B"``).

    Returns
    -------
    pandas.DataFrame
        One row per term, columns ``term, F, df1, df2, p, chi2, lrt_df, p_lrt, n,
        n_groups, note``: the Kenward-Roger F, its degrees of freedom and p; the
        likelihood-ratio chi-square, its degrees of freedom (the coefficients dropped)
        and p; the note names a variance component at the boundary or a fit not fully
        converged.

    Examples
    --------
    >>> y = [1.0, 1.5, 1.2, 1.1, 2.0, 2.2, 2.5, 1.9, 3.1, 2.9, 3.6, 3.0]
    >>> data = pd.DataFrame({"y": y, "condition": [c for c in "abc" for _ in range(4)]})
    >>> data["subject"] = [f"s{i % 4 + 1}" for i in range(12)]
    >>> table = mixedlm(data, "y", "condition", "subject")
    >>> table[["term", "F", "df1", "df2", "chi2", "lrt_df"]].round(1)
            term     F  df1  df2  chi2  lrt_df
    0  condition  79.6  2.0  6.0  31.8     2.0

    The F is the repeated-measures ANOVA's (:func:`casa_core.stats.within.rm_anova`,
    F(2, 6) = 79.605), the likelihood ratio's p far smaller than the F's:

    >>> print(f"{table['p'].iloc[0]:.1e} {table['p_lrt'].iloc[0]:.1e}")
    4.8e-05 1.2e-07
    """
    factors = as_list(fixed)
    if not 1 <= len(factors) <= 2:
        raise ValueError(f"mixedlm: fixed must name 1 or 2 factors, got {factors}")
    terms = [*factors, *([" x ".join(factors)] if interaction and len(factors) == 2 else [])]
    frame = clean(data, dv, [*factors, subject], "mixedlm")
    try:
        n_groups = _require_estimable(frame, dv, factors, subject)
        model_frame = _model_frame(frame, dv, factors, subject)
        pairs, full = _nested_models(factors, terms)
        y = model_frame["y"].to_numpy(dtype=float)
        structures = [*_structures(model_frame, len(factors))]
        designs = {f: _design(f, model_frame) for pair in pairs.values() for f in pair}
        fits = {f: _Fit(np.asarray(X), y, structures, reml=False) for f, X in designs.items()}
        X = _design(full, model_frame)
        reml = _Fit(np.asarray(X), y, structures, reml=True)
        tests = _kenward_roger_tests(X, y, structures, reml)
    except Skipped as why:
        return pd.concat(
            [skipped_row(MIXED_COLUMNS, str(why), term=t) for t in terms], ignore_index=True
        )
    note = _note(factors, reml, [*fits.values()], tests)
    rows = []
    for (term, (with_term, without)), coded in zip(pairs.items(), tests, strict=True):
        lrt_df = float(designs[with_term].shape[1] - designs[without].shape[1])
        chi2 = max(0.0, 2.0 * (fits[with_term].llf - fits[without].llf))  # optimiser noise
        kr = tests[coded]
        rows.append(
            {
                "term": term,
                "F": float(kr["F"]),
                "df1": float(kr["df1"]),
                "df2": float(kr["df2"]),
                "p": float(kr["p"]),
                "chi2": chi2,
                "lrt_df": lrt_df,
                "p_lrt": float(stats.chi2.sf(chi2, lrt_df)),
                "n": len(model_frame),
                "n_groups": n_groups,
                "note": note,
            }
        )
    return pd.DataFrame(rows, columns=[*MIXED_COLUMNS, "note"])


def _require_estimable(frame: pd.DataFrame, dv: str, factors: list[str], subject: str) -> int:
    """The number of participants; raises :class:`Skipped` if the model cannot be fitted."""
    for factor in factors:
        if len(levels(frame[factor])) < 2:
            raise Skipped(f"needs at least 2 levels of {factor!r}, found {levels(frame[factor])}")
    n_groups = frame[subject].nunique()
    if n_groups < 2:
        raise Skipped(f"needs at least 2 participants, got {n_groups}")
    require_representable(frame[dv], dv)
    if frame[dv].var() == 0.0:
        raise Skipped(f"zero variance: every value of {dv!r} is the same")
    return n_groups


def _model_frame(frame: pd.DataFrame, dv: str, factors: list[str], subject: str) -> pd.DataFrame:
    """The data under the formulas' names: ``y``, ``g`` (participant), ``f0``, ``f1`` (str)."""
    names = {dv: "y", subject: "g"} | {f: f"f{i}" for i, f in enumerate(factors)}
    model_frame = frame.rename(columns=names).reset_index(drop=True)
    for column in ["g", *(f"f{i}" for i in range(len(factors)))]:
        model_frame[column] = model_frame[column].astype(str)
    return model_frame


def _nested_models(factors: list[str], terms: list[str]) -> tuple[dict[str, tuple[str, str]], str]:
    """Per term, the formulas of the ML models with and without it; the REML model's formula.

    Main effects are tested in the additive model, the interaction against it.
    """
    parts = [f"C(f{i})" for i in range(len(factors))]
    pairs = {
        factor: (" + ".join(parts), " + ".join(p for p in parts if p != part) or "1")
        for factor, part in zip(factors, parts, strict=True)
    }
    full = " + ".join(parts)
    if len(terms) == 3:
        full = " * ".join(parts)
        pairs[terms[2]] = (full, " + ".join(parts))
    return pairs, full


def _kenward_roger_tests(X, y: np.ndarray, structures: list[np.ndarray], reml: _Fit) -> dict:
    """The Kenward-Roger test of each coded term of the REML fit's design ``X``, by name."""
    variances = [*reml.variances, reml.scale]
    tests = {}
    for name, columns in X.design_info.term_name_slices.items():
        if name != "Intercept":
            L = np.eye(X.shape[1])[columns]
            try:
                tests[name] = kenward_roger(
                    np.asarray(X), y, [*structures, np.eye(len(y))], variances, L
                )
            except np.linalg.LinAlgError:  # a covariance that rounding leaves singular
                tests[name] = pd.Series(dict.fromkeys(KR_COLUMNS, np.nan))
    return tests


def _note(factors: list[str], reml: _Fit, ml_fits: list[_Fit], tests: dict) -> str:
    """The rows' note: the test and random effects, and any fit not converged or at 0."""
    labels = ["participant", *(f"participant x {f}" for f in factors if len(factors) == 2)]
    note = (
        f"Kenward-Roger F (REML; random intercepts: {', '.join(labels)}); likelihood "
        "ratio of ML fits beside it"
    )
    if not all(fit.converged for fit in [reml, *ml_fits]):
        note += "; fit did not fully converge"
    if reml.at_boundary:
        note += (
            f"; boundary fit: the variance of {', '.join(labels[i] for i in reml.at_boundary)} "
            "is estimated at 0 (its stratum merges with the residual)"
        )
    if not all(np.isfinite(kr["F"]) for kr in tests.values()):
        note += "; Kenward-Roger F undefined (no information on a variance component)"
    return note


__all__ = ["BOUNDARY_RATIO", "mixedlm"]
