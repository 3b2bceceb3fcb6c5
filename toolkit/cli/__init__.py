"""The command line (``toolkit ...``): :mod:`~toolkit.cli.main` (the parser and the
commands), :mod:`~toolkit.cli.inputs` (a robot from the arguments),
:mod:`~toolkit.cli.calibrate` (``toolkit calibrate``), :mod:`~toolkit.cli.warmup` (compile
every kernel ahead of time) and :mod:`~toolkit.cli.apidoc` (docs/api.md)."""

from .main import build_parser, main
from .warmup import warmup

__all__ = ["build_parser", "main", "warmup"]
