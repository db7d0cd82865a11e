"""User commands of the ACDS emulator (``scripts/acds``): launcher, monitor, tools."""
