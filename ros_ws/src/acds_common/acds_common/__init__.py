"""Shared pieces every ACDS node needs: units, topic names, scenario loading, the lockstep base."""
