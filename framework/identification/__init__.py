"""System identification from vibration tests (SPEC section 8).

Modules, one job each: ``records`` (test records, NPZ/CSV I/O), ``excitation`` (sweep and
jumping signals), ``simulate`` (modal-superposition simulator), ``campaign`` (the type of a
structure's simulated test campaign: its tests, records and true modes; each structure's
campaign and identified data sets live in its package), ``frf`` (H1, coherence, peak picking),
``subspace`` (N4SID / covariance SSI over model orders), ``stability`` (stability table,
automatic mode selection), ``pipeline`` (the chain and the export to measured modes).
The study is the run kind ``identification`` (:mod:`framework.study.kinds.identification`, ``gomu run
studies/identification.yaml``) with its table rows (``rows``), figures from the tables
(``figures``) and measured-modes files from the tables (``export``).
See README.md in this folder for formats and choices.
"""
