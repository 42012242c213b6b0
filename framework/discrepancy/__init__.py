"""Model-form discrepancy: detect what calibration cannot fix, name the missing physical
effect from a catalogue, add it, and show the gap shrink (SPEC 9, issue 9).

Modules: likelihood (Gaussian noise model, the "gaussian" objective formulation),
calibrate (multi-start least squares), detect (chi-square test, unmatched modes, COMAC),
score (BIC ranking, decisive rule), effects (Effect, Catalogue), beam_effects /
lab_effects / bridge_effects (catalogues), generate (data with hidden effects),
workflow (diagnose), report (tables, figure), config (``gomu diagnose``), study.
"""
