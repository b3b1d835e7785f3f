"""Verification cases with published or analytic reference values (used by tests and benchmarks)."""
