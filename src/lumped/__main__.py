"""``python -m lumped`` runs the ``lumped`` command."""

from .cli import main

if __name__ == "__main__":
    raise SystemExit(main())
