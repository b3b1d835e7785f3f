"""Benchmarks: each module has ``main(argv=None) -> int`` and writes ``benchmarks/results/``."""
