"""Measured modes of the bridge (:func:`measured`) with reference shapes from the initial model.

The 8 subspace-identified (or peak-picked) frequencies of :mod:`.data`. Measured mode
shapes are not published; the reference shapes at the 36 deck sensor DOFs are the
initial (4-element) model's deck modes paired with the measured modes by type and
nearest frequency, so the MAC term guards mode identity only.
"""

from __future__ import annotations

import functools

import numpy as np

from framework.core.errors import InputError, ModelEvaluationError
from framework.measured.modes import MeasuredModes
from framework.structures.bridge.data import (
    DESIGN_MODEL_HZ,
    MEASURED_DAMPING,
    MEASURED_HZ,
    MEASURED_LABELS,
    MEASURED_PEAK_HZ,
    MEASURED_TYPES,
)
from framework.structures.bridge.model import make_model
from framework.structures.bridge.modes import pair_by_type


@functools.lru_cache(maxsize=4)
def _reference_shapes(cable_elements: int) -> tuple[np.ndarray, tuple[str, ...], tuple[float, ...]]:
    model = make_model(cable_elements=cable_elements, fast=False)
    result = model.modal({})
    idx = pair_by_type(result)
    if np.any(idx < 0):
        raise ModelEvaluationError("too_few_modes", f"initial model lacks measured mode types: {idx.tolist()}")
    return result.shapes[:, idx].copy(), result.dofs, tuple(result.frequencies_hz[idx])


def measured(case: str = "base") -> MeasuredModes:
    """The 8 measured modes (subspace frequencies, damping) with reference shapes.

    Measured shapes are not published: the shapes are the initial 4-element model's deck
    modes (paired by type and order) at the 36 edge sensor DOFs, so the MAC term only
    guards mode identity. case: "base" (subspace) or "peak" (peak-picking frequencies).
    """
    if case not in ("base", "peak"):
        raise InputError(f"bridge measured(case=...) must be 'base' or 'peak', got {case!r}")
    shapes, dofs, f_model = _reference_shapes(4)
    return MeasuredModes(
        frequencies_hz=np.array(MEASURED_HZ if case == "base" else MEASURED_PEAK_HZ),
        dofs=dofs,
        shapes=shapes,
        damping_ratio=np.array(MEASURED_DAMPING),
        labels=MEASURED_LABELS,
        name=f"bridge_{case}",
        source="SPEC section 6 (frequencies); shapes from the initial 4-element model",
        meta={
            "shapes": "reference shapes from the initial 4-element model, not measured",
            "mode_types": list(MEASURED_TYPES),
            "design_model_hz": list(DESIGN_MODEL_HZ),
            "initial_model_hz": list(f_model),
        },
    )
