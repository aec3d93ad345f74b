"""Visible-map culling, event-map registration and the steppable tracking engine."""
