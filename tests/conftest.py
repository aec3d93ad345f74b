"""Shared fixtures. Numba caches go to a per-run folder so a clean clone compiles once."""
