"""Simulated power of hypotheses H1-H3: detections per replicate study, then their share.

A replicate study of N participants is analysed as a dataset is (:func:`analyze_study`,
but for the mixed models, which no check reads) and judged by the checks of
:mod:`casa_core.stats.claims` (H1-H3, paper's form and within-subjects form).
:func:`replicate_detections` says, per hypothesis, metric and form, whether the
replicate detected it (:data:`DETECTED`); :func:`power_table` turns the replicates'
detections into power with its Wilson 95 % interval
(``data/processed/power/power.csv``). No timing enters these tables: the same
detections always give the same bytes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import pandas as pd

from casa_core.io.tables import require_columns
from casa_core.stats import _claim_tests as checks
from casa_core.stats.margins import Margins
from casa_core.stats.study import analyze_study

#: Detected: in one replicate, every check of the hypothesis on the metric in that form
#: passed -- each superiority test at p < .05 (the paper's alpha; the omnibus test and
#: the Tukey pair in the paper's form, the repeated-measures ANOVA within subjects) with
#: the means in the direction the paper claims (lower error, efficiency, relative
#: effort), and each non-inferiority bound (one-sided 95 %) below its margin. A check
#: that cannot be decided counts as not detected.
DETECTED = (
    "every check of the hypothesis on the metric in this form passed: superiority at "
    f"p < {checks.SIGNIFICANCE} in the paper's direction (lower is better), "
    "non-inferiority bound below the margin; an undecided check is not a detection"
)
#: The participants of the paper's study (Sec. V-A), marked on the figure.
PAPER_N = 11
#: H1-H3 and the checks that decide them (casa_core.stats.claims).
HYPOTHESES = {"H1": checks.h1_checks, "H2": checks.h2_checks, "H3": checks.h3_checks}
#: The paper's form (each participant-condition independent) and the within-subjects form.
ANALYSES = checks.FORMS
#: The metrics of the hypotheses' words: "more accurate, efficient, and effortless".
METRICS = checks.METRICS
#: ``noninferiority_alpha``: the one-sided level of the non-inferiority checks.
DETECTION_COLUMNS = [
    "variant",
    "replicate",
    "N",
    "hypothesis",
    "metric",
    "analysis",
    "noninferiority_alpha",
    "detected",
]
POWER_COLUMNS = [
    "variant",
    "N",
    "hypothesis",
    "metric",
    "analysis",
    "noninferiority_alpha",
    "power",
    "ci_low",
    "ci_high",
    "replicates",
]


def first_participants(trials: pd.DataFrame, n: int) -> pd.DataFrame:
    """The rows of the first ``n`` participants (``p01``, ``p02``, ... in number order).

    Raises
    ------
    ValueError
        If the table has fewer than ``n`` participants.

    Examples
    --------
    >>> trials = pd.DataFrame({"participant": ["p10", "p2", "p1", "p2"], "error": [1, 2, 3, 4]})
    >>> first_participants(trials, 2)["participant"].tolist()
    ['p2', 'p1', 'p2']
    """
    require_columns(trials, ["participant"], "trials table")
    ids = sorted(trials["participant"].astype(str).unique(), key=lambda p: (len(p), p))
    if len(ids) < n:
        raise ValueError(f"trials table: {len(ids)} participant(s), fewer than N = {n}")
    return trials[trials["participant"].astype(str).isin(ids[:n])]


def replicate_detections(
    trials: pd.DataFrame,
    *,
    sizes: Iterable[int],
    variant: str,
    replicate: int,
    margins: Margins | None = None,
) -> pd.DataFrame:
    """Whether one replicate study detects each of H1-H3, per N, metric and form.

    Parameters
    ----------
    trials : pandas.DataFrame
        The replicate's trials table, with at least ``max(sizes)`` participants.
    sizes : iterable of int
        The numbers of participants; the study of N is the first N participants.
    variant, replicate : str, int
        Written into the rows.
    margins : Margins, optional
        The non-inferiority margins (the config's ``statistics``).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`DETECTION_COLUMNS`; ``detected`` as :data:`DETECTED` says.

    Examples
    --------
    Four participants of the Known Goal task whose error is far lower under CASA; their
    efficiency and relative effort do not vary within a condition, so those tests
    cannot be computed: undecided, not detected.

    >>> levels, jitter = {"NA": 3.0, "PBA": 2.0, "CASA": 1.0}, [0.0, 0.2, -0.1, 0.15, -0.2]
    >>> rows = [dict(participant=f"p{i}", task="known_goal", method=method,
    ...              phase="no_misspecification", error=v + 0.1 * i + jitter[(i + k) % 5],
    ...              efficiency=v, relative_effort=v / 3)
    ...         for i in range(1, 5) for k, (method, v) in enumerate(levels.items())]
    >>> table = replicate_detections(pd.DataFrame(rows), sizes=[4], variant="default",
    ...                              replicate=1, margins=Margins(fractions={"error": 0.1}))
    >>> h1 = table[table["hypothesis"] == "H1"]
    >>> h1.pivot(index="metric", columns="analysis", values="detected")
    ... # doctest: +NORMALIZE_WHITESPACE
    analysis         paper  within
    metric
    efficiency       False   False
    error             True    True
    relative_effort  False   False

    H2 and H3 have no trials here: not detected.

    >>> bool(table[table["hypothesis"] != "H1"]["detected"].any())
    False
    """
    rows = []
    alpha = (margins or Margins()).alpha
    for n in sorted(sizes):
        study = first_participants(trials, n)
        # The checks read no mixed model's row (casa_core.stats._claim_tests).
        stats = analyze_study(study, margins=margins, metrics=list(METRICS), mixed_models=False)
        for hypothesis, judge in HYPOTHESES.items():
            found = judge(stats, study)
            for metric in METRICS:
                for form in ANALYSES:
                    mine = [c for c in found if c.metric == metric and c.form == form]
                    detected = bool(mine) and all(c.passed is True for c in mine)
                    rows.append([variant, replicate, n, hypothesis, metric, form, alpha, detected])
    return pd.DataFrame(rows, columns=DETECTION_COLUMNS)


def wilson_interval(detected: int, replicates: int) -> tuple[float, float]:
    """The Wilson score 95 % interval of a proportion ``detected / replicates``.

    ``statsmodels.stats.proportion.proportion_confint(..., method="wilson")``.

    Examples
    --------
    >>> [round(x, 4) for x in wilson_interval(8, 10)]
    [0.4902, 0.9433]
    """
    from statsmodels.stats.proportion import proportion_confint

    low, high = proportion_confint(detected, replicates, alpha=0.05, method="wilson")
    return float(low), float(high)


def power_table(detections: pd.DataFrame | Sequence[pd.DataFrame]) -> pd.DataFrame:
    """The power per variant, N, hypothesis, metric and form: the share of detections.

    Parameters
    ----------
    detections : DataFrame or sequence of DataFrames
        :func:`replicate_detections` of the replicates (one table or one per replicate).

    Returns
    -------
    pandas.DataFrame
        Columns :data:`POWER_COLUMNS`: ``power`` = detections / ``replicates``, and its
        Wilson 95 % interval ``ci_low``, ``ci_high``; ``noninferiority_alpha`` is the
        one-sided level the non-inferiority checks were run at. Sorted by variant (as given), N,
        hypothesis, metric (:data:`METRICS`' order) and analysis.

    Raises
    ------
    ValueError
        If a replicate appears twice for one variant, N, hypothesis, metric and form.

    Examples
    --------
    >>> one = {"variant": "default", "N": 6, "hypothesis": "H3", "metric": "error",
    ...        "analysis": "paper", "noninferiority_alpha": 0.05}
    >>> rows = pd.DataFrame([one | {"replicate": r, "detected": r <= 8} for r in range(1, 11)])
    >>> power_table(rows).drop(columns="noninferiority_alpha").round(4)
    ... # doctest: +NORMALIZE_WHITESPACE
    variant  N hypothesis metric analysis  power  ci_low  ci_high  replicates
    0  default  6  H3  error  paper  0.8  0.4902  0.9433  10
    """
    if not isinstance(detections, pd.DataFrame):
        detections = pd.concat(list(detections), ignore_index=True)
    require_columns(detections, DETECTION_COLUMNS, "detections table")
    keys = ["variant", "N", "hypothesis", "metric", "analysis", "noninferiority_alpha"]
    twice = detections[detections.duplicated([*keys, "replicate"])]
    if not twice.empty:
        first = twice.iloc[0]
        raise ValueError(
            f"detections: replicate {first['replicate']} of variant {first['variant']}, "
            f"N = {first['N']} appears twice; each replicate's detections come from one table"
        )
    variants = list(dict.fromkeys(detections["variant"]))
    rows = []
    for key, part in detections.groupby(keys, sort=False):
        hits, total = int(part["detected"].astype(bool).sum()), len(part)
        rows.append([*key, hits / total, *wilson_interval(hits, total), total])
    table = pd.DataFrame(rows, columns=POWER_COLUMNS)
    order = {
        "variant": lambda s: s.map(variants.index),
        "metric": lambda s: s.map(list(METRICS).index),
    }
    table = table.sort_values(keys, key=lambda s: order.get(s.name, lambda x: x)(s))
    table["N"] = table["N"].astype(int)
    return table.reset_index(drop=True)
