"""Measured modal data: the MeasuredModes type and every file format it is read from (YAML, CSV, UFF with
a mapping file, pyOMA2 results)."""
