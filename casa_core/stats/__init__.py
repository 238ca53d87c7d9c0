"""Statistics for the CASA user study: tidy tables in, tidy tables out.

``between``: the paper's analyses (ANOVA, ANCOVA, Tukey HSD, non-inferiority);
``within``: the within-subjects ones (repeated-measures ANOVA, mixed model, Friedman,
Wilcoxon with Holm); ``study``: hypotheses H1-H4 as one table; ``apa``: every text the
statistics write, from one test result to the Markdown report of the table.
Nothing here knows about robots or files; condition names come from
:mod:`casa_core.vocabulary`.
"""

from casa_core.stats.apa import report_markdown
from casa_core.stats.between import ancova, anova, non_inferiority, tukey_hsd
from casa_core.stats.study import STATS_COLUMNS, analyze_study
from casa_core.stats.within import friedman, holm, mixedlm, rm_anova, wilcoxon_holm

__all__ = [
    "STATS_COLUMNS",
    "analyze_study",
    "ancova",
    "anova",
    "friedman",
    "holm",
    "mixedlm",
    "non_inferiority",
    "report_markdown",
    "rm_anova",
    "tukey_hsd",
    "wilcoxon_holm",
]
