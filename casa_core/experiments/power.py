"""The power analysis' replicate studies: their seeds, configs and the jobs they take.

The config's ``power`` block names the numbers of participants (``sizes``), the
replicate studies per variant (``replicates``) and the robustness variants
(``variants``, :mod:`casa_core.experiments.robustness`). Replicate ``r`` (1-based) of a
variant is the variant's simulated study with :func:`replicate_seed` as
``simulation.seed`` and as many participants as the largest N: every random draw of the
study comes from that seed, so
each replicate has its own participants, and replicate ``r`` of two variants has the
same ones (variants are compared on the same simulated people). Its study of N is its
first N participants: the protocol counterbalances by participant number, so these are
exactly the participants a study of N with that seed would simulate.

Examples
--------
>>> from casa_core.config import DEFAULT_CONFIG, load_config
>>> config = load_config(DEFAULT_CONFIG)
>>> power_sizes(config), config["power"]["replicates"], power_variants(config)
([6, 8, 11, 16, 24], 200, ['default'])
>>> built = replicate_config(power_variant_config(config, "default"), 3)
>>> built["simulation"]["seed"] == replicate_seed(2021, 3), built["simulation"]["participants"]
(True, 24)
"""

from __future__ import annotations

import copy
from collections.abc import Mapping

import numpy as np

from casa_core.experiments.robustness import variant_config

#: A constant of the seed derivation, so that replicate seeds are not other draws of
#: the config seed's streams (``default_rng([seed, participant, stream])``).
POWER_STREAM = 7_000_001


def replicate_seed(seed: int, replicate: int) -> int:
    """The ``simulation.seed`` of replicate ``replicate`` (1-based) of the config seed ``seed``.

    The first 32-bit word of ``numpy.random.SeedSequence([seed, POWER_STREAM, replicate])``:
    stable (the same config seed always gives the same replicates) and distinct between
    replicates (a hash; :func:`replicate_seeds` checks it).

    Examples
    --------
    >>> replicate_seed(2021, 1), replicate_seed(2021, 2)
    (2375554415, 822571148)
    """
    if replicate < 1:
        raise ValueError(f"replicate must be >= 1 (1-based), got {replicate}")
    words = np.random.SeedSequence([int(seed), POWER_STREAM, int(replicate)]).generate_state(1)
    return int(words[0])


def replicate_seeds(seed: int, replicates: int) -> list[int]:
    """The seeds of replicates 1 to ``replicates``; ValueError if two were equal.

    Examples
    --------
    >>> len(set(replicate_seeds(2021, 200)))
    200
    """
    seeds = [replicate_seed(seed, r) for r in range(1, replicates + 1)]
    if len(set(seeds)) != len(seeds):
        raise ValueError(f"power: two replicates of seed {seed} share a seed; use another seed")
    return seeds


def power_sizes(config: Mapping) -> list[int]:
    """The numbers of participants of the ``power`` block, in increasing order."""
    return sorted(config["power"]["sizes"])


def power_variants(config: Mapping) -> list[str]:
    """The variants the ``power`` target runs."""
    return list(config["power"]["variants"])


def power_variant_config(config: Mapping, variant: str) -> dict:
    """The whole config of ``variant`` for the power target: as many participants as the
    largest N (:func:`casa_core.experiments.robustness.variant_config`, which leaves out the
    ``power`` block, so that the replicates' configs change only with what their jobs read).
    """
    return variant_config(config, variant, participants=max(power_sizes(config)))


def replicate_config(variant_settings: Mapping, replicate: int) -> dict:
    """Replicate ``replicate``'s config: ``variant_settings`` with the replicate's seed.

    ``variant_settings`` is :func:`power_variant_config`'s; its ``simulation.seed`` (the
    study's) is replaced by :func:`replicate_seed` of it.
    """
    built = copy.deepcopy(dict(variant_settings))
    built["simulation"]["seed"] = replicate_seed(built["simulation"]["seed"], replicate)
    return built
