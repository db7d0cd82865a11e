"""CANopen devices from an object dictionary on a socketcand-protocol bus: flight software on the bus (spec §13)."""
