"""What the assistant concludes at one inference step (:class:`Inference`)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Inference:
    """What the assistant concluded at one inference step.

    Attributes
    ----------
    time : float
        Seconds since the trial started, at the end of this step (idle steps included).
    beta : dict
        beta_hat per intent name (the beta used for inference is 1 under PBA).
    belief : dict
        P(theta | xi) per intent name.
    suboptimality : dict
        Scaled suboptimality per intent name.
    intent : str
        The most likely intent theta*.
    alpha : float
        The user's control authority under the assistant's arbitration.
    alpha_by_arbitration : dict
        alpha that each arbitration ("confidence", "distance", "belief") would
        give for the same theta*, for comparing them on one trajectory.
    misspecified : bool
        True when evidence has been seen and every beta_hat is below epsilon.
    evidence_steps : int
        Steps of evidence the estimates rest on (at most ``T / period``): the ``t`` of
        beta_hat and of the likelihood, which counts steps, not seconds.
    """

    time: float
    beta: dict
    belief: dict
    suboptimality: dict
    intent: str
    alpha: float
    alpha_by_arbitration: dict = field(default_factory=dict)
    misspecified: bool = False
    evidence_steps: int = 0
