"""Subspace identification over a range of model orders: poles, damping, complex shapes.

Two estimators of the extended observability matrix O_s = [C; CA; ...; CA^(s-1)]:

* input-output (:func:`n4sid_poles`): PO-MOESP, the N4SID-family method with past inputs
  and outputs as instrumental variables (Verhaegen & Verdult 2007, ch. 9). The block
  Hankel data matrix Z = [U_f; U_p; Y_p; Y_f] is triangularised, Z^T = Q R (L = R^T); the
  column space of L_32 (future outputs on the instruments) is that of O_s.
* output-only (:func:`ssi_cov_poles`): covariance-driven SSI. Output correlations
  R_k = E[y_(t+k) y_t^T] fill the block Toeplitz matrix T = [R_(s+a-b)]_(a,b) = O_s G_s.

For every order n: O_n = U_n S_n^(1/2) from the SVD, C = first block row, A by the shift
invariance O_n[l:] = O_n[:-l] A (least squares). Modal properties from the discrete
eigenvalues mu of A: lambda_c = ln(mu) fs, f = |lambda_c| / 2 pi,
zeta = -Re(lambda_c) / |lambda_c|, shapes C psi (complex).

Why our own code: the ``nfoursid`` package implements the same PO-MOESP projection but
recomputes, for every model order, a full SVD of an (s l x N) matrix with the N x N right
factor (memory O(N^2): 45 GB for a 391 s bridge record at 200 Hz), so it cannot run a
stability sweep over 10-80 orders on test-length records. It is used only as a
cross-check in the tests (:func:`nfoursid_poles`, needs the "ident" extra).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from framework.core.errors import InputError, MissingDependencyError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Poles:
    """Poles of a stability sweep: ``table`` (order, frequency_hz, damping_ratio) and the
    complex ``shapes`` (n_rows, n_out) aligned with the table rows."""

    table: pd.DataFrame
    shapes: np.ndarray
    output_labels: tuple[str, ...]
    method: str

    @property
    def orders(self) -> list[int]:
        return sorted(self.table["order"].unique().tolist())


def modes_from_state_space(a: np.ndarray, c: np.ndarray, sampling_hz: float):
    """(f_hz, zeta, complex shapes (n_out, k)) of the oscillatory poles of a discrete A.

    lambda_c = ln(mu) fs; one pole of each complex-conjugate pair (Im > 0) is kept.
    """
    mu, psi = np.linalg.eig(a)
    ok = np.abs(mu) > 1e-12
    lam = np.log(mu[ok].astype(complex)) * sampling_hz
    psi = psi[:, ok]
    keep = lam.imag > 1e-9
    lam, psi = lam[keep], psi[:, keep]
    f = np.abs(lam) / (2 * math.pi)
    zeta = -lam.real / np.abs(lam)
    order = np.argsort(f)
    return f[order], zeta[order], (c @ psi)[:, order]


def _block_hankel(x: np.ndarray, start: int, rows: int, cols: int) -> np.ndarray:
    """Block Hankel matrix with blocks x[start + i + j] (rows i, columns j), shape (rows*ch, cols)."""
    n_ch = x.shape[1]
    out = np.empty((rows * n_ch, cols))
    for i in range(rows):
        out[i * n_ch : (i + 1) * n_ch] = x[start + i : start + i + cols].T
    return out


def _poles_from_observability(u_o, s_o, n_out, orders, sampling_hz, labels, method) -> Poles:
    rows, shapes = [], []
    for n in orders:
        if n > u_o.shape[1] or n > u_o.shape[0] - n_out:
            raise InputError(
                f"{method}: model order {n} exceeds what the block rows allow ({u_o.shape[0] - n_out}); "
                f"increase block_rows"
            )
        obs = u_o[:, :n] * np.sqrt(s_o[:n])
        c = obs[:n_out]
        a = np.linalg.lstsq(obs[:-n_out], obs[n_out:], rcond=None)[0]
        f, z, phi = modes_from_state_space(a, c, sampling_hz)
        for k in range(f.size):
            rows.append((n, k, f[k], z[k]))
        shapes.append(phi.T)
    table = pd.DataFrame(rows, columns=["order", "pole", "frequency_hz", "damping_ratio"])
    shp = np.concatenate(shapes, axis=0) if shapes else np.zeros((0, n_out), complex)
    return Poles(table, shp, tuple(labels), method)


def _check(y: np.ndarray, block_rows: int, orders: Sequence[int], where: str) -> np.ndarray:
    y = np.asarray(y, float)
    if y.ndim != 2:
        raise InputError(f"{where}: outputs must be (n_samples, n_channels), got shape {y.shape}")
    if block_rows < 2:
        raise InputError(f"{where}: block_rows must be >= 2, got {block_rows!r}")
    if not orders or min(orders) < 1:
        raise InputError(f"{where}: orders must be positive integers, got {list(orders)!r}")
    if y.shape[0] < 4 * block_rows + 10:
        raise InputError(f"{where}: {y.shape[0]} samples are too few for block_rows={block_rows}")
    return y


def n4sid_poles(
    inputs: np.ndarray,
    outputs: np.ndarray,
    sampling_hz: float,
    orders: Sequence[int],
    block_rows: int,
    output_labels: Sequence[str] | None = None,
) -> Poles:
    """Input-output subspace identification (PO-MOESP) for each model order in ``orders``."""
    y = _check(outputs, block_rows, orders, "n4sid")
    u = np.asarray(inputs, float).reshape(len(y), -1)
    s, n_out, n_in = block_rows, y.shape[1], u.shape[1]
    cols = y.shape[0] - 2 * s + 1
    z = np.vstack(
        [
            _block_hankel(u, s, s, cols),  # U_f
            _block_hankel(u, 0, s, cols),  # U_p
            _block_hankel(y, 0, s, cols),  # Y_p
            _block_hankel(y, s, s, cols),  # Y_f
        ]
    )
    r = np.linalg.qr(z.T, mode="r")
    low = r.T
    a0, a1 = s * n_in, 2 * s * n_in + s * n_out
    l32 = low[a1:, a0:a1]
    u_o, s_o, _ = np.linalg.svd(l32, full_matrices=False)
    labels = output_labels or [f"out{i + 1}" for i in range(n_out)]
    log.debug("n4sid: %d samples, %d block rows, singular values %s", y.shape[0], s, s_o[:6])
    return _poles_from_observability(u_o, s_o, n_out, orders, sampling_hz, labels, "n4sid")


def output_correlations(y: np.ndarray, max_lag: int, biased: bool = False) -> np.ndarray:
    """R_k = 1/(N-k) sum_t y_(t+k) y_t^T for k = 0..max_lag, shape (max_lag+1, l, l).

    ``biased`` divides by N instead: right for free decays (snap-back), whose energy sits
    at the start of the record, where 1/(N-k) would inflate the late lags and so lower the
    apparent damping.
    """
    n = y.shape[0]
    return np.stack([y[k:].T @ y[: n - k] / (n if biased else n - k) for k in range(max_lag + 1)])


def ssi_cov_poles(
    outputs: np.ndarray,
    sampling_hz: float,
    orders: Sequence[int],
    block_rows: int,
    output_labels: Sequence[str] | None = None,
    biased: bool = False,
) -> Poles:
    """Output-only covariance-driven SSI for each model order in ``orders``
    (``biased`` correlations for free-decay records, see :func:`output_correlations`)."""
    y = _check(outputs, block_rows, orders, "ssi_cov")
    y = y - y.mean(axis=0)
    s, n_out = block_rows, y.shape[1]
    r = output_correlations(y, 2 * s, biased)
    t = np.empty((s * n_out, s * n_out))
    for a in range(s):
        for b in range(s):
            t[a * n_out : (a + 1) * n_out, b * n_out : (b + 1) * n_out] = r[s + a - b]
    u_o, s_o, _ = np.linalg.svd(t)
    labels = output_labels or [f"out{i + 1}" for i in range(n_out)]
    return _poles_from_observability(u_o, s_o, n_out, orders, sampling_hz, labels, "ssi_cov")


def nfoursid_poles(
    inputs: np.ndarray,
    outputs: np.ndarray,
    sampling_hz: float,
    orders: Sequence[int],
    block_rows: int,
) -> Poles:
    """The same sweep with the ``nfoursid`` package (short records only: memory O(N^2))."""
    try:
        from nfoursid.nfoursid import NFourSID
    except ImportError as exc:
        raise MissingDependencyError(
            "nfoursid is not installed; install the optional extra: pip install 'gomu[ident]'"
        ) from exc
    u = np.asarray(inputs, float).reshape(len(outputs), -1)
    y = np.asarray(outputs, float)
    df = pd.DataFrame(
        np.column_stack([u, y]),
        columns=[f"u{i}" for i in range(u.shape[1])] + [f"y{i}" for i in range(y.shape[1])],
    )
    model = NFourSID(
        df,
        output_columns=[f"y{i}" for i in range(y.shape[1])],
        input_columns=[f"u{i}" for i in range(u.shape[1])],
        num_block_rows=block_rows,
    )
    model.subspace_identification()
    rows, shapes = [], []
    for n in orders:
        ss, _ = model.system_identification(rank=n)
        f, z, phi = modes_from_state_space(ss.a, ss.c, sampling_hz)
        rows += [(n, k, f[k], z[k]) for k in range(f.size)]
        shapes.append(phi.T)
    table = pd.DataFrame(rows, columns=["order", "pole", "frequency_hz", "damping_ratio"])
    return Poles(table, np.concatenate(shapes), tuple(f"y{i}" for i in range(y.shape[1])), "nfoursid")


def pyoma2_ssi_poles(
    outputs: np.ndarray,
    sampling_hz: float,
    orders: Sequence[int],
    block_rows: int,
    output_labels: Sequence[str] | None = None,
) -> Poles:
    """Covariance SSI with pyOMA2's ``build_hank(..., "cov")`` and ``SSI_fast`` (the "ident"
    extra), poles extracted as in :func:`ssi_cov_poles`: an independent check of our code."""
    try:
        from pyoma2.functions import ssi
    except ImportError as exc:
        raise MissingDependencyError(
            "pyOMA2 is not installed; install the optional extra: pip install 'gomu[ident]'"
        ) from exc
    y = _check(outputs, block_rows, orders, "pyoma2_ssi")
    y = (y - y.mean(axis=0)).T
    hank, _ = ssi.build_hank(y, y, block_rows, "cov")
    _, a_list, c_list, _ = ssi.SSI_fast(hank, block_rows, max(orders))
    rows, shapes = [], []
    for n in orders:
        f, z, phi = modes_from_state_space(a_list[n], c_list[n], sampling_hz)
        rows += [(n, k, f[k], z[k]) for k in range(f.size)]
        shapes.append(phi.T)
    table = pd.DataFrame(rows, columns=["order", "pole", "frequency_hz", "damping_ratio"])
    labels = output_labels or [f"out{i + 1}" for i in range(y.shape[0])]
    return Poles(table, np.concatenate(shapes), tuple(labels), "pyoma2_ssi")


def modal_phase_collinearity(phi: np.ndarray) -> float:
    """MPC = ((l1 - l2) / (l1 + l2))^2, l1 >= l2 the eigenvalues of the 2x2 covariance of
    [Re phi, Im phi]: 1 for a normal (real up to a rotation) mode, ~0 for a noise pole."""
    phi = np.asarray(phi, complex)
    re, im = phi.real, phi.imag
    c = np.array([[re @ re, re @ im], [re @ im, im @ im]])
    lam = np.linalg.eigvalsh(c)
    total = lam[0] + lam[1]
    return float(((lam[1] - lam[0]) / total) ** 2) if total > 0 else 0.0


def real_shape(phi: np.ndarray) -> np.ndarray:
    """Best real approximation of a complex shape, normalized to max |value| = 1 (largest positive).

    Rotates by alpha = arg(sum phi_k^2) / 2 (the principal direction of the points in the
    complex plane), then takes the real part.
    """
    phi = np.asarray(phi, complex)
    alpha = 0.5 * np.angle(np.sum(phi**2))
    v = np.real(phi * np.exp(-1j * alpha))
    k = int(np.argmax(np.abs(v)))
    return v / v[k] if v[k] != 0 else v
