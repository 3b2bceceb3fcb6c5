"""How the compiled engine uses numba, decided once per process and in one place.

* **Where compiled kernels are cached.** numba's on-disk cache holds pickles it loads and
  runs, so the toolkit only ever points it at a folder of this user's that no one else can
  write: ``$NUMBA_CACHE_DIR`` when that is such a folder (otherwise it is ignored, with a
  :class:`EngineCacheWarning`), else ``<toolkit cache>/numba-<numba version>`` (the render
  cache's private folder, :mod:`toolkit.common.cache`), else a private temporary folder. When
  none can be written (a read-only home and temporary folder) the kernels are compiled in
  memory, every process anew: everything works, the first calls are slower. A cache write
  that fails later (a full disk) is skipped with one warning instead of failing the call.
  The package folder itself is never written.
* **A cached kernel is as new as every source it was made from.** numba keys a cached
  kernel by its own file's time stamp, but a kernel holds the machine code of every kernel
  it calls, from any file, and the constants it reads: a change to one of those (a
  checkout that touches only ``bound_kernels.py``) left the kernels of other files that
  call it loaded stale from the cache (found by a benchmark that timed the old code).
  Every kernel's stamp also holds the digest of its module and of every package file that
  module imports (:mod:`toolkit.common.sources`; the package's files read once per
  process), so a change to any of those compiles it anew, in place, and a change elsewhere
  (the robot's face, the CLI) recompiles nothing.
* **One lock around parallel launches.** numba's ``workqueue`` threading layer (the one a
  plain ``pip install`` may get) aborts the process when two threads launch parallel
  kernels at once; every parallel kernel is launched under :data:`PARALLEL_LOCK`, so a
  :class:`~toolkit.robot.Robot` may be used from any number of threads on any layer.
  Serial kernels release the GIL and run concurrently.
* **No call waits for the compiler.** A kernel with no machine code yet, here or in the
  cache, runs as Python while a background process compiles it
  (:mod:`toolkit.common.background`; ``TOOLKIT_COMPILE=wait`` compiles in the call, as the
  test suite does). A call that does compile (``wait``, a batch too large for Python, a
  kernel compiled in memory) says so once on the ``toolkit.compile`` logger (a warning,
  which Python prints to stderr where no logging is set up; not a :mod:`warnings` warning,
  which ``-W error`` would raise from inside numba), and ``toolkit warmup`` compiles every
  kernel ahead. The seconds spent compiling (numba's compile events: loading from the cache
  is not compiling) add up in :func:`compile_seconds`, which a call with a time limit leaves
  out of its clock.
* **Forks.** GNU OpenMP (numba's ``omp`` layer) cannot run in a child forked after the
  parent used it: the child hangs. Unless the user chose a layer (``NUMBA_THREADING_LAYER``)
  the toolkit asks numba for ``tbb`` when it is installed, else ``workqueue``, so a
  ``multiprocessing`` pool forked after batch calls works.
"""

from __future__ import annotations

import logging
import os
import threading
import time
import types
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

from . import background, cache, sources

__all__ = [
    "PARALLEL_LOCK",
    "EngineCacheWarning",
    "Twin",
    "cache_folder",
    "compile_seconds",
    "inline_kernel",
    "kernel",
    "parallel_kernel",
    "sources_digest",
    "twin_kernel",
]

PARALLEL_LOCK = threading.RLock()
"""Held while a parallel (``prange``) kernel runs."""


class EngineCacheWarning(UserWarning):
    """The compiled kernels' cache folder was refused or could not be written."""


_SETUP_LOCK = threading.Lock()
_CHOICE: list[tuple[Path | None, str]] = []
_WARNED: set[str] = set()


def _warn_once(key: str, message: str) -> None:
    if key not in _WARNED:
        _WARNED.add(key)
        warnings.warn(message, EngineCacheWarning, stacklevel=3)


def _writable(folder: Path) -> bool:
    """True if a file can be created (and removed) in ``folder``."""
    probe = folder / f".probe-{os.getpid()}-{threading.get_ident()}"
    try:
        with open(probe, "wb") as handle:
            handle.write(b"0" * 4096)
        probe.unlink()
        return True
    except OSError:
        return False


def _private_folder(folder: Path) -> Path | None:
    """``folder`` (created 0700) if it is a private, writable folder of this user. Its
    parent, the toolkit's cache folder, is made 0700 too where it is new (``mkdir``'s
    ``parents`` would make it open to reading, and the render and covers caches would
    then never use it)."""
    try:
        folder.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        folder.mkdir(mode=0o700, exist_ok=True)
    except OSError:
        return None
    return folder if cache.is_private(folder) and _writable(folder) else None


