"""Modal-superposition simulator of vibration tests (exact zero-order-hold discretization).

A :class:`ModalSystem` is a set of classically damped modes seen through inputs and outputs:

    q_r'' + 2 zeta_r omega_r q_r' + omega_r^2 q_r = gamma_r . u(t)          (r = 1..m)
    y = Phi_out q''  + D u     (quantity "acceleration": D is the rigid-body feedthrough,
                                e.g. the table acceleration seen by an absolute accelerometer)
    y = Phi_out q              (quantity "displacement")

gamma (m, n_in) is the modal force per unit input: Phi_f^T F for forces F (n_dof, n_in)
applied at DOFs, or -Phi^T M r for a base acceleration along the influence vector r, with
mass-normalized shapes Phi. The same class therefore serves a structure given by M and K
(:meth:`ModalSystem.from_matrices`, lab frame) and one given only by modal data
(frequencies, damping, mass-normalized shapes at input and output DOFs; bridge).

Each mode is discretized exactly for a piecewise-constant input (ZOH, matrix exponential of
the augmented 3x3 system) and filtered with ``scipy.signal.lfilter``; free vibration from
initial modal displacements/velocities (snap-back) is added in closed form.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.signal

from framework.core.errors import InputError


@dataclass(frozen=True)
class ModalSystem:
    """Modes (frequencies_hz, damping_ratio) with input participation and output shapes.

    gamma: (m, n_in) modal force per unit input; output_shapes: (n_out, m);
    feedthrough: (n_out, n_in) added to accelerations (None = zero).
    """

    frequencies_hz: np.ndarray
    damping_ratio: np.ndarray
    gamma: np.ndarray
    output_shapes: np.ndarray
    output_labels: tuple[str, ...]
    input_labels: tuple[str, ...]
    quantity: str = "acceleration"
    feedthrough: np.ndarray | None = None

    def __post_init__(self) -> None:
        f = np.atleast_1d(np.asarray(self.frequencies_hz, float))
        z = np.broadcast_to(np.asarray(self.damping_ratio, float), f.shape).copy()
        if np.any(f <= 0):
            raise InputError(f"ModalSystem: frequencies_hz must be > 0, got {f.tolist()}")
        if np.any((z < 0) | (z >= 1)):
            raise InputError(f"ModalSystem: damping_ratio must be in [0, 1), got {z.tolist()}")
        g = np.asarray(self.gamma, float).reshape(f.size, -1)
        phi = np.asarray(self.output_shapes, float)
        if phi.shape != (len(self.output_labels), f.size):
            raise InputError(
                f"ModalSystem: output_shapes has shape {phi.shape}, expected "
                f"({len(self.output_labels)} outputs, {f.size} modes)"
            )
        if g.shape[1] != len(self.input_labels):
            raise InputError(f"ModalSystem: gamma has {g.shape[1]} input columns for {len(self.input_labels)} labels")
        if self.quantity not in ("acceleration", "displacement"):
            raise InputError(f"ModalSystem: quantity must be 'acceleration' or 'displacement', got {self.quantity!r}")
        d = np.zeros((phi.shape[0], g.shape[1])) if self.feedthrough is None else np.asarray(self.feedthrough, float)
        if d.shape != (phi.shape[0], g.shape[1]):
            raise InputError(f"ModalSystem: feedthrough has shape {d.shape}, expected {(phi.shape[0], g.shape[1])}")
        for name, value in (
            ("frequencies_hz", f),
            ("damping_ratio", z),
            ("gamma", g),
            ("output_shapes", phi),
        ):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "feedthrough", d)
        object.__setattr__(self, "output_labels", tuple(self.output_labels))
        object.__setattr__(self, "input_labels", tuple(self.input_labels))

    @property
    def n_modes(self) -> int:
        return int(self.frequencies_hz.size)

    @classmethod
    def from_matrices(
        cls,
        mass: np.ndarray,
        stiffness: np.ndarray,
        damping_ratio: Sequence[float] | float,
        input_forces: np.ndarray,
        output_matrix: np.ndarray,
        output_labels: Sequence[str],
        input_labels: Sequence[str],
        quantity: str = "acceleration",
        feedthrough: np.ndarray | None = None,
    ) -> ModalSystem:
        """Modes of K phi = omega^2 M phi (mass-normalized); gamma = Phi^T F, shapes = C_out Phi."""
        w2, phi = scipy.linalg.eigh(np.asarray(stiffness, float), np.asarray(mass, float))
        if np.any(w2 <= 0):
            raise InputError(f"ModalSystem.from_matrices: K is not positive definite (eigenvalue {w2.min():.4g})")
        f = np.sqrt(w2) / (2 * math.pi)
        return cls(
            f,
            damping_ratio,
            phi.T @ np.asarray(input_forces, float).reshape(len(f), -1),
            np.asarray(output_matrix, float) @ phi,
            tuple(output_labels),
            tuple(input_labels),
            quantity,
            feedthrough,
        )

    @classmethod
    def base_excitation(
        cls,
        mass: np.ndarray,
        stiffness: np.ndarray,
        damping_ratio: Sequence[float] | float,
        influence: np.ndarray,
        output_matrix: np.ndarray,
        output_labels: Sequence[str],
        input_label: str = "base_acc",
    ) -> ModalSystem:
        """Base acceleration a_g along ``influence`` r: F = -M r a_g; outputs absolute
        accelerations y = C_out (u'' + r a_g), hence feedthrough C_out r."""
        r = np.asarray(influence, float).reshape(-1, 1)
        c = np.asarray(output_matrix, float)
        return cls.from_matrices(
            mass,
            stiffness,
            damping_ratio,
            -np.asarray(mass, float) @ r,
            c,
            output_labels,
            (input_label,),
            "acceleration",
            c @ r,
        )

    def modal_displacement(self, forces: np.ndarray) -> np.ndarray:
        """Static modal displacements q = gamma u / omega^2 for a constant input u (n_in,)."""
        w = 2 * math.pi * self.frequencies_hz
        return self.gamma @ np.asarray(forces, float) / w**2


def _zoh_mode(omega: float, zeta: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Discrete (b, a) of q[k] and q'[k] per unit modal force, exact for a ZOH input.

    Continuous x' = [[0, 1], [-w^2, -2 zeta w]] x + [0, 1]^T p; expm of the augmented
    matrix gives (Ad, Bd); ss2tf turns each output row into a second-order filter.
    """
    a = np.array([[0.0, 1.0, 0.0], [-(omega**2), -2 * zeta * omega, 1.0], [0.0, 0.0, 0.0]])
    e = scipy.linalg.expm(a * dt)
    ad, bd = e[:2, :2], e[:2, 2:]
    b, den = scipy.signal.ss2tf(ad, bd, np.eye(2), np.zeros((2, 1)))
    return b, den


