"""Gaussian likelihood of the measured data from an updating problem's residual vector, and
priors from the parameter bounds.

Noise model: every modal residual r_i of the problem is taken as an independent Gaussian error
with a standard deviation s_i implied by the data's noise (:class:`~framework.inference.noise.DataNoise`:
the data's standard deviations where given, else the assumed defaults of
:mod:`framework.inference.noise`). How a residual relates to the data noise is the
formulation's own knowledge: ``problem.formulation.residual_std(measured, spec, noise)``
returns the scales s_i, the standard deviation of each residual's datum in the data's units
and the number of independent data (the formulations of :mod:`framework.updating.formulations`
implement it; the problem is taken duck-typed, nothing here knows a formulation by name). A
formulation without ``residual_std`` has its residuals taken as standard normal (named as an
assumption). Every assumed standard deviation, and every approximation a formulation makes
(e.g. its MAC rows taken as Gaussian), is written in the ``noise_assumed`` text, "" when all
standard deviations come from the data. Penalty rows (ratio constraints, Tikhonov) are not
data and are left out of the likelihood.

    ln L(theta) = -1/2 sum_i (r_i / s_i)^2 - sum_i ln sigma_i - n/2 ln(2 pi)

with sigma_i the standard deviation of datum i in its own units (Hz for a frequency, the
shape's units for a shape component; the MAC row's s_i for a MAC row), so that ln L is the
density of the data as measured (a hand computation in Hz gives the same number).

A failed evaluation has ln L = -inf.

Priors on theta (physical units), independent per parameter: ``uniform`` on the bounds
(default); ``normal``: N(initial, (width * span)^2) truncated to the bounds (width default
0.25 of the bound span).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.special import ndtr

from framework.core.errors import InputError
from framework.core.parameters import ParameterSet
from framework.inference.noise import DataNoise, data_noise

LN_2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class NoiseModel:
    """Standard deviation of each modal residual, s (m_r,), and the assumption made ("" if none).

    n_data: number of data (frequencies + independent shape components) for chi2 / dof;
    data_std: standard deviation of each residual's datum in the data's units (normalization);
    data: the data's noise (standard deviations and their sources) the scales come from."""

    scales: np.ndarray
    assumed: str
    n_data: int
    data_std: np.ndarray | None = None
    data: DataNoise | None = None

    @property
    def log_norm(self) -> float:
        std = self.scales if self.data_std is None else self.data_std
        return float(-np.sum(np.log(std)) - 0.5 * std.size * LN_2PI)

    @property
    def sources(self) -> dict[str, str]:
        """{"frequency": source, "shape": source} of the data's standard deviations ("" unused)."""
        if self.data is None:
            return {"frequency": "", "shape": ""}
        return {"frequency": self.data.frequency_source, "shape": self.data.shape_source}

    def log_likelihood(self, residuals: np.ndarray, ok: np.ndarray | None = None) -> np.ndarray:
        """ln L of residual rows (n, >= m_r): the first m_r columns are the modal residuals."""
        R = np.atleast_2d(np.asarray(residuals, float))[:, : self.scales.size]
        chi2 = np.sum((R / self.scales) ** 2, axis=1)
        out = -0.5 * chi2 + self.log_norm
        if ok is not None:
            out = np.where(ok, out, -np.inf)
        return out

    def chi2(self, residuals: np.ndarray) -> np.ndarray:
        R = np.atleast_2d(np.asarray(residuals, float))[:, : self.scales.size]
        return np.sum((R / self.scales) ** 2, axis=1)


