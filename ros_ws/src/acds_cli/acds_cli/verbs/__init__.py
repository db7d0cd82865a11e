"""Verb groups of ``scripts/acds``: each module defines ``register(subparsers)``."""
