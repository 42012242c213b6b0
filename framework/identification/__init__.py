"""System identification from vibration tests (SPEC section 8).

Modules, one job each: ``records`` (test records, NPZ/CSV I/O), ``excitation`` (sweep,
jumping, noise signals), ``simulate`` (modal-superposition simulator), ``lab_tests`` and
``bridge_tests`` (the simulated tests of the two structures), ``frf`` (H1, coherence, peak
picking), ``subspace`` (N4SID / covariance SSI over model orders), ``stability``
(stability diagram, automatic mode selection), ``pipeline`` (the chain and the export to
measured modes), ``study`` (the end-to-end study writing ``results/identification``).
See README.md in this folder for formats and choices.
"""
