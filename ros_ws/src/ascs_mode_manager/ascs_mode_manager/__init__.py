"""Mode manager: HEAO Mode 1A→1B→cruise and SSS perigee automatic turn-on (spec §8)."""
