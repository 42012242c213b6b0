"""Complex identified mode shapes made real for updating against normal modes.

A complex shape phi is rotated in the complex plane by the angle that maximises its real
part, then the real part is kept:

    ||Re(phi e^{-i a})||^2 = (||phi||^2 + Re(e^{-2 i a} sum_k phi_k^2)) / 2,
    maximal for a = arg(sum_k phi_k^2) / 2,      v = Re(phi e^{-i a}).

The sign is then fixed so that the entry of largest magnitude is positive. The loss of
the step is 1 - MAC(phi, v): 0 for a mode that is real up to a rotation (a classically
damped normal mode), larger for a genuinely complex (or noisy) mode.
"""

from __future__ import annotations

import numpy as np

from framework.core.correlation import mac


def real_mode_shape(phi) -> tuple[np.ndarray, float]:
    """(v, mac_loss): the real shape of the module docstring and 1 - MAC(phi, v)."""
    phi = np.asarray(phi)
    if not np.iscomplexobj(phi):
        return phi.astype(float), 0.0
    alpha = 0.5 * np.angle(np.sum(phi**2))
    v = np.real(phi * np.exp(-1j * alpha))
    k = int(np.argmax(np.abs(v)))
    if v[k] < 0:
        v = -v
    if not np.any(v):
        return v, 1.0
    return v, max(0.0, 1.0 - mac(phi, v))
