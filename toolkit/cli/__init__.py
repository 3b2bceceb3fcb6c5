"""The command line (``toolkit ...``): :mod:`~toolkit.cli.main` (the parser and the
commands), :mod:`~toolkit.cli.inputs` (a robot from the arguments),
:mod:`~toolkit.cli.calibrate` (``toolkit calibrate``), :mod:`~toolkit.cli.precompile` (compile
every kernel ahead of time) and :mod:`~toolkit.cli.apidoc` (docs/api.md)."""

from typing import TYPE_CHECKING, Any

from .main import build_parser, main

if TYPE_CHECKING:
    from .precompile import warmup


def __getattr__(name: str) -> Any:
    if name == "warmup":  # imported when asked for: the parser alone loads nothing heavy
        from .precompile import warmup

        globals()["warmup"] = warmup  # found directly from now on
        return warmup
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["build_parser", "main", "warmup"]
