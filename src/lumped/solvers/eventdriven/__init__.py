"""eventdriven."""
