"""Mode shapes on the structure's geometry, as tables.

- :mod:`.geometry`: the geometry and full mode shapes of a model (nodes, elements with a
  group such as deck, pylon or cable, the displacement of every node in every mode) and
  where its measured DOFs are (sensor points);
- :mod:`.tables`: the tables ``geometry``, ``mode_shapes``, ``sensor_shapes``,
  ``mac_matrix`` and ``comac`` of a model at given parameter values against measured modes;
- :mod:`.stage`: the post-run stage of ``gomu run`` that writes these tables for a study
  (initial model and the best updated run).

Figures are drawn from these tables only (:mod:`framework.figures`), so ``gomu report``
works where the model cannot be built.
"""
