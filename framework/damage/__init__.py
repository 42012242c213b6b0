"""Damage estimation (SPEC 7): damage indices, L-curve corner, two-state problems."""
