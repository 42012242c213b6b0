"""Whitened (Gaussian) residuals of measured modes given paired model modes: one definition
for one point and for a population (a point is a population of one).

Noise model (independent Gaussian errors, standard deviations from
:mod:`framework.inference.noise`):

- frequency of measured mode j:  f_e,j = f_j + e,  e ~ N(0, sigma_f,j^2);
- shape component k of mode j:   phi_e,kj = c_j phi_kj + e,  e ~ N(0, s_kj^2), with an
  unknown scale c_j per mode (the shapes' scaling is arbitrary).

Whitened residuals of a matched pair (a = model, e = measured, W = diag(1 / s^2)):

    r_f,j  = (f_a,j - f_e,j) / sigma_f,j
    r_s,kj = (c_j a_kj - e_kj) / s_kj,   c_j = a' W e / a' W a   (least-squares scale)

so that sum_k r_s,kj^2 = e'We - (a'We)^2 / (a'Wa), the weighted form of ||e||^2 (1 - MAC).
chi2 = sum r^2 and -2 ln L = chi2 + const. Each mode contributes 1 + (n_dof - 1) data (one
scale per mode is fitted).

Unmatched measured mode (no model mode paired with it): it costs what a pair at the matching
limit would cost,

    chi2_u,j = (window f_e,j / sigma_f,j)^2 + (1 - mac_threshold) e'We,

carried by r_f,j (its shape residuals are 0), so that leaving a mode unmatched is never
cheaper than matching it badly. The pairing itself belongs to the caller (the ``gaussian``
formulation of :mod:`framework.updating.formulations`).
"""

from __future__ import annotations

import numpy as np

#: relative frequency distance that an unmatched mode is charged (module docstring)
DEFAULT_UNMATCHED_WINDOW = 0.1


def unmatched_chi2(f_e: np.ndarray, sigma_f: np.ndarray, window: float, shapes: np.ndarray | None = None,
                   shape_std: np.ndarray | None = None, mac_threshold: float = 0.5) -> np.ndarray:
    """chi2_u,j (m,) charged for each measured mode when it is unmatched (module docstring)."""
    out = (window * f_e / sigma_f) ** 2
    if shapes is not None:
        out = out + (1.0 - mac_threshold) * np.sum((shapes / shape_std) ** 2, axis=0)
    return out


def whitened_residuals(f_model: np.ndarray, matched: np.ndarray, f_e: np.ndarray, sigma_f: np.ndarray,
                       chi2_unmatched: np.ndarray, a: np.ndarray | None = None, e: np.ndarray | None = None,
                       s: np.ndarray | None = None) -> np.ndarray:
    """Whitened residuals (n, m [+ m n_dof]) of n points.

    f_model (n, m): the model frequency paired with each measured mode (any value where
    unmatched); matched (n, m); f_e, sigma_f (m,); chi2_unmatched (m,); a (n, n_dof, m): the
    paired model shapes at the measured DOFs (any value where unmatched), e and s (n_dof, m):
    measured shapes and their standard deviations; without shapes only the frequency part.
    The layout is [r_f (m), mode 1's n_dof shape residuals, mode 2's, ...]."""
    matched = np.asarray(matched, bool)
    r_f = np.where(matched, np.nan_to_num(f_model - f_e) / sigma_f, np.sqrt(chi2_unmatched)[None, :])
    if a is None:
        return r_f
    n = len(f_model)
    w = 1.0 / s**2
    awa = np.sum(a * a * w, axis=1)
    c = np.where(awa > 0, np.sum(a * e * w, axis=1) / np.where(awa > 0, awa, 1.0), 0.0)
    r_s = (c[:, None, :] * a - e) / s
    r_s = np.where(matched[:, None, :], r_s, 0.0)
    return np.concatenate([r_f, np.swapaxes(r_s, 1, 2).reshape(n, -1)], axis=1)


def n_data(n_modes: int, n_dofs: int, shapes: bool) -> int:
    """Independent data of the whitened residuals: m frequencies + m (n_dof - 1) shape components."""
    return n_modes + (n_modes * (n_dofs - 1) if shapes else 0)


def n_residuals(n_modes: int, n_dofs: int, shapes: bool) -> int:
    return n_modes + (n_modes * n_dofs if shapes else 0)


def split_chi2(residuals: np.ndarray, n_modes: int) -> np.ndarray:
    """[chi2_frequency, chi2_shape] of residual rows (..., r) (shape part 0 without shapes)."""
    r2 = np.asarray(residuals) ** 2
    f = r2[..., :n_modes].sum(-1)
    s = r2[..., n_modes:].sum(-1)
    return np.stack([f, s], axis=-1)


def per_mode_chi2(residuals: np.ndarray, n_modes: int, n_dofs: int, shapes: bool) -> tuple[np.ndarray, np.ndarray]:
    """chi2 per measured mode of one residual vector: (frequency part (m,), shape part (m,))."""
    r = np.asarray(residuals)
    f = r[:n_modes] ** 2
    if not shapes:
        return f, np.zeros(n_modes)
    s = (r[n_modes : n_modes + n_modes * n_dofs] ** 2).reshape(n_modes, n_dofs).sum(axis=1)
    return f, s
