"""Mission planning: the phase plan and the information-driven orbit assignment."""