def noise_model(problem, noise: DataNoise | None = None) -> NoiseModel:
    """The residual standard deviations of ``problem`` given the data's noise (default: the
    data's standard deviations, else the assumed defaults; module docstring)."""
    measured, spec, formulation = problem.measured, problem.spec, problem.formulation
    if noise is None:
        noise = data_noise(measured, use_shapes=bool(getattr(spec, "use_shapes", True)))
    residual_std = getattr(formulation, "residual_std", None)
    if residual_std is None:
        n = problem.n_modal_residuals
        name = getattr(formulation, "name", "") or getattr(spec, "formulation", "")
        return NoiseModel(np.ones(n), f"residuals of formulation {name!r} taken as standard normal", n,
                          np.ones(n), noise)
    std = residual_std(measured, spec, noise)
    scales = np.asarray(std.scales, float)
    if scales.size != problem.n_modal_residuals:
        raise RuntimeError(f"residual_std gave {scales.size} scales for {problem.n_modal_residuals} modal residuals")
    if np.any(scales <= 0) or not np.all(np.isfinite(scales)):
        raise InputError("likelihood: a residual has zero weight (alpha, beta or a mode weight is 0); "
                         "its standard deviation would be 0")
    if not std.uses_shape_std:  # the shapes' noise does not enter: report no source for it
        noise = replace(noise, shape_std=None, shape_source="")
    assumed = noise.assumptions() + ([std.assumption] if std.assumption else [])
    return NoiseModel(scales, "; ".join(assumed), int(std.n_data), np.asarray(std.data_std, float), noise)


# ---- priors --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Prior:
    """Independent prior on theta: ``uniform`` on the bounds or truncated ``normal``
    N(initial, (width span)^2) on the bounds."""

    parameters: ParameterSet
    kind: str = "uniform"
    width: float = 0.25

    def __post_init__(self):
        if self.kind not in ("uniform", "normal"):
            raise InputError(f"prior: kind must be 'uniform' or 'normal', got {self.kind!r}")
        if not (0 < self.width < np.inf):
            raise InputError(f"prior: width must be a number > 0, got {self.width!r}")

    @property
    def span(self) -> np.ndarray:
        return self.parameters.upper - self.parameters.lower

    def _normal(self):
        p = self.parameters
        mu, sd = p.initial, self.width * self.span
        mass = ndtr((p.upper - mu) / sd) - ndtr((p.lower - mu) / sd)
        return mu, sd, mass

    def log_pdf(self, theta: np.ndarray) -> np.ndarray:
        """ln p(theta) for rows (n, k) (-inf outside the bounds)."""
        theta = np.atleast_2d(np.asarray(theta, float))
        p = self.parameters
        inside = np.all((theta >= p.lower) & (theta <= p.upper), axis=1)
        if self.kind == "uniform":
            value = np.full(len(theta), -np.sum(np.log(self.span)))
        else:
            mu, sd, mass = self._normal()
            z = (theta - mu) / sd
            value = np.sum(-0.5 * z**2 - np.log(sd) - 0.5 * LN_2PI - np.log(mass), axis=1)
        return np.where(inside, value, -np.inf)

    def hessian(self) -> np.ndarray:
        """-d^2 ln p / dtheta^2 (k, k): 0 for uniform, diag(1 / sd^2) for normal."""
        if self.kind == "uniform":
            return np.zeros((len(self.parameters),) * 2)
        return np.diag(1.0 / (self.width * self.span) ** 2)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """n draws (n, k) of theta."""
        p = self.parameters
        if self.kind == "uniform":
            return p.lower + rng.random((n, len(p))) * self.span
        from scipy.special import ndtri

        mu, sd, _ = self._normal()
        lo, hi = ndtr((p.lower - mu) / sd), ndtr((p.upper - mu) / sd)
        u = lo + rng.random((n, len(p))) * (hi - lo)
        return np.clip(mu + sd * ndtri(u), p.lower, p.upper)


def log_posterior_x(problem, noise: NoiseModel, prior: Prior, runner=None):
    """ln p(x | data) + const of normalized points X (n, k) as a function (for the samplers):
    ln L(theta(x)) + ln p(theta(x)); -inf outside [0, 1]^k or where the evaluation failed
    (the population in one ``problem.evaluate`` call, vectorized where the model and the
    formulation allow it)."""

    def log_prob(X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, float))
        inside = np.all((X >= 0.0) & (X <= 1.0), axis=1)
        out = np.full(len(X), -np.inf)
        if inside.any():
            theta = problem.parameters.to_physical(X[inside])
            out[inside] = log_likelihood(problem, noise, X[inside], runner) + prior.log_pdf(theta)
        return out

    return log_prob


def log_likelihood(problem, noise: NoiseModel, X: np.ndarray, runner=None) -> np.ndarray:
    """ln L at normalized points X (n, k): one ``problem.evaluate`` of the population."""
    ev = problem.evaluate(np.atleast_2d(np.asarray(X, float)), runner)
    return noise.log_likelihood(ev.residuals, ev.ok)
