"""No call waits for the compiler: a kernel not compiled yet runs as Python while a process
of its own compiles it.

A kernel's first call after an installation used to wait for numba: 15-25 s for the first
``ik``, 30 s for the first ``plan`` on an idle 2-core machine, minutes on a loaded one. Now
the first call of a kernel whose machine code is in neither this process nor the cache
(:mod:`toolkit.common.compiler`) runs the kernel's own Python body (``py_func``: the same
code, one body, no second implementation) and hands the kernel and the types of its
arguments to a compiling process started in the background. Once that process has written
the machine code to the cache, the next call loads it from there (milliseconds) and runs
compiled.

* **What runs as Python is the kernel, whole**: the kernels it calls run as Python too
  (unless this process has them compiled already), under ``numpy.errstate(all="ignore")``,
  as numba's ``error_model="numpy"`` computes: overflow and division by zero give infinities
  and NaN, silently. Its result is the compiled kernel's to rounding. Where Python's
  semantics part from numba's (``math.sin(inf)`` raises, numba returns NaN; an index past
  an array's end raises), the call is made again compiled, in this process, as before.
* **Which mode**: ``TOOLKIT_COMPILE=background`` (the default) or ``wait`` (every call
  compiles what it needs before it runs: the test suite's choice, and the background
  process's own). :func:`waiting` holds ``wait`` within a block (``toolkit.warmup`` compiles
  every kernel in its own process). With no private cache folder (kernels compiled in
  memory) a background process could hand nothing over: calls wait, as before.
* **Large batches wait.** A batch large enough to spread over the cores (64 rows or more)
  runs on the kernel's serial twin while a background process compiles the parallel one, up
  to :data:`PYTHON_ROWS` rows; a larger one compiles the parallel kernel first, as before (a
  million rows would take longer as Python than the compiler does).
* **Said once**: the first call that runs as Python says so on the ``toolkit.compile``
  logger, with the expected wait.
* **One at a time**: a background process holds a lock file in the cache folder while it
  compiles, so several processes started at once (a fork pool's workers, scripts run
  together) compile one after the other, and the later ones load what the first wrote.
* **Safe**: the background process is this interpreter started afresh (``sys.executable``)
  with the toolkit's own folder first on its path and the cache folder (private: 0700) as its
  working folder; it reads the jobs from a pipe and compiles only kernels the toolkit
  registered under that name. A process forked from this one starts its own. If the
  background process fails, or its kernels do not show up in the cache, the calls compile in
  this process, as before.
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import logging
import os
import pickle
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "LOCK_NAME",
    "PYTHON_ROWS",
    "attach",
    "main",
    "mode",
    "pending",
    "serial_for_now",
    "waiting",
]

MODES = ("background", "wait")

_REGISTRY: dict[tuple[str, str], tuple[Any, Path]] = {}
"""(module, qualified name) -> the toolkit's dispatcher and the cache folder it is kept in:
what a background process may compile."""
PYTHON_ROWS = 1024
"""The largest batch a parallel kernel not compiled yet hands to its serial twin (module
doc); a larger one waits for the compiler."""
_LOCAL = threading.local()
_HELD: list[int] = [0]


def mode() -> str:
    """``"background"`` or ``"wait"`` (module doc), from ``TOOLKIT_COMPILE`` unless
    :func:`waiting` holds ``wait``; an unknown value is refused."""
    if _HELD[0]:
        return "wait"
    chosen = os.environ.get("TOOLKIT_COMPILE", "background").strip().lower() or "background"
    if chosen not in MODES:
        raise ValueError(f"TOOLKIT_COMPILE={chosen!r}: expected one of {', '.join(MODES)}")
    return chosen


@contextlib.contextmanager
def waiting() -> Iterator[None]:
    """Within the block every call compiles what it needs before it runs (all threads)."""
    with _SCHEDULER.lock:
        _HELD[0] += 1
    try:
        yield
    finally:
        with _SCHEDULER.lock:
            _HELD[0] -= 1


def _key(dispatcher: Any) -> tuple[str, str]:
    func = dispatcher.py_func
    return str(func.__module__), str(func.__qualname__)


def attach(dispatcher: Any, folder: Path | None, parallel: bool = False) -> None:
    """Route ``dispatcher``'s uncompiled calls through this module (``folder``: the cache
    folder the kernels are kept in; None: compiled in memory, calls wait). A ``parallel``
    one is only registered: :func:`serial_for_now` decides for it (module doc)."""
    if folder is None or not hasattr(dispatcher, "py_func"):  # NUMBA_DISABLE_JIT: a function
        return  # nothing a background process could hand over
    key = _key(dispatcher)
    if "<locals>" in key[1]:
        return
    _REGISTRY.setdefault(key, (dispatcher, folder))
    if not parallel:
        original = dispatcher._compile_for_args
        dispatcher._compile_for_args = functools.partial(_route, dispatcher, original, folder)


def _types(dispatcher: Any, args: tuple[Any, ...]) -> tuple[Any, ...] | None:
    """numba's types of ``args`` as ``dispatcher`` reads them (None: one it does not take)."""
    from numba.core.dispatcher import OmittedArg
    from numba.core.types import Omitted

    omitted: Callable[[Any], Any] = Omitted
    try:
        return tuple(
            omitted(a.value) if isinstance(a, OmittedArg) else dispatcher.typeof_pyval(a)
            for a in args
        )
    except Exception:  # numba's own error, from its own path
        return None


