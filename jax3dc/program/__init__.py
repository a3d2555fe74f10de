"""Part programs (SPEC §6): parsed and interpreted, never executed."""
