"""Model-form discrepancy: detect what calibration cannot fix, name the missing physical
effect from a catalogue, add it, and show the gap shrink (SPEC 9, issue 9).

Modules: likelihood (Gaussian noise model, the "gaussian" objective formulation),
calibrate (multi-start least squares), detect (chi-square test, unmatched modes, COMAC),
score (BIC ranking, decisive rule), holdout (held-out-mode prediction), effects (Effect,
Catalogue; each structure's catalogue lives in its package under framework/structures/),
generate (data with hidden effects), config (the data source of a diagnose config), workflow (diagnose),
tables (a diagnosis as tidy tables), outcomes (cases and rates of hidden-effect studies),
report (figures from the tables). Run kind ``diagnose``: :mod:`framework.study.kinds.diagnose`.
"""
