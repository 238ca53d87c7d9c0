"""The study: simulated participants, the protocol, the trial runner and the Likert model."""
