"""The stats table's columns and the collector that builds its rows (see ``study``)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

#: The columns of stats.csv, in order (see :func:`casa_core.stats.analyze_study`).
STATS_COLUMNS = [
    "hypothesis",
    "analysis",
    "task",
    "metric",
    "term",
    "comparison",
    "statistic",
    "df1",
    "df2",
    "p",
    "effect_size",
    "estimate",
    "ci_low",
    "ci_high",
    "margin",
    "noninferior",
    "n",
    "p_uncorrected",
    "epsilon",
    "sphericity_W",
    "sphericity_p",
    "note",
]
#: Significant digits of every number of stats.csv: beyond about 14 the last bits of the
#: LAPACK behind statsmodels and pingouin depend on the processor's kernel.
DIGITS = 8
#: On every non-inferiority row: the one-sided level of its test and bound
#: (:func:`noninferiority_level` reads it back from stats.csv).
LEVEL_NOTE = "one-sided level {:g}"
#: Epsilon below 1 by more than rounding: the Greenhouse-Geisser correction applies.
_EPSILON_ONE = 1.0 - 1e-9


class Rows:
    """Collects the rows of the stats table, one per test (or per term, pair or comparison)."""

    def __init__(self) -> None:
        self.rows: list[dict] = []

    def add(self, **values) -> None:
        row: dict[str, Any] = {column: np.nan for column in STATS_COLUMNS}
        row.update({"comparison": "", "note": ""})
        row.update({k: v for k, v in values.items() if k in STATS_COLUMNS})
        self.rows.append(row)

    def take(self, key: dict, line: pd.Series, fields: dict[str, str], **values) -> None:
        """Add a row with ``fields`` (stats column -> column of ``line``) taken from ``line``."""
        self.add(**key, **{column: line[name] for column, name in fields.items()}, **values)

    def terms(self, key: dict, table: pd.DataFrame, stat: str, effect: str, extra=None):
        for _, line in table.iterrows():
            note = line["note"]
            if extra is not None:
                note = "; ".join(x for x in (note, extra(line)) if x)
            self.take(
                key,
                line,
                {"statistic": stat, "df1": "df1", "p": "p", "n": "n"},
                term=str(line["term"]),
                df2=line.get("df2", np.nan),
                effect_size=line.get(effect, np.nan),
                note=note,
            )

    def repeated(self, key: dict, table: pd.DataFrame) -> None:
        """rm_anova rows: where epsilon < 1, ``p`` and the dfs are Greenhouse-Geisser's.

        The uncorrected p stays in ``p_uncorrected``; ``epsilon`` and Mauchly's test of
        sphericity (``sphericity_W``, ``sphericity_p``) are reported for every term.
        """
        for _, line in table.iterrows():
            eps = float(line["eps"])
            corrected = np.isfinite(eps) and eps < _EPSILON_ONE and np.isfinite(line["p_gg"])
            scale = eps if corrected else 1.0
            note = line["note"]
            if corrected:
                gg = (
                    f"Greenhouse-Geisser corrected: epsilon = {eps:.3f}, df x epsilon, "
                    f"uncorrected p = {line['p']:.4g}"
                )
                note = "; ".join(x for x in (gg, note) if x)
            self.take(
                key,
                line,
                {"statistic": "F", "effect_size": "ng2", "n": "n", "p_uncorrected": "p"},
                term=str(line["term"]),
                df1=line["df1"] * scale,
                df2=line["df2"] * scale,
                p=line["p_gg"] if corrected else line["p"],
                epsilon=eps,
                sphericity_W=line["W_spher"],
                sphericity_p=line["p_spher"],
                note=note,
            )

    def tukey(self, key: dict, table: pd.DataFrame) -> None:
        fields = {"p": "p", "estimate": "diff", "ci_low": "ci_low", "ci_high": "ci_high"}
        for _, line in table.iterrows():
            self.take(
                key,
                line,
                fields | {"note": "note"},
                term="method",
                comparison="" if pd.isna(line["A"]) else versus(line["A"], line["B"]),
                n=line["n_A"] + line["n_B"],
                # Model-based contrasts carry their t and residual df.
                statistic=line.get("t", np.nan),
                df1=line.get("df", np.nan),
            )

    def noninferiority(
        self, key: dict, table: pd.DataFrame, paired: bool, welch: bool = False, extra: str = ""
    ) -> None:
        line = table.iloc[0]
        # The word "paired" marks the within-subjects row only (stats.claims reads it).
        design = (
            "paired by participant"
            if paired
            else "independent samples, Welch's unequal variances"
            if welch
            else "independent samples, as the paper"
        )
        verdict = line["noninferior"]
        fields = {"statistic": "t", "df1": "df", "p": "p", "estimate": "estimate"}
        self.take(
            key,
            line,
            fields | {"ci_high": "bound", "margin": "margin"},
            term="method",
            comparison=versus(line["new"], line["reference"]),
            noninferior=verdict if not pd.isna(verdict) else pd.NA,
            n=line["n_new"] + (0 if paired else line["n_reference"]),
            note="; ".join(x for x in (line["note"], design, extra) if x),
        )

    def friedman(self, key: dict, line: pd.Series) -> None:
        fields = {"statistic": "Q", "df1": "df1", "p": "p", "effect_size": "W", "n": "n"}
        self.take(key, line, fields | {"note": "note"}, analysis="friedman", term="method")

    def wilcoxon(self, key: dict, table: pd.DataFrame) -> None:
        """One row per comparison; the note gives the Holm family and the unadjusted p."""
        family, skipped = len(table), int(table["p_unc"].isna().sum())
        fields = {"statistic": "V", "p": "p", "effect_size": "rbc", "estimate": "median_diff"}
        for _, line in table.iterrows():
            note = line["note"]
            if np.isfinite(line["p_unc"]):
                note = f"p Holm-adjusted over {family}"
                if skipped:
                    note += f" ({skipped} skipped, counted in the family)"
                note += f"; unadjusted p = {line['p_unc']:.4g}"
                note = "; ".join(x for x in (note, line["note"]) if x)
            self.take(
                key,
                line,
                fields | {"n": "n"},
                analysis="wilcoxon",
                term="method",
                comparison=versus(line["A"], line["B"]),
                note=note,
            )


def versus(a, b) -> str:
    return f"{a} vs {b}"


def noninferiority_level(notes) -> float | None:
    """The one-sided level the non-inferiority rows' ``notes`` name (:data:`LEVEL_NOTE`).

    Examples
    --------
    >>> noninferiority_level(["paired by participant; one-sided level 0.025", ""])
    0.025
    >>> noninferiority_level(["independent samples, as the paper"]) is None
    True
    """
    import re

    pattern = re.compile(re.escape(LEVEL_NOTE).replace(r"\{:g\}", r"([0-9.eE+-]+)"))
    found = {float(m.group(1)) for note in notes if (m := pattern.search(str(note)))}
    return found.pop() if len(found) == 1 else None


def significant(table: pd.DataFrame, digits: int = DIGITS) -> pd.DataFrame:
    """``table`` with every float rounded to ``digits`` significant digits (NaN stays).

    Examples
    --------
    >>> significant(pd.DataFrame({"p": [0.012345678949, 4.413731782073364, np.nan]}))["p"].tolist()
    [0.012345679, 4.4137318, nan]
    """
    out = table.copy()
    for column in out.columns:
        if out[column].dtype == np.float64:
            out[column] = [float(f"{v:.{digits}g}") for v in out[column].tolist()]
    return out
