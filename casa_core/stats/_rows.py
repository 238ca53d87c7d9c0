"""The stats table's columns and the collector that builds its rows (see ``study``)."""

from __future__ import annotations

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
    "note",
]


class Rows:
    """Collects the rows of the stats table, one per test (or per term, pair or comparison)."""

    def __init__(self) -> None:
        self.rows: list[dict] = []

    def add(self, **values) -> None:
        row = {column: np.nan for column in STATS_COLUMNS}
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
            )

    def noninferiority(self, key: dict, table: pd.DataFrame, paired: bool) -> None:
        line = table.iloc[0]
        design = "paired by participant" if paired else "independent samples, as the paper"
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
            note="; ".join(x for x in (line["note"], design) if x),
        )

    def friedman(self, key: dict, line: pd.Series) -> None:
        fields = {"statistic": "Q", "df1": "df1", "p": "p", "effect_size": "W", "n": "n"}
        self.take(key, line, fields | {"note": "note"}, analysis="friedman", term="method")

    def wilcoxon(self, key: dict, table: pd.DataFrame) -> None:
        """One row per comparison; the note gives the Holm family and the unadjusted p."""
        family = int(table["p_unc"].notna().sum())
        fields = {"statistic": "V", "p": "p", "effect_size": "rbc", "estimate": "median_diff"}
        for _, line in table.iterrows():
            note = line["note"]
            if np.isfinite(line["p_unc"]):
                note = f"p Holm-adjusted over {family}; unadjusted p = {line['p_unc']:.4g}"
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
