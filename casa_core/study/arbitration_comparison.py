"""The arbitration comparison (paper, Sec. IV-B and Fig. alpha_methods).

The robot knows the green and purple goals; the trajectory moves optimally to
the red goal, which it does not know. Along it we record, per known goal, the
belief P(theta | xi) and the confidence beta_hat, and the user's control
authority alpha that distance (PBA), belief and confidence (CASA) arbitration
would give for the most likely goal.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from casa_core.assist.assistant import Assistant

COLUMNS = ["t", "intent", "belief", "beta", "alpha_distance", "alpha_belief", "alpha_confidence"]


def compare_arbitrations(assistant: Assistant, trajectory: np.ndarray) -> pd.DataFrame:
    """Feed ``trajectory`` (states every ``assistant.period``, the first the start) to it.

    Returns
    -------
    DataFrame
        One row per (inference step, known intent) with the columns of
        ``data/processed/case_study/arbitration.csv``; the three alpha columns
        repeat across the intents of a step. The first rows (t = 0) are the prior.
    """
    trajectory = np.asarray(trajectory, dtype=float)
    assistant.reset(trajectory[0])
    n = len(assistant.names)
    rows = [(0.0, name, 1.0 / n, 0.0, 1.0, 1.0, 1.0) for name in assistant.names]
    for state in trajectory[1:]:
        step = assistant.update(state, user_input=True)  # the trajectory is the user's
        alphas = step.alpha_by_arbitration
        for name in assistant.names:
            rows.append(
                (
                    step.time,
                    name,
                    step.belief[name],
                    step.beta[name],
                    alphas["distance"],
                    alphas["belief"],
                    alphas["confidence"],
                )
            )
    return pd.DataFrame(rows, columns=COLUMNS)
