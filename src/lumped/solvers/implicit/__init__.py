"""implicit."""
