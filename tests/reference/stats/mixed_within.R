# Reference values for casa_core.stats.mixed, kenward_roger and the ratio margins of
# noninferiority (tests/stats/test_stats_mixed_kr.py). Our own seeded data, no
# third-party data: writes mixed_within.csv (the data) and mixed_within_r.csv (R's
# numbers). Run from this folder: Rscript mixed_within.R (versions in README.md).
suppressPackageStartupMessages({
  library(lme4)
  library(lmerTest)
  library(pbkrtest)
})
options(contrasts = c("contr.sum", "contr.poly"))  # type III tests of main effects
set.seed(31)

# 11 participants x 3 methods x 2 tasks, one value per cell (a participant's cell mean):
# random intercepts per participant, participant x method and participant x task.
n <- 11
design <- expand.grid(method = c("a", "b", "c"), task = c("t1", "t2"),
                      participant = sprintf("p%02d", 1:n), stringsAsFactors = FALSE)
design <- design[, c("participant", "method", "task")]
u <- setNames(rnorm(n, 0, 1.0), sprintf("p%02d", 1:n))
um <- rnorm(n * 3, 0, 0.6); names(um) <- outer(sprintf("p%02d", 1:n), c("a", "b", "c"), paste)
ut <- rnorm(n * 2, 0, 0.5); names(ut) <- outer(sprintf("p%02d", 1:n), c("t1", "t2"), paste)
fixed <- c(a = 0, b = -0.5, c = -0.9)[design$method] + c(t1 = 0, t2 = 0.7)[design$task] +
  ifelse(design$method == "c" & design$task == "t2", 0.6, 0)
design$y <- round(10 + fixed + u[design$participant] +
  um[paste(design$participant, design$method)] +
  ut[paste(design$participant, design$task)] + rnorm(nrow(design), 0, 0.4), 4)
# Five cells missing at random: the unbalanced design (dropped = 1).
design$dropped <- 0L
design$dropped[sample(nrow(design), 5)] <- 1L
write.csv(design, "mixed_within.csv", row.names = FALSE, quote = FALSE)

rows <- list()
add <- function(case, test, term, statistic, df1, df2, p) {
  rows[[length(rows) + 1]] <<- data.frame(case = case, test = test, term = term,
    statistic = statistic, df1 = df1, df2 = df2, p = p)
}
terms <- c("method", "task", "method:task")
for (case in c("balanced", "unbalanced")) {
  d <- if (case == "balanced") design else design[design$dropped == 0, ]
  full <- lmer(y ~ method * task + (1 | participant) + (1 | participant:method) +
                 (1 | participant:task), data = d, REML = TRUE)
  for (ddf in c("Kenward-Roger", "Satterthwaite")) {
    a <- anova(full, type = 3, ddf = ddf)
    for (term in terms) {
      add(case, ddf, term, a[term, "F value"], a[term, "NumDF"], a[term, "DenDF"],
          a[term, "Pr(>F)"])
    }
  }
  # pbkrtest directly: the interaction as a comparison of nested REML models.
  additive <- update(full, . ~ . - method:task)
  kr <- KRmodcomp(full, additive)$test["Ftest", ]
  add(case, "KRmodcomp", "method:task", kr$stat, kr$ndf, kr$ddf, kr$p.value)
  # Likelihood ratios of ML fits: main effects in the additive model, the interaction
  # against it (type II, as casa_core.stats.mixed tests them).
  ml <- function(f) lmer(f, data = d, REML = FALSE)
  re <- "(1 | participant) + (1 | participant:method) + (1 | participant:task)"
  f <- function(fixed) as.formula(paste("y ~", fixed, "+", re))
  m_add <- ml(f("method + task")); m_full <- ml(f("method * task"))
  for (pair in list(list("method", ml(f("task")), m_add), list("task", ml(f("method")), m_add),
                    list("method:task", m_add, m_full))) {
    lr <- anova(pair[[2]], pair[[3]])
    add(case, "LRT", pair[[1]], lr$Chisq[2], lr$Df[2], NA, lr[["Pr(>Chisq)"]][2])
  }
  vc <- as.data.frame(VarCorr(full))
  for (i in seq_len(nrow(vc))) add(case, "REML variance", vc$grp[i], vc$vcov[i], NA, NA, NA)
}
# One factor, random intercept only: task t1, unbalanced.
d <- design[design$task == "t1" & design$dropped == 0, ]
one <- lmer(y ~ method + (1 | participant), data = d, REML = TRUE)
a <- anova(one, type = 3, ddf = "Kenward-Roger")
add("one factor", "Kenward-Roger", "method", a["method", "F value"], a["method", "NumDF"],
    a["method", "DenDF"], a["method", "Pr(>F)"])

# Ratio margins: H0 mean(new) - (1 + f) mean(reference) >= 0, one-sided at alpha = 0.05,
# on the t1 cells of methods c (new) and a (reference), f = 0.05. Paired: a t-test of
# the differences new - (1 + f) reference; independent: Welch's t of new against
# (1 + f) reference. The bound: the ratio r at which the test's p is alpha (Fieller).
t1 <- design[design$task == "t1", ]
new <- t1$y[t1$method == "c"]; ref <- t1$y[t1$method == "a"]
f <- 0.05
paired_p <- function(r) t.test(new - r * ref, alternative = "less")$p.value
welch_p <- function(r) t.test(new, r * ref, alternative = "less")$p.value
for (form in c("paired", "welch")) {
  p_of <- if (form == "paired") paired_p else welch_p
  test <- if (form == "paired") t.test(new - (1 + f) * ref, alternative = "less") else
    t.test(new, (1 + f) * ref, alternative = "less")
  bound <- uniroot(function(r) p_of(r) - 0.05, c(mean(new) / mean(ref), 2), tol = 1e-12)$root
  add(paste("ratio", form), "t", "ratio", test$statistic, test$parameter, NA, test$p.value)
  add(paste("ratio", form), "Fieller bound", "ratio", bound, NA, NA, NA)
  add(paste("ratio", form), "estimate", "ratio", mean(new) / mean(ref), NA, NA, NA)
}
out <- do.call(rbind, rows)
write.csv(out, "mixed_within_r.csv", row.names = FALSE, quote = FALSE)
print(out, digits = 10)
