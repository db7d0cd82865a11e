"""Rigid-body dynamics, environment (orbit, tilted-dipole field, sun) and reaction wheels (spec §3, §4)."""
