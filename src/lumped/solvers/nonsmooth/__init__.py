"""nonsmooth."""
