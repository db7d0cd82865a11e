"""HEAO cold-gas reaction control subsystem: tanks, regulators, pressure switch, six thrusters (seed 002 §5)."""