def _choose() -> tuple[Path | None, str]:
    import numba

    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        chosen = Path(env)
        if cache.is_private(chosen) and _writable(chosen):
            return chosen, "NUMBA_CACHE_DIR"
        _warn_once(
            "env",
            f"NUMBA_CACHE_DIR={env!r} is ignored by the toolkit: it is not a folder of this "
            "user's closed to others (0700), and numba's cache runs the pickles it loads",
        )
    tag = f"numba-{numba.__version__}"
    choices = (
        (cache.cache_dir, "private cache folder"),
        (cache.fallback_dir, "private temp folder"),
    )
    for base, why in choices:
        try:
            folder = _private_folder(base() / tag)
        except OSError:  # the fallback could not even make a folder
            folder = None
        if folder is not None:
            return folder, why
    _warn_once(
        "none",
        "no private folder can be written for the compiled kernels' cache: they are compiled "
        "in memory in every process (a few seconds per kernel on first use)",
    )
    return None, "in memory (no writable private folder)"


def cache_folder() -> tuple[Path | None, str]:
    """(folder, why) of the compiled kernels' cache; folder None: compiled in memory."""
    with _SETUP_LOCK:
        if not _CHOICE:
            _CHOICE.append(_choose())
        return _CHOICE[0]


def _choose_threading_layer() -> None:
    """TBB when installed, else the workqueue layer (unless the user named one)."""
    from numba.core import config

    if os.environ.get("NUMBA_THREADING_LAYER"):
        return
    try:
        import tbb  # noqa: F401

        layer = "tbb"
    except ImportError:
        layer = "workqueue"
    setattr(config, "THREADING_LAYER", layer)  # noqa: B010 - numba's config has no stubs


sources_digest = sources.sources_digest

_DIGEST: list[str] = []
""":func:`sources_digest` of this process's package, once (the stamp of a kernel outside it)."""


def _stamp(dispatcher: Any) -> None:
    """Where numba reads the dispatcher's cache stamp (its file's time and size), the digest
    of what it is compiled from instead (module doc), worked out when the cache is first
    read (every kernel it calls is defined by then): :func:`~toolkit.common.sources.
    kernel_digest`, or where that cannot be followed, of its module and what that imports
    (:func:`~toolkit.common.sources.module_digest`), or of every package file. An index
    written under another digest reads as stale, and numba compiles the kernel anew and
    writes over it."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    if cache_file is None or "_source_stamp" not in vars(cache_file):
        return  # compiled in memory (no cache)
    del cache_file._source_stamp  # numba's: the file's time, which an installation changes
    func = getattr(dispatcher, "py_func", None)
    if func is not None:  # its file's bytes as they stand now, when its code was read
        sources.read_file(func.__code__.co_filename)
    cache_file._toolkit_kernel = func
    cache_file.__class__ = _stamped_class(type(cache_file))


def _digest_of(func: Any) -> str:
    """:func:`_stamp`'s digest of the kernel ``func``."""
    digest = sources.kernel_digest(func) if func is not None else None
    if digest is None:
        digest = sources.module_digest(str(getattr(func, "__module__", "")))
    if digest is None:
        with _SETUP_LOCK:
            if not _DIGEST:
                _DIGEST.append(sources.sources_digest())
            digest = _DIGEST[0]
    return digest


_STAMPED: dict[type, type] = {}


def _stamped_class(base: type) -> type:
    """``base`` (numba's index file class) with ``_source_stamp`` the kernel's digest, read
    once, on first use."""
    with _SETUP_LOCK:
        if base not in _STAMPED:

            def stamp(self: Any) -> tuple[str, str]:
                found: tuple[str, str] | None = self.__dict__.get("_toolkit_stamp")
                if found is None:
                    found = ("toolkit", _digest_of(self._toolkit_kernel))
                    self.__dict__["_toolkit_stamp"] = found
                return found

            _STAMPED[base] = type(f"Stamped{base.__name__}", (base,),
                                  {"_source_stamp": property(stamp)})  # fmt: skip
        return _STAMPED[base]


def _guard_saves(dispatcher: Any) -> None:
    """A cache write that fails (full disk, folder removed) warns once and is skipped."""
    cache = getattr(dispatcher, "_cache", None)
    save = getattr(cache, "save_overload", None)
    if cache is None or save is None:
        return

    def guarded(*args: Any, **kwargs: Any) -> None:
        try:
            save(*args, **kwargs)
        except OSError as exc:
            _warn_once(
                "save",
                f"a compiled kernel could not be written to its cache ({exc}); it stays "
                "compiled in memory for this process",
            )

    cache.save_overload = guarded


