"""Simulated measured modes: the one simulator of noisy identified modes, with two documented
noise kinds.

Shape normalisation (every kind): each model shape at the measured DOFs is first scaled so that
its largest-magnitude component is +1, so the stored numbers do not depend on the solver's
normalisation.

Noise kinds:

- :class:`Noise` (Gaussian; the diagnosis's simulated tests and the coverage study): from the
  generator, first one N(0, 1) draw per frequency, then one per shape component ((n_dof, m),
  row-major):

      f_e = f (1 + frequency_std_rel eps_f),   phi_e = phi + shape_std_rel eps_phi,

  and the data carry frequency_std_hz = frequency_std_rel f_e (relative to the measured value,
  as a vibration test reports it; it differs from the noise's sigma by a factor 1 + O(rel)) and
  shape_std = shape_std_rel (the normalised shapes' peak is 1), unless ``with_stds`` is false.
  Named levels :data:`NOISE_LEVELS`; ``very_high`` is the assumed default of
  :mod:`framework.inference.noise` (1 % / 5 %).
- :class:`UniformShapeNoise` (SPEC 7, the beam damage study): frequencies exact, shapes
  phi_e = phi (1 + a eps), eps ~ U[-1, 1], one draw (n_dof, m); the data carry no standard
  deviations (the source gives none).

Entry points: :func:`noisy_measurement` (modes in, MeasuredModes out; used by the diagnosis's
generator and the damage study) and :func:`simulate` (coverage studies: a truth drawn from the
prior, then a noisy measurement of its modes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from framework.core.errors import InputError
from framework.inference.noise import DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL
from framework.measured.modes import MeasuredModes


@dataclass(frozen=True)
class Noise:
    """Gaussian measurement noise: relative frequency std and shape std (of the largest component)."""

    frequency_std_rel: float = 0.002
    shape_std_rel: float = 0.01
    name: str = ""
    kind = "gaussian"

    def __post_init__(self) -> None:
        for k in ("frequency_std_rel", "shape_std_rel"):
            v = getattr(self, k)
            if isinstance(v, bool) or not (np.isfinite(v) and v > 0):
                raise InputError(f"noise.{k} must be > 0, got {v!r}")

    def apply(self, f: np.ndarray, phi: np.ndarray | None, rng: np.random.Generator):
        """(f_e, phi_e) from the generator (frequencies first, then shapes)."""
        f_e = f * (1.0 + self.frequency_std_rel * rng.standard_normal(f.size))
        phi_e = None if phi is None else phi + self.shape_std_rel * rng.standard_normal(phi.shape)
        return f_e, phi_e

    def stds(self, f_e: np.ndarray, phi_e: np.ndarray | None):
        """(frequency_std_hz, shape_std) the data carry."""
        return self.frequency_std_rel * f_e, None if phi_e is None else np.full(phi_e.shape, self.shape_std_rel)


#: named levels of simulated tests (relative frequency std, shape std of a peak-1 shape)
NOISE_LEVELS = {
    "low": Noise(0.002, 0.01, "low"),
    "high": Noise(0.005, 0.03, "high"),
    "very_high": Noise(DEFAULT_FREQUENCY_STD_REL, DEFAULT_SHAPE_STD_REL, "very_high"),
}


@dataclass(frozen=True)
class UniformShapeNoise:
    """SPEC 7 shape noise: phi (1 + amplitude eps), eps ~ U[-1, 1]; frequencies exact."""

    amplitude: float
    kind = "uniform_multiplicative"

    def __post_init__(self) -> None:
        a = self.amplitude
        if isinstance(a, bool) or not (np.isfinite(a) and a >= 0):
            raise InputError(f"shape noise amplitude (noise_fraction) must be a finite number >= 0, got {a!r}")

    def apply(self, f: np.ndarray, phi: np.ndarray | None, rng: np.random.Generator):
        phi_e = None if phi is None else phi * (1.0 + self.amplitude * rng.uniform(-1.0, 1.0, size=phi.shape))
        return np.array(f, float), phi_e

    def stds(self, f_e, phi_e):
        return None, None


def peak_normalized(phi: np.ndarray) -> np.ndarray:
    """Each column scaled so that its largest-magnitude component is +1."""
    phi = np.asarray(phi, float)
    return phi / phi[np.argmax(np.abs(phi), axis=0), np.arange(phi.shape[1])]


def noisy_measurement(frequencies_hz: np.ndarray, shapes: np.ndarray | None, dofs, noise,
                      rng: np.random.Generator, with_stds: bool = True, **fields) -> MeasuredModes:
    """MeasuredModes of model modes (frequencies (m,), shapes at ``dofs`` (n_dof, m) or None) with
    the noise ``noise`` (:class:`Noise` or :class:`UniformShapeNoise`) drawn from ``rng``, the
    shapes peak-normalised first; ``fields``: the other MeasuredModes fields (labels, name,
    source, meta)."""
    f = np.asarray(frequencies_hz, float)
    phi = None if shapes is None else peak_normalized(shapes)
    f_e, phi_e = noise.apply(f, phi, rng)
    f_std, s_std = noise.stds(f_e, phi_e) if with_stds else (None, None)
    return MeasuredModes(f_e, tuple(dofs), phi_e, frequency_std_hz=f_std, shape_std=s_std, **fields)


def simulate(model, parameters, template: MeasuredModes, prior, rng: np.random.Generator,
             noise: Noise) -> tuple[np.ndarray, MeasuredModes]:
    """(theta_0 (k,), simulated MeasuredModes) for coverage studies: from the run's generator,
    theta_0 ~ prior, then the model's lowest m modes at theta_0 (m and the DOFs of a template
    data set) measured with ``noise`` (:func:`noisy_measurement`); the truth in
    ``meta["truth"]``."""
    theta0 = prior.sample(rng, 1)[0]
    values = {p.name: p.initial for p in model.parameters}
    values.update(parameters.as_dict(theta0))
    result = model.modal(values)
    m = template.n_modes
    shapes = np.asarray(result.at(template.dofs)[:, :m], float) if template.has_shapes else None
    measured = noisy_measurement(result.frequencies_hz[:m], shapes, template.dofs, noise, rng,
                                 labels=tuple(f"mode {j + 1}" for j in range(m)), name=f"{template.name}_simulated",
                                 source=f"simulated from {template.source}", meta={"truth": parameters.as_dict(theta0)})
    return theta0, measured
