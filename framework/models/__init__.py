"""Structural models: the StructuralModel protocol, the OpenSees path and the built-in structures."""