class _CompileClock:
    """numba's compile events (under its one compiler lock, so never two at once): the
    seconds they took, and one notice (module doc) at the first toolkit kernel's."""

    def __init__(self) -> None:
        self.depth, self.total, self.began, self.told = 0, 0.0, 0.0, False

    def on_start(self, event: Any) -> None:
        if self.depth == 0:
            self.began = time.perf_counter()
            func = getattr((event.data or {}).get("dispatcher"), "py_func", None)
            if not self.told and str(getattr(func, "__module__", "")).startswith("toolkit."):
                self.told = True
                folder, _ = cache_folder()
                where = f"cached in {folder}" if folder is not None else "kept in memory"
                logging.getLogger("toolkit.compile").warning(
                    "this call waits for the compiler: the toolkit's kernels compile at their "
                    "first use after an installation (seconds to a minute per kind of call, "
                    "%s); `toolkit warmup` compiles every kernel ahead", where,
                )  # fmt: skip
        self.depth += 1

    def on_end(self, event: Any) -> None:
        self.depth -= 1
        if self.depth == 0:
            self.total += time.perf_counter() - self.began


_CLOCK: list[Any] = []


def _listen() -> None:
    """Register :class:`_CompileClock` with numba once per process (under the set-up lock)."""
    if _CLOCK:
        return
    from numba.core import event

    class Listener(event.Listener):  # numba ships no stubs
        def __init__(self, clock: _CompileClock) -> None:
            self.clock = clock

        def on_start(self, event: Any) -> None:
            self.clock.on_start(event)

        def on_end(self, event: Any) -> None:
            self.clock.on_end(event)

    clock = _CompileClock()
    event.register("numba:compile", Listener(clock))  # type: ignore[no-untyped-call]
    _CLOCK.append(clock)


def compile_seconds() -> float:
    """Seconds this process has spent compiling kernels so far (0.0 before any)."""
    return float(_CLOCK[0].total) if _CLOCK else 0.0


def _decorate(parallel: bool, inline: bool = False) -> Callable[[Callable[..., Any]], Any]:
    def wrap(func: Callable[..., Any]) -> Any:
        import numba
        from numba.core import config

        folder, _ = cache_folder()
        with _SETUP_LOCK:
            _listen()
            _choose_threading_layer()
            saved = getattr(config, "CACHE_DIR", "")
            setattr(config, "CACHE_DIR", str(folder) if folder is not None else "")  # noqa: B010
            try:
                dispatcher = numba.njit(
                    cache=folder is not None,
                    nogil=True,
                    error_model="numpy",
                    parallel=parallel,
                    forceinline=inline,
                )(func)
            finally:
                setattr(config, "CACHE_DIR", saved)  # noqa: B010
        _stamp(dispatcher)
        _guard_saves(dispatcher)
        background.attach(dispatcher, folder, parallel)
        return dispatcher

    return wrap


kernel = _decorate(False)
"""``numba.njit`` for the toolkit's serial kernels (cache and GIL as described above)."""
inline_kernel = _decorate(False, inline=True)
"""The same for the small helpers of the hot loops, inlined into their callers (numba then
prunes the reference counting of the arrays they pass, a quarter of the IK loop's time).
Not for a helper that hands its arrays on to a kernel it calls: inlined, it keeps their
counts at each use (30 ns a pair in the collision pre-filter's loop,
:func:`toolkit.collision.bound_kernels._deep_apart`)."""
parallel_kernel = _decorate(True)
"""The same for ``prange`` kernels; launch them under :data:`PARALLEL_LOCK`."""


def _renamed(func: Callable[..., Any], suffix: str) -> Callable[..., Any]:
    """A copy of ``func`` under another qualified name: numba's on-disk cache keys a
    function by its file, qualified name and bytecode, not by its compile options, so the
    serial and the parallel compilation of one function need two names, or one would load
    the other's machine code."""
    clone = types.FunctionType(
        func.__code__, func.__globals__, f"{func.__name__}_{suffix}", func.__defaults__,
        func.__closure__,
    )  # fmt: skip
    clone.__qualname__ = f"{func.__qualname__}_{suffix}"
    clone.__module__, clone.__doc__ = func.__module__, func.__doc__
    return clone


class Twin:
    """One Python function compiled twice: ``parallel`` (its ``prange`` loops spread over
    every core) and ``serial`` (``prange`` runs as ``range``: one core, no thread launch).
    ``twin(spread, *args)`` runs the one asked for, the parallel one under
    :data:`PARALLEL_LOCK` (or, while a background process compiles it, the serial one:
    :func:`toolkit.common.background.serial_for_now`)."""

    def __init__(self, func: Callable[..., Any]) -> None:
        self.serial = _decorate(False)(_renamed(func, "serial"))
        self.parallel = _decorate(True)(func)
        self.__name__, self.__doc__ = func.__name__, func.__doc__

    def __call__(self, spread: bool, *args: Any) -> Any:
        if not spread or background.serial_for_now(self.parallel, args):
            return self.serial(*args)
        with PARALLEL_LOCK:
            return self.parallel(*args)


def twin_kernel(func: Callable[..., Any]) -> Twin:
    """Compile a kernel with ``prange`` loops as a serial and a parallel :class:`Twin`."""
    return Twin(func)
