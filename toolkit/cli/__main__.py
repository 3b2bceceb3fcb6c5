"""``python -m toolkit.cli``: the same as the ``toolkit`` command."""

from .main import main

raise SystemExit(main())
