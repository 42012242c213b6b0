"""Samplers of the posterior in normalized coordinates x in [0, 1]^k, behind one interface.

Choice (swappable: a sampler is one entry of :data:`SAMPLERS`):

- posterior: ``emcee`` (affine-invariant ensemble MCMC, Goodman & Weare 2010): no tuning
  beyond the number of walkers, invariant to the strong linear correlations that updating
  parameters show (kyy with ex, the storey stiffnesses), and each step proposes one point per
  walker half, so a whole half-ensemble is evaluated as one population (one vectorized
  ``UpdatingProblem.evaluate`` call, or one batch for the process/Dask runners);
- evidence: ``dynesty`` (nested sampling, Skilling 2006; static sampler, multi-ellipsoid
  bounds): ln Z with its own error estimate, and posterior samples as a by-product. Its
  proposals are sequential (each depends on the last live point replaced), so it evaluates one
  point at a time (in process; the lab frame's evaluation is sub-millisecond). Preferred over
  TMCMC because it is a well-kept package with an error estimate of ln Z, and over SMC in PyMC
  because the model is a black box with no gradients.

Every random draw comes from the generator passed in (``np.random.Generator`` built from the
run's seed), so a run is reproducible on every evaluation backend (the log-density is pure).

Diagnostics (hand-written because they are a few lines on arrays):
- integrated autocorrelation time per parameter (``emcee.autocorr.integrated_time`` with
  tol=0) and ESS = n_walkers n_steps / tau;
- split R-hat (Gelman et al. 2013) with each walker's chain split in two halves:
  R = sqrt(((n-1)/n W + B/n) / W).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

log = logging.getLogger(__name__)

LogDensity = Callable[[np.ndarray], np.ndarray]  # (n, k) -> (n,)


@dataclass
class SamplerResult:
    """Posterior draws (n, k) in x (equally weighted), diagnostics per parameter and the evidence."""

    draws: np.ndarray
    log_prob: np.ndarray
    n_evaluations: int
    ess: np.ndarray
    rhat: np.ndarray
    acceptance: float = float("nan")
    log_evidence: float = float("nan")
    log_evidence_error: float = float("nan")
    extra: dict = field(default_factory=dict)


def split_rhat(chains: np.ndarray) -> np.ndarray:
    """Split R-hat per parameter of chains (n_steps, n_chains, k)."""
    n = chains.shape[0] // 2
    if n < 2:
        return np.full(chains.shape[-1], np.nan)
    halves = np.concatenate([chains[:n], chains[n : 2 * n]], axis=1)  # (n, 2 m, k)
    means = halves.mean(axis=0)
    W = halves.var(axis=0, ddof=1).mean(axis=0)
    B = n * means.var(axis=0, ddof=1)
    var = (n - 1) / n * W + B / n
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(var / W)


def run_emcee(log_prob: LogDensity, x0: np.ndarray, rng: np.random.Generator, n_walkers: int = 32,
              n_steps: int = 2000, burn: int = 500, thin: int = 1, progress: bool = False) -> SamplerResult:
    """Ensemble MCMC from the walkers' start x0 (n_walkers, k); draws after ``burn`` steps."""
    import emcee
    from emcee.autocorr import integrated_time

    k = x0.shape[1]
    count = {"n": 0}

    def counted(X):
        count["n"] += len(X)
        return log_prob(X)

    sampler = emcee.EnsembleSampler(n_walkers, k, counted, vectorize=True)
    state = emcee.State(x0, random_state=np.random.RandomState(int(rng.integers(2**32))).get_state())
    sampler.run_mcmc(state, n_steps, progress=progress)
    chain = sampler.get_chain(discard=burn, thin=thin)  # (n, walkers, k)
    lp = sampler.get_log_prob(discard=burn, thin=thin)
    tau = integrated_time(chain, tol=0, quiet=True)
    ess = chain.shape[0] * chain.shape[1] / np.maximum(tau, 1.0)
    return SamplerResult(chain.reshape(-1, k), lp.reshape(-1), count["n"], ess, split_rhat(chain),
                         acceptance=float(np.mean(sampler.acceptance_fraction)),
                         extra={"autocorr_time": tau.tolist()})


def run_dynesty(log_like: LogDensity, k: int, rng: np.random.Generator, prior_transform=None,
                n_live: int = 200, dlogz: float = 0.5, n_draws: int = 4000,
                max_evaluations: int | None = None) -> SamplerResult:
    """Static nested sampling of ln L over the prior given by ``prior_transform`` (unit cube ->
    x; default identity: uniform in x). Returns resampled equal-weight draws and ln Z +- error."""
    import dynesty
    from dynesty.utils import resample_equal

    transform = prior_transform or (lambda u: u)
    count = {"n": 0}

    def single(x):
        count["n"] += 1
        return float(log_like(np.asarray(x, float)[None, :])[0])

    sampler = dynesty.NestedSampler(single, transform, k, nlive=n_live, rstate=rng)
    sampler.run_nested(dlogz=dlogz, print_progress=False, maxcall=max_evaluations)
    res = sampler.results
    weights = np.exp(res.logwt - res.logz[-1])
    draws = resample_equal(res.samples, weights / weights.sum(), rstate=rng)
    idx = rng.choice(len(draws), size=min(n_draws, len(draws)), replace=False)
    ess = np.full(k, float(np.sum(weights) ** 2 / np.sum(weights**2)))
    return SamplerResult(draws[idx], np.full(len(idx), np.nan), count["n"], ess, np.full(k, np.nan),
                         log_evidence=float(res.logz[-1]), log_evidence_error=float(res.logzerr[-1]),
                         extra={"n_iterations": int(res.niter)})


#: posterior samplers by name (each: (log_prob, x0, rng, **settings) -> SamplerResult)
SAMPLERS = {"emcee": run_emcee}
#: evidence samplers by name (each: (log_like, k, rng, prior_transform, **settings) -> SamplerResult)
EVIDENCE_SAMPLERS = {"dynesty": run_dynesty}
