"""Space-filling start points in the normalized box [0, 1]^k, drawn from a run's seed.

- "sobol": scrambled Sobol' sequence (scipy.stats.qmc.Sobol); its balance properties hold for
  n a power of 2, other n are its first n points (scipy's warning about that is silenced);
- "latin_hypercube": scipy.stats.qmc.LatinHypercube (one point per stratum of every axis);
- "random": uniform, numpy's default_rng(seed).

The same (n, k, seed, sampler) always gives the same points.
"""

from __future__ import annotations

import warnings
from typing import Literal

import numpy as np

Sampler = Literal["sobol", "latin_hypercube", "random"]


def sample(n: int, k: int, seed: int, sampler: Sampler = "sobol") -> np.ndarray:
    """n points (n, k) in [0, 1)^k."""
    if n < 1 or k < 1:
        raise ValueError(f"sample: need n >= 1 points in k >= 1 dimensions, got n={n}, k={k}")
    rng = np.random.default_rng(seed)
    if sampler == "random":
        return rng.random((n, k))
    from scipy.stats import qmc

    if sampler == "sobol":
        engine = qmc.Sobol(d=k, scramble=True, rng=rng)
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*balance properties of Sobol.*")
            return engine.random(n)
    if sampler == "latin_hypercube":
        return qmc.LatinHypercube(d=k, rng=rng).random(n)
    raise ValueError(f"unknown sampler {sampler!r}; use sobol, latin_hypercube or random")
