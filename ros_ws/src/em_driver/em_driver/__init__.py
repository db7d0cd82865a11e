"""Electromagnets and bridge-switch drivers with the ±ε hysteresis current band (spec §6)."""
