"""Shading Lab's benchmarks: one module each on a shared harness (``harness/``).

    .venv/bin/python scripts/bench list
    .venv/bin/python scripts/bench run NAME [--quick] [--out DIR] [options]

See README.md beside this file: how to list, run and add a benchmark.
"""