def serial_for_now(parallel: Any, args: tuple[Any, ...]) -> bool:
    """True if a batch for the ``parallel`` twin should run on the serial one (compiled, or
    as Python) while a background process compiles the parallel one: it is compiled
    neither here nor in the cache, and the batch (``args[0]``'s rows) is at most
    :data:`PYTHON_ROWS`."""
    if not hasattr(parallel, "py_func") or parallel.overloads or mode() == "wait":
        return False  # a plain function (NUMBA_DISABLE_JIT), or compiled here already
    registered = _REGISTRY.get(_key(parallel))
    rows = getattr(args[0], "shape", (PYTHON_ROWS + 1,)) if args else (PYTHON_ROWS + 1,)
    if registered is None or not rows or rows[0] > PYTHON_ROWS:
        return False
    sig = _types(parallel, args)
    return sig is not None and _SCHEDULER.state(parallel, sig, registered[1]) == "pending"


def _route(
    dispatcher: Any, original: Callable[..., Any], folder: Path, *args: Any, **kws: Any
) -> Any:
    """numba's dispatcher asks this for the callable to run on ``args`` when it holds no
    machine code for their types (it then calls it with ``args``)."""
    if kws:  # numba folds keywords into ``args``; anything else is its own to answer
        return original(*args, **kws)
    if getattr(_LOCAL, "depth", 0):  # inside a kernel running as Python: stay there
        from numba.core.dispatcher import OmittedArg

        if any(isinstance(a, OmittedArg) for a in args):
            return lambda *given: dispatcher.py_func(*_values(given))
        return dispatcher.py_func
    if mode() == "wait":
        return original(*args)
    from numba.core.dispatcher import OmittedArg
    from numba.core.types import Omitted

    try:
        omitted: Callable[[Any], Any] = Omitted
        sig = tuple(
            omitted(a.value) if isinstance(a, OmittedArg) else dispatcher.typeof_pyval(a)
            for a in args
        )
    except Exception:  # a type numba does not take: its own error, from its own path
        return original(*args)
    if _SCHEDULER.state(dispatcher, sig, folder) != "pending":
        return original(*args)
    return functools.partial(_as_python, dispatcher, original, sig)


def _plain(value: Any) -> Any:
    """numpy scalars as the Python ones a compiled kernel returns (tuples item by item)."""
    if isinstance(value, tuple):
        return tuple(_plain(v) for v in value)
    return value.item() if isinstance(value, np.generic) else value


def _values(args: tuple[Any, ...]) -> list[Any]:
    """``args`` with numba's stand-ins for omitted arguments replaced by their defaults."""
    from numba.core.dispatcher import OmittedArg

    return [a.value if isinstance(a, OmittedArg) else a for a in args]


def _as_python(dispatcher: Any, original: Callable[..., Any], sig: Any, *args: Any) -> Any:
    """Run the kernel's Python body; where Python's semantics part from numba's, compile."""
    values = _values(args)
    _LOCAL.depth = getattr(_LOCAL, "depth", 0) + 1
    try:
        with np.errstate(all="ignore"):
            return _plain(dispatcher.py_func(*values))
    except (ArithmeticError, ValueError, TypeError, IndexError, AttributeError):
        pass  # Python raised where the compiled kernel computes (module doc)
    finally:
        _LOCAL.depth -= 1
    _SCHEDULER.forget(dispatcher, sig)
    return original(*args)(*args)


def _cached(dispatcher: Any, sig: tuple[Any, ...]) -> bool:
    """True if the cache holds ``dispatcher``'s machine code for ``sig`` (valid for today's
    sources: a stale index reads as empty)."""
    cache = getattr(dispatcher, "_cache", None)
    try:
        key = cache._index_key(sig, dispatcher.targetctx.codegen())  # type: ignore[union-attr]
        return key in cache._cache_file._load_index()  # type: ignore[union-attr]
    except Exception:  # an unreadable index: numba's own load decides
        return False


_WORKER = (
    "import sys; sys.path.insert(0, {root!r}); "
    "from toolkit.common import background; background.main()"
)
_NOTICE = (
    "the toolkit's kernels compile at their first use after an installation: until a "
    "background process has compiled the ones this program uses (about half a minute to "
    "two minutes, once; cached in %s), they run as Python, slower; `toolkit warmup` "
    "compiles every kernel ahead"
)


