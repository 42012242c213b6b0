"""The noise model of measured modes: the standard deviation of every measured frequency and
shape component, where each came from, and the assumed defaults (defined here, once).

Every user of measurement noise reads it from here: the likelihood and the linearized and
sampled posteriors (:mod:`framework.inference.likelihood`, the ``posterior`` run kind and the
linearized uncertainty of every updating run), the ``gaussian`` formulation (its whitening),
the diagnosis (its chi-square noise test, :func:`consistency_test`) and the simulators of
noisy modes (:mod:`framework.inference.simulate`, whose ``very_high`` level equals the
default).

Sources. Each standard deviation has a source:

- ``data``: given by the measured data (``frequency_std_hz``, ``shape_std``);
- ``estimated``: estimated from repeated tests (a :class:`DataNoise` built by an estimator and
  passed in where a ``DataNoise`` is accepted; the estimator itself is a later addition);
- ``assumed``: the data give none; the defaults below (or a caller's levels) are used, and
  every output names the assumption (``noise_assumed`` columns, the diagnosis's warning).

A frequency's standard deviation is relative to the measured frequency; a shape component's
is relative to the largest measured |component| of its mode (so it does not depend on how the
shape is scaled).

Assumed defaults: sigma_f = 1 % of f, sigma_phi = 5 % of the mode's largest component. They
are chosen at the upper end of the scatter of identified modes between repeated tests of civil
structures, so that an assumption is not below the real noise:

- Within one record, the identification uncertainty of a well-excited mode's frequency is a
  few tenths of a percent or less; it falls with record length and rises with damping (Au,
  Brownjohn & Mottershead 2018, "Quantifying and managing uncertainty in operational modal
  analysis", Mech. Syst. Signal Process. 102, 139-157; for subspace identification Doehler,
  Lam & Mevel 2013, "Uncertainty quantification for modal parameters from stochastic subspace
  identification on multi-setup measurements", MSSP 36(2), 562-581). That is a lower bound of
  the scatter between tests.
- Between tests, environmental and operational conditions (temperature above all) move the
  identified frequencies by more than the identification error (Sohn et al. 1999, "An
  experimental study of temperature effect on modal parameters of the Alamosa Canyon Bridge",
  Earthq. Eng. Struct. Dyn. 28, 879-897: a daily cycle; Peeters & De Roeck 2001, "One-year
  monitoring of the Z24-Bridge: environmental effects versus damage events", EESD 30(2),
  149-171). How measurement-error variances are set in Bayesian updating (fixed beforehand or
  estimated) is reviewed by Simoen, De Roeck & Lombaert 2015, "Dealing with uncertainty in
  model updating for damage assessment: a review", MSSP 56-57, 123-149.
- Repeated field tests at hand: the steel pedestrian bridge of the SMU benchmark
  (ywang-structures/Structural-Model-Updating, read from ../shared/benchmarks/smu; 7 to 16
  repeated tests per mode, their standard deviations in the data): sigma_f / f = 0.74, 0.47,
  0.51, 0.82 and 2.0 % for modes 1-5; shape standard deviation relative to the mode's peak,
  root mean square over the 58 channels, 4.6, 2.9, 4.3, 5.4 and 33 %.

1 % and 5 % are at or above that scatter for the four well-identified modes; 0.5 % / 2 % (this
framework's earlier likelihood default) lie below it for most of them. The diagnosis's false
discovery target (at most 5 % of null cases flagged) holds only when the assumed noise is not
below the real noise: an assumption a factor r too small inflates chi2 by r^2 and flags a
correct model. Assuming too much costs power (a small discrepancy may go undetected) and gives
wider intervals: the conservative side for both the test and the uncertainty. A poorly excited
mode (the footbridge's mode 5) exceeds any default: data should carry their own standard
deviations.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import stats

from framework.core.errors import InputError
from framework.measured.modes import MeasuredModes

#: sigma_f / f assumed where the data give no frequency standard deviation (module docstring)
DEFAULT_FREQUENCY_STD_REL = 0.01
#: shape standard deviation assumed where the data give none, as a fraction of the mode's
#: largest measured |component| (module docstring)
DEFAULT_SHAPE_STD_REL = 0.05
#: where a standard deviation came from
SOURCES = ("data", "estimated", "assumed")


@dataclass(frozen=True)
class DataNoise:
    """Standard deviation of each measured datum and its source.

    frequency_std_hz (m,); shape_std (n_dof, m) in the shapes' units, None when the shapes are
    not used; frequency_source / shape_source: one of :data:`SOURCES` ("" for unused shapes);
    frequency_std_rel / shape_std_rel: the levels used where the source is ``assumed``.
    """

    frequency_std_hz: np.ndarray
    shape_std: np.ndarray | None
    frequency_source: str
    shape_source: str
    frequency_std_rel: float = DEFAULT_FREQUENCY_STD_REL
    shape_std_rel: float = DEFAULT_SHAPE_STD_REL

    def __post_init__(self):
        for what, source in (("frequency", self.frequency_source), ("shape", self.shape_source)):
            if source not in SOURCES and not (what == "shape" and source == ""):
                raise ValueError(f"noise: {what} source must be one of {SOURCES}, got {source!r}")

    def assumptions(self, shapes: bool = True) -> list[str]:
        """The assumed standard deviations, one text each (none when every one has a source)."""
        out = []
        if self.frequency_source == "assumed":
            out.append(f"frequency std {100 * self.frequency_std_rel:g} % of f")
        if shapes and self.shape_source == "assumed":
            out.append(f"shape std {100 * self.shape_std_rel:g} % of the peak")
        return out

    @property
    def assumed(self) -> str:
        """"" when no standard deviation is assumed, else what is assumed ("; "-joined)."""
        return "; ".join(self.assumptions())


def data_noise(
    measured: MeasuredModes,
    frequency_std_rel: float = DEFAULT_FREQUENCY_STD_REL,
    shape_std_rel: float = DEFAULT_SHAPE_STD_REL,
    use_shapes: bool = True,
) -> DataNoise:
    """The standard deviations of ``measured``: the data's own where given, else the levels
    (relative to f, and to each mode's largest |shape component|), with their sources.

    A frequency standard deviation of 0 in the data is an input error (no identified frequency
    is exact); a shape standard deviation of 0 is allowed (a normalising component)."""
    for name, v in (("frequency_std_rel", frequency_std_rel), ("shape_std_rel", shape_std_rel)):
        if isinstance(v, bool) or not (np.isfinite(v) and v > 0):
            raise InputError(f"noise.{name} must be a number > 0, got {v!r}")
    f = measured.frequencies_hz
    if measured.frequency_std_hz is not None:
        f_std, f_source = np.asarray(measured.frequency_std_hz, float), "data"
        zero = np.flatnonzero(f_std <= 0)
        if zero.size:
            raise InputError(f"{measured.source}: frequency_std_hz of mode {zero[0] + 1} is 0; give the "
                             "frequency's standard deviation, or leave the field out to assume "
                             f"{100 * frequency_std_rel:g} % of f")
    else:
        f_std, f_source = frequency_std_rel * f, "assumed"
    s_std, s_source = None, ""
    if use_shapes and measured.has_shapes:
        if measured.shape_std is not None:
            s_std, s_source = np.asarray(measured.shape_std, float), "data"
        else:
            peak = np.max(np.abs(measured.shapes), axis=0)
            s_std, s_source = np.broadcast_to(shape_std_rel * peak, measured.shapes.shape).copy(), "assumed"
    return DataNoise(f_std, s_std, f_source, s_source, float(frequency_std_rel), float(shape_std_rel))


def with_stds(measured: MeasuredModes, noise: DataNoise) -> MeasuredModes:
    """Copy of ``measured`` carrying the standard deviations of ``noise`` (e.g. to fix a
    workflow's assumption once, as the diagnosis does)."""
    s_std = noise.shape_std if noise.shape_std is not None else measured.shape_std
    return replace(measured, frequency_std_hz=np.asarray(noise.frequency_std_hz, float), shape_std=s_std)


# ---- the noise test -------------------------------------------------------------------------
def consistency_test(chi2: float, n_data: int, k: int) -> tuple[int, float]:
    """(degrees of freedom, p-value) of the chi-square test of a calibrated model: with Gaussian
    noise of known standard deviations and a model containing the truth, the minimum chi2 over k
    parameters follows (to first order) chi2 with n_data - k degrees of freedom (at least 1);
    p = P(chi2_dof >= chi2)."""
    dof = max(int(n_data) - int(k), 1)
    return dof, float(stats.chi2.sf(chi2, dof))
