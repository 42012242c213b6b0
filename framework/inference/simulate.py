"""Simulated data for coverage studies: truth drawn from the prior, data drawn exactly as the
likelihood assumes.

From the run's generator, in this order: theta_0 ~ prior; the model's lowest m modes at
theta_0 (m and the DOFs of a template data set); f_e,j = f_j + sigma_f,j N(0, 1) with
sigma_f,j = frequency_std_rel f_j; shapes scaled to a largest component of +1, then
phi_e = phi + shape_std_rel N(0, 1) per component. The data carry these standard
deviations (``frequency_std_hz``, ``shape_std``), so the likelihood uses exactly the noise
that made them, and the truth in ``meta["truth"]``.
"""

from __future__ import annotations

import numpy as np

from framework.measured.modes import MeasuredModes


def simulate(model, parameters, template: MeasuredModes, prior, rng: np.random.Generator,
             frequency_std_rel: float, shape_std_rel: float) -> tuple[np.ndarray, MeasuredModes]:
    """(theta_0 (k,), simulated MeasuredModes) (module docstring)."""
    theta0 = prior.sample(rng, 1)[0]
    values = {p.name: p.initial for p in model.parameters}
    values.update(parameters.as_dict(theta0))
    result = model.modal(values)
    m = template.n_modes
    f = np.asarray(result.frequencies_hz[:m], float)
    f_std = frequency_std_rel * f
    f_e = f + f_std * rng.standard_normal(m)
    shapes = s_std = None
    if template.has_shapes:
        phi = np.asarray(result.at(template.dofs)[:, :m], float)
        peak = phi[np.argmax(np.abs(phi), axis=0), np.arange(m)]
        phi = phi / peak
        s_std = np.full(phi.shape, shape_std_rel)
        shapes = phi + s_std * rng.standard_normal(phi.shape)
    measured = MeasuredModes(f_e, template.dofs, shapes, labels=tuple(f"mode {j + 1}" for j in range(m)),
                             frequency_std_hz=f_std, shape_std=s_std, name=f"{template.name}_simulated",
                             source=f"simulated from {template.source}",
                             meta={"truth": parameters.as_dict(theta0)})
    return theta0, measured
