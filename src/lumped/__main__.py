"""``python -m lumped`` runs the ``lumped`` command."""

from .cli import main

raise SystemExit(main())
