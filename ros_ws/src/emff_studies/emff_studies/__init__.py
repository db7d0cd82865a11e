"""EMFF mission studies (seed 004 slides 40–55): a mission package of its own, because its verbs fly the formation
laws of ``acds_controller`` against the graph and against the airtrack plant of ``dynamics`` — two packages' cores,
which neither package may import from the other (docs/architecture.md "Adding a mission")."""