class _Scheduler:
    """The kernels waiting for a background process, and that process."""

    def __init__(self) -> None:
        self.lock = threading.RLock()
        self.pid = os.getpid()
        self.pending: dict[tuple[Any, ...], tuple[Any, tuple[Any, ...]]] = {}
        self.queue: list[tuple[Any, ...]] = []
        self.tried: set[tuple[Any, ...]] = set()
        self.failed: set[tuple[Any, ...]] = set()
        self.worker: tuple[subprocess.Popen[bytes], list[tuple[Any, ...]]] | None = None
        self.told = False

    def state(self, dispatcher: Any, sig: tuple[Any, ...], folder: Path) -> str:
        """``"pending"`` (run as Python), or ``"ready"``/``"failed"`` (numba loads or
        compiles it here)."""
        key = (*_key(dispatcher), sig)
        with self.lock:
            if self.pid != os.getpid():  # forked: the background process is the parent's
                self.pid, self.worker, self.queue = os.getpid(), None, []
                self.pending.clear()
            self._poll(folder)
            if key in self.failed:
                return "failed"
            if key in self.pending:
                return "pending"
            if _cached(dispatcher, sig):
                return "ready"
            if key in self.tried:  # compiled in the background, yet not in the cache
                self.failed.add(key)
                return "failed"
            self.pending[key] = (dispatcher, sig)
            self.queue.append(key)
            self._poll(folder)
            self._tell(folder)
            return "pending" if key in self.pending else "failed"

    def forget(self, dispatcher: Any, sig: tuple[Any, ...]) -> None:
        """``sig`` compiles in this process from now on."""
        with self.lock:
            self.failed.add((*_key(dispatcher), sig))

    def _poll(self, folder: Path) -> None:
        """Collect a finished background process; start one for the queue."""
        if self.worker is not None and self.worker[0].poll() is not None:
            process, keys = self.worker
            self.worker = None
            for key in keys:
                self.pending.pop(key, None)
                (self.tried if process.returncode == 0 else self.failed).add(key)
        if self.worker is None and self.queue:
            keys, self.queue = self.queue, []
            jobs = [(k[0], k[1], self.pending[k][1]) for k in keys]
            try:
                self.worker = (_start(jobs, folder), keys)
            except (OSError, ValueError, pickle.PicklingError):
                for key in keys:
                    self.pending.pop(key, None)
                    self.failed.add(key)

    def _tell(self, folder: Path) -> None:
        if not self.told:
            self.told = True
            logging.getLogger("toolkit.compile").warning(_NOTICE, folder)


_SCHEDULER = _Scheduler()


def _start(jobs: list[tuple[str, str, Any]], folder: Path) -> subprocess.Popen[bytes]:
    """A background process compiling ``jobs`` into ``folder`` (module doc: Safe)."""
    payload = pickle.dumps(jobs)
    root = str(Path(__file__).resolve().parents[2])
    env = {**os.environ, "TOOLKIT_COMPILE": "wait", "NUMBA_CACHE_DIR": str(folder)}
    process = subprocess.Popen(
        [sys.executable, "-c", _WORKER.format(root=root)],
        stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        cwd=str(folder), env=env, close_fds=True, start_new_session=True,
    )  # fmt: skip
    assert process.stdin is not None
    try:
        process.stdin.write(payload)
    finally:
        process.stdin.close()
    return process


def pending() -> int:
    """How many kernel signatures of this process wait for a background process."""
    with _SCHEDULER.lock:
        return len(_SCHEDULER.pending)


def main() -> None:
    """The background process: compile the jobs read from standard input (pickled
    (module, qualified name, types) triples of the toolkit's own kernels) into the cache;
    exit 1 if any failed."""
    with contextlib.suppress(OSError, AttributeError):
        os.nice(5)  # the user's own process first
    jobs = pickle.load(sys.stdin.buffer)
    failed = 0
    with _one_at_a_time(Path(os.environ.get("NUMBA_CACHE_DIR") or ".")):
        for module, qualname, sig in jobs:
            if not str(module).startswith("toolkit."):
                failed += 1
                continue
            try:
                importlib.import_module(module)
                dispatcher, _ = _REGISTRY[(module, qualname)]
                dispatcher.compile(sig)  # loaded instead where another process compiled it
            except Exception:  # reported by the exit status; the caller compiles it itself
                failed += 1
    sys.exit(1 if failed else 0)


LOCK_NAME = ".background.lock"
"""The file in the cache folder a background process holds (``flock``) while it compiles."""


@contextlib.contextmanager
def _one_at_a_time(folder: Path) -> Iterator[None]:
    """Hold the cache folder's lock: one background process compiles at a time, so the
    processes of a fork pool (or scripts started together) do not compile the same kernels
    side by side; the later ones then find most of them in the cache and load them. Where
    the lock cannot be taken (no ``fcntl``, a folder that cannot be written) nothing waits."""
    try:
        import fcntl

        handle = open(folder / LOCK_NAME, "ab")  # held for the block
    except (ImportError, OSError):
        yield
        return
    try:
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield
    finally:
        handle.close()  # releases the lock
