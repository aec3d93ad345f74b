"""Evaluation: trajectory metrics through evo, speed bins, plots, the benchmark suite, sweeps and their executors."""
