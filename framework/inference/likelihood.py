"""Gaussian likelihood of the measured data from an updating problem's residual vector, and
priors from the parameter bounds.

Noise model: every modal residual r_i of the problem (:mod:`framework.updating.objectives`) is taken as
an independent Gaussian error with a standard deviation s_i implied by the data:

- formulation ``spec`` (r_f,i = sqrt(alpha w_f,i) (f_a,i - f_e,i) / f_e,i): exactly
  s_i = sqrt(alpha w_f,i) sigma_f,i / f_e,i, sigma_f,i = ``frequency_std_hz`` of the data;
  the MAC rows r_s,i = sqrt(beta w_s,i) (1 - sqrt MAC_i) / sqrt MAC_i are not Gaussian in
  shape noise; they are taken as Gaussian with s = sqrt(beta w_s,i) (n_dof - 1) s_rel^2 / 2,
  the size of the MAC term that shape noise of relative std s_rel gives (an assumption, always
  named in ``noise_assumed``);
- formulation ``gaussian`` (:mod:`framework.diagnosis.likelihood`): residuals are already
  whitened by the data's standard deviations, s_i = 1;
- any other formulation: s_i = 1 (residuals taken as standard normal; named as assumed).

Where the data give no standard deviation, sigma_f = 0.5 % f_e and s_rel = 0.02 (this
module's defaults; the diagnosis's noise test assumes a more conservative 1 % and 5 %, see
:mod:`framework.diagnosis.likelihood`); every default used is written in the
``noise_assumed`` text, "" when all standard deviations come from the data. Penalty rows
(ratio constraints, Tikhonov) are not data and are left out of the likelihood.

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

from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from framework.core.errors import InputError
from framework.core.parameters import ParameterSet

DEFAULT_FREQUENCY_STD_REL = 0.005
DEFAULT_SHAPE_STD_REL = 0.02
LN_2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class NoiseModel:
    """Standard deviation of each modal residual, s (m_r,), and the assumption made ("" if none).

    n_data: number of data (frequencies + independent shape components) for chi2 / dof;
    data_std: standard deviation of each residual's datum in the data's units (normalization)."""

    scales: np.ndarray
    assumed: str
    n_data: int
    data_std: np.ndarray | None = None

    @property
    def log_norm(self) -> float:
        std = self.scales if self.data_std is None else self.data_std
        return float(-np.sum(np.log(std)) - 0.5 * std.size * LN_2PI)

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


def noise_model(problem, frequency_std_rel: float = DEFAULT_FREQUENCY_STD_REL,
                shape_std_rel: float = DEFAULT_SHAPE_STD_REL) -> NoiseModel:
    """The residual standard deviations of ``problem`` (module docstring)."""
    measured, spec = problem.measured, problem.spec
    m, n_res = measured.n_modes, problem.n_modal_residuals
    assumed: list[str] = []
    f_std = measured.frequency_std_hz
    if f_std is None or np.any(f_std <= 0):
        f_std = frequency_std_rel * measured.frequencies_hz
        assumed.append(f"frequency std {100 * frequency_std_rel:g} % of f")
    name = spec.formulation
    shape_rows = n_res > m
    if name == "spec":
        scales = np.sqrt(spec.alpha * measured.w_frequency) * f_std / measured.frequencies_hz
        if shape_rows:
            n_dof = len(measured.dofs)
            if measured.shape_std is not None and np.all(measured.shape_std >= 0):
                peak = np.max(np.abs(measured.shapes), axis=0)
                s_rel = np.sqrt(np.mean((measured.shape_std / peak) ** 2, axis=0))
                what = "shape_std of the data"
            else:
                s_rel = np.full(m, shape_std_rel)
                what = f"shape std {100 * shape_std_rel:g} % of the peak"
            s_mac = np.sqrt(spec.beta * measured.w_shape) * max(n_dof - 1, 1) * s_rel**2 / 2.0
            scales = np.r_[scales, s_mac]
            data_std = np.r_[f_std, s_mac]
            assumed.append(f"MAC residual Gaussian with std (n_dof-1) s^2/2 ({what})")
        else:
            data_std = np.asarray(f_std, float)
        if np.any(scales <= 0):
            raise InputError("likelihood: a residual has zero weight (alpha, beta or a mode weight is 0); "
                             "its standard deviation would be 0")
    elif name == "gaussian":
        scales = np.ones(n_res)
        data_std = np.asarray(f_std, float)
        if shape_rows:
            s_std = measured.shape_std
            if s_std is None:
                s_std = DEFAULT_SHAPE_STD_REL * np.max(np.abs(measured.shapes), axis=0) * np.ones_like(measured.shapes)
            data_std = np.r_[data_std, np.asarray(s_std, float).T.ravel()]
        if measured.frequency_std_hz is None:
            assumed[:] = ["frequency std 0.5 % of f (gaussian formulation)"]
        if shape_rows and measured.shape_std is None:
            assumed.append("shape std 2 % of the peak (gaussian formulation)")
    else:
        scales = np.ones(n_res)
        data_std = scales
        assumed = [f"residuals of formulation {name!r} taken as standard normal"]
    if name == "gaussian" and shape_rows:
        n_data = m * len(measured.dofs)  # m frequencies + m (n_dof - 1) shape components
    else:
        n_data = n_res
    return NoiseModel(np.asarray(scales, float), "; ".join(assumed), int(n_data), np.asarray(data_std, float))


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
    (the Gaussian formulation's population in one call, :mod:`framework.inference.batch`)."""

    def log_prob(X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, float))
        inside = np.all((X >= 0.0) & (X <= 1.0), axis=1)
        out = np.full(len(X), -np.inf)
        if inside.any():
            from framework.inference.batch import log_likelihood_batch

            theta = problem.parameters.to_physical(X[inside])
            out[inside] = log_likelihood_batch(problem, noise, X[inside], runner) + prior.log_pdf(theta)
        return out

    return log_prob
