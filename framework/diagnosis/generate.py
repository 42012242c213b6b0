"""Measured data with a hidden effect: truth = model + effect + parameter errors + noise.

From one ``np.random.default_rng(seed)``, in this order:

1. base parameters theta_i = theta_i,0 (1 + parameter_error_rel N(0, 1)) (additive
   ``parameter_error_rel * span`` for parameters whose initial value is 0), clipped to
   the bounds;
2. for each hidden effect: a variant (uniform over ``hidden_variants``, unless given)
   and its parameter values (uniform over the effect's ``hidden_values`` ranges, scaled
   towards the null value by ``magnitude``, unless given);
3. the truth model's modes; the modes a test would measure (``select_modes``);
4. the Gaussian noise of :class:`framework.inference.simulate.Noise` (the one simulator of
   noisy modes): shapes normalized to a largest component of +1, f_e = f (1 +
   frequency_std_rel N(0, 1)), then phi_e = phi + shape_std_rel N(0, 1) per component.

The returned :class:`MeasuredModes` carries ``frequency_std_hz = frequency_std_rel f_e``
and ``shape_std = shape_std_rel`` (the noise actually used; none with ``with_stds=False``),
and the truth in ``meta``. Named levels: :data:`framework.inference.simulate.NOISE_LEVELS`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from framework.core.errors import InputError
from framework.diagnosis.effects import Catalogue
from framework.inference.simulate import NOISE_LEVELS, Noise, noisy_measurement
from framework.measured.modes import MeasuredModes

__all__ = ["NOISE_LEVELS", "HiddenCase", "Noise", "generate"]


@dataclass(frozen=True)
class HiddenCase:
    """Hidden effects {name: variant or None (random)}, their values (optional), seed, noise.

    magnitude scales each drawn effect value's distance from its null value
    (v = null + magnitude (v_drawn - null)); 1 = the catalogue's clearly present effect.
    """

    hidden: Mapping[str, str | None] = field(default_factory=dict)
    values: Mapping[str, float] = field(default_factory=dict)
    seed: int = 0
    noise: Noise = field(default_factory=Noise)
    parameter_error_rel: float = 0.05
    magnitude: float = 1.0
    #: False: the returned data carry no standard deviations (as many measured-modes files)
    with_stds: bool = True


def generate(catalogue: Catalogue, case: HiddenCase, name: str = "") -> MeasuredModes:
    """Simulated measurement of the truth model described by ``case``."""
    rng = np.random.default_rng(case.seed)
    truth: dict[str, float] = {}
    for p in catalogue.base_parameters:
        if p.initial != 0:
            v = p.initial * (1.0 + case.parameter_error_rel * rng.standard_normal())
        else:
            v = p.initial + case.parameter_error_rel * p.span * rng.standard_normal()
        truth[p.name] = float(np.clip(v, p.lower, p.upper))
    active: dict[str, str] = {}
    for eff_name, variant in case.hidden.items():
        eff = catalogue.effect(eff_name)
        choices = eff.hidden_variants or eff.variants
        active[eff_name] = str(variant) if variant is not None else str(choices[rng.integers(len(choices))])
        for p in eff.parameters:
            if p.name in case.values:
                v = float(case.values[p.name])
            elif p.name in eff.hidden_values:
                lo, hi = eff.hidden_values[p.name]
                v = float(p.initial + case.magnitude * (rng.uniform(lo, hi) - p.initial))
            else:
                raise InputError(f"{catalogue.structure}: no value for hidden parameter {p.name!r} of {eff_name!r}")
            truth[p.name] = v
    unknown = sorted(set(case.values) - set(truth))
    if unknown:
        raise InputError(f"hidden values given for unknown parameters {unknown}; known: {sorted(truth)}")
    model = catalogue.model(active)
    result = model.modal(truth)
    idx = catalogue.modes_to_measure(result)
    f = result.frequencies_hz[idx]
    noise = case.noise
    hidden_txt = ",".join(f"{k}[{v}]" if v else k for k, v in active.items()) or "none"
    return noisy_measurement(
        f,
        result.shapes[:, idx],
        result.dofs,
        noise,
        rng,
        with_stds=case.with_stds,
        labels=_labels(catalogue, result, idx),
        name=name or f"{catalogue.structure}_{hidden_txt}_seed{case.seed}",
        source=f"generated: {catalogue.structure}, hidden {hidden_txt}, seed {case.seed}",
        meta={
            "truth_parameters": truth,
            "hidden": active,
            "truth_frequencies_hz": f.tolist(),
            "truth_mode_index": idx.tolist(),
            "noise": {"frequency_std_rel": noise.frequency_std_rel, "shape_std_rel": noise.shape_std_rel},
            "seed": case.seed,
            "magnitude": case.magnitude,
        },
    )


def _labels(catalogue: Catalogue, result, idx: np.ndarray) -> tuple[str, ...]:
    if catalogue.label_modes is not None:
        return tuple(catalogue.label_modes(result, idx))
    if len(catalogue.mode_labels) == len(idx):
        return tuple(catalogue.mode_labels)
    return tuple(f"mode {i + 1}" for i in range(len(idx)))