def _free_response(omega, zeta, q0, v0, t):
    """Closed-form free vibration q(t), q'(t) of an underdamped mode."""
    wd = omega * math.sqrt(1 - zeta**2)
    e = np.exp(-zeta * omega * t)
    c, s = np.cos(wd * t), np.sin(wd * t)
    b = (v0 + zeta * omega * q0) / wd
    q = e * (q0 * c + b * s)
    v = e * (-zeta * omega * (q0 * c + b * s) + (-q0 * wd * s + b * wd * c))
    return q, v


def simulate(
    system: ModalSystem,
    inputs: np.ndarray | None,
    sampling_hz: float,
    n_samples: int | None = None,
    q0: np.ndarray | None = None,
    v0: np.ndarray | None = None,
) -> np.ndarray:
    """Outputs (n, n_out) for inputs (n, n_in) held constant over each sample (ZOH).

    q0, v0: initial modal displacements and velocities (m,), e.g. for a snap-back test.
    Acceleration outputs use q'' = gamma u - 2 zeta w q' - w^2 q.
    """
    if sampling_hz <= 0:
        raise InputError(f"simulate: sampling_hz must be > 0, got {sampling_hz!r}")
    n_in = len(system.input_labels)
    if inputs is None:
        if n_samples is None:
            raise InputError("simulate: give inputs or n_samples")
        inputs = np.zeros((n_samples, n_in))
    u = np.asarray(inputs, float).reshape(len(inputs), -1)
    if u.shape[1] != n_in:
        raise InputError(f"simulate: inputs have {u.shape[1]} columns, the system has {n_in} inputs")
    n, dt = u.shape[0], 1.0 / sampling_hz
    t = np.arange(n) * dt
    m = system.n_modes
    q0 = np.zeros(m) if q0 is None else np.asarray(q0, float)
    v0 = np.zeros(m) if v0 is None else np.asarray(v0, float)
    modal_force = u @ system.gamma.T  # (n, m)
    q = np.empty((n, m))
    v = np.empty((n, m))
    for r in range(m):
        w, z = 2 * math.pi * system.frequencies_hz[r], system.damping_ratio[r]
        b, den = _zoh_mode(w, z, dt)
        q[:, r] = scipy.signal.lfilter(b[0], den, modal_force[:, r])
        v[:, r] = scipy.signal.lfilter(b[1], den, modal_force[:, r])
        if q0[r] or v0[r]:
            fq, fv = _free_response(w, z, q0[r], v0[r], t)
            q[:, r] += fq
            v[:, r] += fv
    if system.quantity == "displacement":
        return q @ system.output_shapes.T
    w = 2 * math.pi * system.frequencies_hz
    acc = modal_force - 2 * system.damping_ratio * w * v - w**2 * q
    return acc @ system.output_shapes.T + u @ system.feedthrough.T


def add_noise(signal: np.ndarray, ratio: float, rng: np.random.Generator) -> np.ndarray:
    """Signal + Gaussian white noise of standard deviation ``ratio`` x RMS of each channel."""
    if ratio < 0:
        raise InputError(f"add_noise: noise ratio must be >= 0, got {ratio!r}")
    x = np.asarray(signal, float)
    if ratio == 0 or x.size == 0:
        return x.copy()
    x2 = x.reshape(len(x), -1)
    rms = np.sqrt(np.mean(x2**2, axis=0))
    return (x2 + ratio * rms * rng.standard_normal(x2.shape)).reshape(x.shape)
