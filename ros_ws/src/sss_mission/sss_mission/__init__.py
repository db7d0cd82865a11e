"""SSS mission (seed 001): a mission package of its own for its verbs, which use the CLI's mechanism (a node package's
code may not: the runtime that starts its nodes depends on it) around ascs_mode_manager's SSS cores (docs/architecture.md
"Adding a mission")."""
