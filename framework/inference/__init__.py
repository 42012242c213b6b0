"""Uncertainty of the updated model: likelihood and priors, linearized posterior, evidence,
sampled posterior (see docs/uncertainty.md)."""
