"""HEAO acquisition mission (seed 002 Table 4-7): a mission package of its own, because its summary reads the mode
stream of ``ascs_mode_manager``'s HEAO mode logic and the wheel capacity of ``dynamics``' wheel model — two
packages' cores, which neither package may import from the other (docs/architecture.md "Adding a mission")."""
