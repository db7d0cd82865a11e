"""OreSat mission (seed 003): a mission package of its own for its verb, which uses the CLI's mechanism (a node package's
code may not: the runtime that starts its nodes depends on it) around em_driver's torque-rod design core (docs/architecture.md
"Adding a mission")."""
