"""The type of a residual formulation, and what it says about its residuals' noise."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


class ResidualStd(NamedTuple):
    """How a formulation's modal residuals relate to the data noise.

    scales (r_m,): standard deviation of each modal residual; data_std (r_m,): standard
    deviation of each residual's datum in the data's units (the likelihood's normalization);
    n_data: number of independent data; assumption: an approximation the formulation makes
    ("" if none), named in ``noise_assumed``; uses_shape_std: the shapes' noise entered."""

    scales: np.ndarray
    data_std: np.ndarray
    n_data: int
    assumption: str = ""
    uses_shape_std: bool = False


@dataclass(frozen=True)
class Formulation:
    """A residual formulation, selected by ``objective.formulation: <name>``.

    residuals(result, measured, spec) -> (modal residuals (r_m,), ModeCorrelation);
    n_residuals(measured, spec) -> r_m; split(residuals (..., r_m), measured, spec) -> the
    objective vector (..., len(objective_names)).
    """

    name: str
    residuals: Callable
    n_residuals: Callable
    split: Callable
    objective_names: tuple[str, ...] = ("Pi_f", "Pi_MAC")
    #: optional vectorized residuals(freqs (n, m), shapes (n, dof, m), measured, spec) ->
    #: (residuals (n, r), ModeCorrelations), or None when it cannot (the per-point path is used)
    batch_residuals: Callable | None = None
    #: optional check of ``ObjectiveSpec.options`` (raises ValueError naming the key); None:
    #: the formulation reads no options
    check_options: Callable[[dict], None] | None = None
    #: optional exact Jacobian jacobian(result, derivatives, correlation, measured, spec) -> (r, k)
    #: d residuals / d theta from :class:`~framework.core.modal_derivatives.ModalDerivatives` of the
    #: paired modes (pairing held fixed); None: finite differences only
    jacobian: Callable | None = None
    #: residual_std(measured, spec, noise: DataNoise) -> ResidualStd: the standard deviation of
    #: each modal residual given the data's noise (:mod:`framework.inference.noise`); used by
    #: the likelihood (:func:`framework.inference.likelihood.noise_model`)
    residual_std: Callable | None = None
    #: optional check_data(measured, spec), raising InputError for data the formulation cannot use
    check_data: Callable | None = None
    #: the objective's alpha and beta weight its terms (a zero alpha without a shape term would
    #: make it identically 0)
    uses_weights: bool = True
