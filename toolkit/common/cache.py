"""An on-disk cache of generated text files (rendered URDFs) that nobody can poison.

* **Verified before use**: each entry ``NAME`` has a sidecar ``NAME.sha256`` holding the
  SHA-256 of the text the toolkit generated. In a private folder (below) an entry is used
  when the file, read without following symbolic links, matches its sidecar; in any other
  folder the text is generated again and compared. Anything else (truncated, edited,
  planted, a symlink) is rewritten.
* **Written atomically**: a temporary file in the same folder, flushed and fsynced, then
  renamed over the entry (the rename replaces a symlink, never writes through it).
* **Private folders only**: the preferred folder is ``$TOOLKIT_CACHE_DIR`` or
  ``$XDG_CACHE_HOME/manipulator-toolkit`` (``~/.cache/manipulator-toolkit``), created
  0700. When it cannot be written, the fallback is ``$TMPDIR/manipulator-toolkit-UID``,
  used only if it is a real folder owned by this user and closed to others (0700);
  otherwise a fresh private folder from ``tempfile.mkdtemp`` serves this process.
* A read-only cache still works: entries that verify are read from it; missing ones are
  written to the fallback.
"""

from __future__ import annotations

import hashlib
import os
import stat
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path

from ..errors import CacheError

# store() is the renderer's; is_private the engine's; write_atomic the viewer's save_html;
# kept_bytes the covers store's (toolkit.collision.stored)
__all__ = ["cache_dir", "fallback_dir"]

_LOCK = threading.Lock()
_PROCESS_DIR: list[Path] = []  # the mkdtemp folder of this process, made at most once


def cache_dir() -> Path:
    """The preferred cache folder (``$TOOLKIT_CACHE_DIR``, else the XDG cache folder)."""
    env = os.environ.get("TOOLKIT_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "manipulator-toolkit"


def is_private(folder: Path) -> bool:
    """True if ``folder`` is a real folder (not a link) of this user, closed to others."""
    try:
        info = os.lstat(folder)
    except OSError:
        return False
    mine = not hasattr(os, "getuid") or info.st_uid == os.getuid()
    return stat.S_ISDIR(info.st_mode) and mine and not info.st_mode & 0o077


def fallback_dir() -> Path:
    """A private folder for entries the preferred folder cannot take (see the module doc)."""
    uid = os.getuid() if hasattr(os, "getuid") else "user"
    folder = Path(tempfile.gettempdir()) / f"manipulator-toolkit-{uid}"
    try:
        folder.mkdir(mode=0o700, exist_ok=True)
    except OSError:
        pass
    if is_private(folder):
        return folder
    with _LOCK:  # someone else owns it, or it is open to others: a folder of our own
        if not _PROCESS_DIR:
            try:
                _PROCESS_DIR.append(Path(tempfile.mkdtemp(prefix="manipulator-toolkit-")))
            except OSError as exc:
                raise CacheError(f"no private cache folder could be made: {exc}") from exc
        return _PROCESS_DIR[0]


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _read(path: Path) -> bytes | None:
    """The bytes of a regular file, without following a symbolic link; None otherwise."""
    flags = os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except OSError:
        return None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return None
        chunks = []
        while chunk := os.read(fd, 1 << 20):
            chunks.append(chunk)
        return b"".join(chunks)
    finally:
        os.close(fd)


def write_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a private temporary file in its folder, renamed
    over it: a reader sees the old file or the whole new one, never a part; a symbolic
    link at ``path`` is replaced, not followed."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _valid(path: Path, expected: str) -> bool:
    """The entry exists as a regular file whose bytes and sidecar both match ``expected``."""
    data, side = _read(path), _read(path.with_name(path.name + ".sha256"))
    return data is not None and side is not None and _digest(data) == side.decode() == expected


def _consistent(path: Path) -> bytes | None:
    """The entry's bytes where it is a regular file matching its sidecar (trusted in a
    private folder); None otherwise."""
    data, side = _read(path), _read(path.with_name(path.name + ".sha256"))
    return (
        data if data is not None and side is not None and _digest(data) == side.decode() else None
    )


def store(filename: str, make_text: Callable[[], str]) -> Path:
    """A verified cache file holding the text ``make_text()`` returns.

    In a private folder a self-consistent entry is reused without calling ``make_text``;
    otherwise the text is made and the entry reused only if it matches, else (re)written.
    Raises :class:`~toolkit.errors.CacheError` only when no private folder can take it.
    """
    text: str | None = None
    for choice in ("preferred", "fallback"):
        folder = cache_dir() if choice == "preferred" else fallback_dir()
        path = folder / filename
        if is_private(folder) and _consistent(path) is not None:
            return path
        text = make_text() if text is None else text
        data = text.encode("utf-8")
        expected = _digest(data)
        if _valid(path, expected):
            return path
        try:
            folder.mkdir(mode=0o700, parents=True, exist_ok=True)
            write_atomic(path, data)
            write_atomic(path.with_name(filename + ".sha256"), expected.encode())
        except OSError:
            continue  # a read-only folder: the private fallback takes the entry
        if _valid(path, expected):
            return path
    raise CacheError(f"could not write a verified cache file {filename!r} to any cache folder")


def kept_bytes(filename: str, make: Callable[[], bytes]) -> bytes:
    """The bytes of a cache entry ``filename`` of a private folder (the preferred one, else
    the fallback) where it matches its sidecar, else ``make()``'s, written there for the
    next process (where a folder takes it; the bytes are returned whatever happens to the
    writing). An entry of a folder others can write is never read: its bytes are made."""
    for choice in ("preferred", "fallback"):
        try:
            folder = cache_dir() if choice == "preferred" else fallback_dir()
        except CacheError:
            continue
        kept = _consistent(folder / filename) if is_private(folder) else None
        if kept is not None:
            return kept
    data = make()
    for choice in ("preferred", "fallback"):
        try:
            folder = cache_dir() if choice == "preferred" else fallback_dir()
            folder.mkdir(mode=0o700, parents=True, exist_ok=True)
            if not is_private(folder):
                continue
            path = folder / filename
            write_atomic(path, data)
            write_atomic(path.with_name(filename + ".sha256"), _digest(data).encode())
            break
        except (OSError, CacheError):
            continue  # a read-only folder: the next one, or none (made each process)
    return data
