"""Reporting: analyses (tables -> tables), figures drawn from tables, reproduction report."""
