"""Statistics for the CASA user study: tidy tables in, tidy tables out.

Nothing here knows about robots or files; condition names come from
:mod:`casa_core.vocabulary`. The modules, each with one job:

- :mod:`~casa_core.stats.between`, :mod:`~casa_core.stats.noninferiority`: the paper's
  analyses (ANOVA, ANCOVA, Tukey HSD, non-inferiority: pooled, Welch, paired);
- :mod:`~casa_core.stats.posthoc`: the method x task interaction and its comparisons;
- :mod:`~casa_core.stats.within`, :mod:`~casa_core.stats.mixed`,
  :mod:`~casa_core.stats.kenward_roger`, :mod:`~casa_core.stats.ranks`: the
  within-subjects analyses (repeated-measures ANOVA, the mixed model and its
  Kenward-Roger F, Friedman, Wilcoxon with Holm);
- :mod:`~casa_core.stats.margins`: non-inferiority margins from the config;
- :mod:`~casa_core.stats.descriptives`: the data's source, participants, means and SDs;
- :mod:`~casa_core.stats.study`: hypotheses H1-H4 as one table (``stats.csv``);
- :mod:`~casa_core.stats.wide`: the participants' cell means, one row each (``wide.csv``);
- :mod:`~casa_core.stats.apa`: APA-style text (``stats.md``);
- :mod:`~casa_core.stats.summary`: the results at a glance (``summary.md``);
- :mod:`~casa_core.stats.claims`: each claim of the paper judged on a dataset's tables
  (its verdicts: :mod:`~casa_core.stats.verdicts`; why one is not holds:
  :mod:`~casa_core.stats.causes`);
- :mod:`~casa_core.stats.results`: those verdicts as ``results.md``;
- :mod:`~casa_core.stats.robustness`: the claims under each modelling variant;
- :mod:`~casa_core.stats.power`: each replicate's detections and the power table.
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
