"""radau."""
