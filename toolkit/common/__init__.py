"""What every package of the toolkit uses, below all of them:

* :mod:`~toolkit.common.validate`: the one family of input checks (each message names the
  argument, the value and what is allowed);
* :mod:`~toolkit.common.shared`: per-thread values, pickling and equality by constructor
  arguments, the user's own line for warnings;
* :mod:`~toolkit.common.cache`: private folders and a file store that nobody can poison
  (rendered URDFs, the compiled kernels' folder);
* :mod:`~toolkit.common.tables`: CSV tables read as users write them;
* :mod:`~toolkit.common.renames`: keywords renamed, the old name kept for a release;
* :mod:`~toolkit.common.background`: a kernel not compiled yet runs as Python while a
  background process compiles it (no call waits for the compiler);
* :mod:`~toolkit.common.kept`: what an object keeps once computed, under its own lock
  (made anew in a forked child).
"""

from . import background, cache, compiler, kept, renames, shared, sources, tables, validate
from .compiler import (
    PARALLEL_LOCK,
    EngineCacheWarning,
    Twin,
    cache_folder,
    compile_seconds,
    inline_kernel,
    kernel,
    parallel_kernel,
    twin_kernel,
)
from .kept import Kept
from .shared import ByArguments, PerThread, caller_level

__all__ = [
    "PARALLEL_LOCK",
    "ByArguments",
    "EngineCacheWarning",
    "Kept",
    "PerThread",
    "Twin",
    "background",
    "cache",
    "cache_folder",
    "caller_level",
    "compile_seconds",
    "compiler",
    "inline_kernel",
    "kept",
    "kernel",
    "parallel_kernel",
    "renames",
    "shared",
    "sources",
    "tables",
    "twin_kernel",
    "validate",
]
