"""Thin command-line wrappers; each subcommand is one module with a ``main`` function tyro reads."""
