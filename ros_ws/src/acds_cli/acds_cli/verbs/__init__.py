"""Verb groups of ``scripts/acds``: each module defines ``register(subparsers)``; a package adds its own through
the entry-point group ``acds.verbs`` with the same protocol (:mod:`acds_common.plugins`)."""
