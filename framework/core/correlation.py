"""Correlation of analytical (a) and experimental (e) modes: pure numpy functions.

Shapes are column vectors: an array (n_dof, m) holds m modes. Complex shapes are
accepted (conjugate transposes are used), so the same functions serve identified modes.

- relative frequency error   eps_j = (f_a,j - f_e,j) / f_e,j
- modal scale factor         MSF_j = (phi_e,j^H phi_a,j) / (phi_e,j^H phi_e,j)
- modal assurance criterion  MAC(a, e) = |phi_e^H phi_a|^2 / ((phi_e^H phi_e)(phi_a^H phi_a))
- COMAC of DOF k over m paired modes
      COMAC_k = (sum_r |phi_a,kr phi_e,kr|)^2 / (sum_r |phi_a,kr|^2 sum_r |phi_e,kr|^2)
- pairing: each measured mode gets the analytical mode of highest MAC (one-to-one,
  optionally within a relative frequency window); a measured mode whose best partner has
  MAC below a threshold is *unmatched* and reported as such.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment


def _as_modes(phi, name: str) -> np.ndarray:
    arr = np.asarray(phi)
    if arr.dtype == object or not np.issubdtype(arr.dtype, np.number):
        raise ValueError(f"{name}: mode shapes must be numeric, got dtype {arr.dtype}")
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise ValueError(f"{name}: expected a vector or an (n_dof, n_modes) array, got shape {arr.shape}")
    if arr.shape[0] == 0 or arr.shape[1] == 0:
        raise ValueError(f"{name}: empty mode-shape array of shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name}: mode shapes contain NaN or inf")
    return arr


def _norms2(phi: np.ndarray, name: str) -> np.ndarray:
    n2 = np.sum(np.abs(phi) ** 2, axis=0)
    zero = np.flatnonzero(n2 == 0)
    if zero.size:
        raise ValueError(f"{name}: mode {int(zero[0]) + 1} has zero norm; MAC is undefined")
    return n2


def frequency_errors(f_analytical, f_measured) -> np.ndarray:
    """eps = (f_a - f_e) / f_e, element-wise."""
    fa = np.asarray(f_analytical, dtype=float)
    fe = np.asarray(f_measured, dtype=float)
    if fa.shape != fe.shape:
        raise ValueError(f"frequency arrays differ in shape: {fa.shape} vs {fe.shape}")
    if np.any(fe <= 0) or not np.all(np.isfinite(fe)):
        raise ValueError(f"measured frequencies must be finite and > 0, got {fe.tolist()}")
    return (fa - fe) / fe


def mac_matrix(phi_a, phi_e) -> np.ndarray:
    """MAC of every measured mode (rows) with every analytical mode (columns)."""
    a = _as_modes(phi_a, "phi_a")
    e = _as_modes(phi_e, "phi_e")
    if a.shape[0] != e.shape[0]:
        raise ValueError(f"phi_a has {a.shape[0]} DOFs but phi_e has {e.shape[0]}")
    cross = np.abs(e.conj().T @ a) ** 2
    return np.clip(cross / np.outer(_norms2(e, "phi_e"), _norms2(a, "phi_a")), 0.0, 1.0)


def mac(phi_a, phi_e) -> float:
    """MAC of two single mode shapes."""
    a = _as_modes(phi_a, "phi_a")
    e = _as_modes(phi_e, "phi_e")
    if a.shape[1] != 1 or e.shape[1] != 1:
        raise ValueError("mac() takes two vectors; use mac_matrix() for several modes")
    return float(mac_matrix(a, e)[0, 0])


def mac_paired(phi_a, phi_e) -> np.ndarray:
    """MAC of column j of phi_a with column j of phi_e."""
    a = _as_modes(phi_a, "phi_a")
    e = _as_modes(phi_e, "phi_e")
    if a.shape != e.shape:
        raise ValueError(f"paired shapes differ: {a.shape} vs {e.shape}")
    cross = np.abs(np.sum(e.conj() * a, axis=0)) ** 2
    return np.clip(cross / (_norms2(e, "phi_e") * _norms2(a, "phi_a")), 0.0, 1.0)


def msf(phi_a, phi_e) -> np.ndarray:
    """MSF_j = (phi_e,j^H phi_a,j) / (phi_e,j^H phi_e,j), for paired columns."""
    a = _as_modes(phi_a, "phi_a")
    e = _as_modes(phi_e, "phi_e")
    if a.shape != e.shape:
        raise ValueError(f"paired shapes differ: {a.shape} vs {e.shape}")
    out = np.sum(e.conj() * a, axis=0) / _norms2(e, "phi_e")
    return out if np.iscomplexobj(out) else out.real


def comac(phi_a, phi_e) -> np.ndarray:
    """COMAC per DOF over paired columns (phi_a[:, r] paired with phi_e[:, r])."""
    a = _as_modes(phi_a, "phi_a")
    e = _as_modes(phi_e, "phi_e")
    if a.shape != e.shape:
        raise ValueError(f"paired shapes differ: {a.shape} vs {e.shape}")
    num = np.sum(np.abs(a * e), axis=1) ** 2
    den = np.sum(np.abs(a) ** 2, axis=1) * np.sum(np.abs(e) ** 2, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)


@dataclass(frozen=True)
class Pairing:
    """Result of pairing measured modes with analytical ones.

    analytical_index[j]: index of the analytical mode paired with measured mode j, or -1
    when unmatched; best_index[j]: best candidate even when unmatched; mac[j]: MAC of the
    pair (of the best candidate when unmatched); matched[j]: MAC >= threshold.
    """

    analytical_index: np.ndarray
    best_index: np.ndarray
    mac: np.ndarray
    matched: np.ndarray
    mac_matrix: np.ndarray | None

    @property
    def unmatched(self) -> np.ndarray:
        return np.flatnonzero(~self.matched)


def pair_modes(
    f_a,
    f_e,
    phi_a=None,
    phi_e=None,
    *,
    mac_threshold: float = 0.5,
    frequency_window: float | None = None,
    method: str = "mac",
) -> Pairing:
    """Pair measured modes with analytical modes.

    method "mac": one-to-one assignment maximizing the summed MAC (Hungarian algorithm)
    among candidates within ``frequency_window`` (relative, e.g. 0.3 = +-30 %); pairs
    below ``mac_threshold`` or outside the window are unmatched. method "order": measured mode j with analytical
    mode j. method "frequency": nearest frequency, one-to-one. Without shapes only
    "order" and "frequency" are possible, and every pair counts as matched.
    """
    fa = np.asarray(f_a, dtype=float)
    fe = np.asarray(f_e, dtype=float)
    m_e, m_a = fe.size, fa.size
    if method not in ("mac", "order", "frequency"):
        raise ValueError(f"pairing method must be 'mac', 'order' or 'frequency', got {method!r}")
    mm = None
    if phi_a is not None and phi_e is not None:
        mm = mac_matrix(phi_a, phi_e)
        if mm.shape != (m_e, m_a):
            raise ValueError(f"MAC matrix {mm.shape} does not match {m_e} measured / {m_a} analytical modes")
    elif method == "mac":
        method = "frequency"
    if method == "order":
        if m_a < m_e:
            idx = np.r_[np.arange(m_a), -np.ones(m_e - m_a, dtype=int)]
        else:
            idx = np.arange(m_e)
        best = idx.copy()
    else:
        if method == "mac":
            score = mm.copy()
        else:
            score = -np.abs(fa[None, :] - fe[:, None]) / fe[:, None]
        if frequency_window is not None:
            far = np.abs(fa[None, :] - fe[:, None]) / fe[:, None] > frequency_window
            score = np.where(far, -np.inf if method == "frequency" else -1.0, score)
        finite = np.where(np.isfinite(score), score, -1e9)
        rows, cols = linear_sum_assignment(finite, maximize=True)
        idx = -np.ones(m_e, dtype=int)
        idx[rows] = cols
        best = idx.copy()
    mac_pair = np.full(m_e, np.nan)
    valid = idx >= 0
    if mm is not None:
        mac_pair[valid] = mm[np.flatnonzero(valid), idx[valid]]
        matched = valid & (mac_pair >= mac_threshold)
    else:
        matched = valid.copy()
    if method != "order" and frequency_window is not None:
        inside = np.zeros(m_e, dtype=bool)
        inside[valid] = np.abs(fa[idx[valid]] - fe[valid]) / fe[valid] <= frequency_window
        matched &= inside
    final = np.where(matched, idx, -1)
    return Pairing(final, best, mac_pair, matched, mm)


def mac_matrix_batch(phi_a: np.ndarray, phi_e: np.ndarray) -> np.ndarray:
    """MAC matrices of a population: phi_a (n, n_dof, m_a), phi_e (n_dof, m_e) -> (n, m_e, m_a).

    Zero-norm analytical modes get MAC 0 (they can never be matched)."""
    cross = np.abs(np.einsum("dk,ndj->nkj", phi_e.conj(), phi_a)) ** 2
    ne = np.sum(np.abs(phi_e) ** 2, axis=0)
    na = np.sum(np.abs(phi_a) ** 2, axis=1)
    den = ne[None, :, None] * na[:, None, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.clip(np.where(den > 0, cross / np.where(den > 0, den, 1.0), 0.0), 0.0, 1.0)


_MAX_ASSIGNMENTS = 5040


def assignments(m_e: int, m_a: int) -> np.ndarray | None:
    """All one-to-one maps of m_e measured to m_a analytical modes (rows), or None if too many."""
    import itertools
    import math

    if m_e > m_a or math.perm(m_a, m_e) > _MAX_ASSIGNMENTS:
        return None
    return np.array(list(itertools.permutations(range(m_a), m_e)), dtype=int).reshape(-1, m_e)


def pair_modes_batch(f_a: np.ndarray, f_e: np.ndarray, mm: np.ndarray | None, *, mac_threshold: float = 0.5,
                     frequency_window: float | None = None, method: str = "mac"):
    """Vectorized :func:`pair_modes` for a population; f_a (n, m_a), mm (n, m_e, m_a) or None.

    Enumerates every one-to-one assignment (exact, like the Hungarian algorithm) and keeps
    the one of largest total score. Returns (index (n, m_e) with -1 unmatched, mac (n, m_e),
    matched (n, m_e)), or None when the sizes are too large for enumeration.
    """
    n, m_a = f_a.shape
    m_e = f_e.size
    if method == "mac" and mm is None:
        method = "frequency"
    if method == "order":
        if m_a < m_e:
            return None
        idx = np.tile(np.arange(m_e), (n, 1))
    else:
        P = assignments(m_e, m_a)
        if P is None:
            return None
        rel = np.abs(f_a[:, None, :] - f_e[None, :, None]) / f_e[None, :, None]  # (n, m_e, m_a)
        if method == "mac":
            score = mm.copy()
            if frequency_window is not None:
                score = np.where(rel > frequency_window, -1.0, score)
        else:
            score = -rel
            if frequency_window is not None:
                score = np.where(rel > frequency_window, -1e9, score)
        total = score[:, np.arange(m_e)[None, :], P].sum(axis=2)  # (n, n_assignments)
        idx = P[np.argmax(total, axis=1)]
    rows = np.arange(n)[:, None]
    cols = np.arange(m_e)[None, :]
    if mm is None:
        mac = np.full((n, m_e), np.nan)
        matched = np.ones((n, m_e), dtype=bool)
    else:
        mac = mm[rows, cols, idx]
        matched = mac >= mac_threshold
    if method != "order" and frequency_window is not None:
        matched &= np.abs(f_a[rows, idx] - f_e[None, :]) / f_e[None, :] <= frequency_window
    return np.where(matched, idx, -1), mac, matched
