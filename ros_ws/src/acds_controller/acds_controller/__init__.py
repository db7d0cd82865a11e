"""Transfer assembly and DPA control laws: B-dot, B×H, wheel laws (spec §7)."""
