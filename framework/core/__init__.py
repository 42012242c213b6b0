"""Foundations used by every layer: errors, strict text readers, atomic files, tidy tables, provenance,
parameters, modal correlation (MAC, pairing) and modal derivatives. Imports nothing else of the framework."""
