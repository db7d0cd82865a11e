"""Triaxial fluxgate magnetometer (spec §5, study Table 4-5)."""
