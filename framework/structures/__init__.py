"""Built-in structures, one package each, described by typed descriptors and registered once.

- :mod:`.descriptor`: :class:`~.descriptor.StructureDescriptor`, what the framework knows of a
  structure (model, measured data, effects, geometry, reproduction rows, simulated tests,
  modelling choices, identified data sets);
- :mod:`.registry`: one line per built-in structure and the look-ups every feature uses;
- :mod:`.references`: a user's ``module:function`` (or ``module:DESCRIPTOR``) in a config,
  described by the same type;
- one package per structure, each with its ``descriptor.py``: :mod:`.lab_frame` (3-DOF and
  detailed models), :mod:`.bridge`, :mod:`.beam`, :mod:`.smu` (four-storey frame and
  footbridge), :mod:`.frame_two_bay`.

How to add one: docs/tutorials/add-a-structure.md.
"""
