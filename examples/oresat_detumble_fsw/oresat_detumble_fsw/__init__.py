"""OreSat B̂×ω detumble flight software: a user's own node, flown in the ACDS emulator's loop (issue 20 §3)."""
