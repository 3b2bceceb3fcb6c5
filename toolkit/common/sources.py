"""Digests of the package's own source files: what a compiled kernel was made from.

A compiled kernel holds the machine code of every kernel it calls and the constants it
reads, from any module it imports; numba's cache knows only the kernel's own file. A
kernel's cache entry is therefore stamped with :func:`module_digest` of its module: the
bytes of every package file that module imports, directly or through others (an import
read from the files' text, ``from .x import y`` and ``import toolkit.x`` alike, at any
indentation; a name imported from a package counts the package's ``__init__`` and, where
it is a submodule, that file). A change to a file no kernel module imports (the robot's
face, the CLI, the docs' generators) recompiles nothing; a change to a kernel's file, or to
one it imports, recompiles it and its callers' modules, which import it.
:func:`sources_digest` covers every file (a module outside the package: a user's kernel).
"""

from __future__ import annotations

import hashlib
import re
import threading
from pathlib import Path

__all__ = ["module_digest", "sources_digest"]

ROOT = Path(__file__).resolve().parent.parent
"""The toolkit package's folder."""

_IMPORT = re.compile(
    r"^[ \t]*from[ \t]+(?P<dots>\.*)(?P<name>[\w.]*)[ \t]+import[ \t]+(?P<names>\([^)]*\)|[^\n#]*)"
    r"|^[ \t]*import[ \t]+(?P<plain>[\w.]+(?:[ \t]*,[ \t]*[\w.]+)*)",
    re.MULTILINE,
)
_LOCK = threading.Lock()
_GRAPHS: dict[Path, dict[Path, tuple[bytes, set[Path]]]] = {}


def _file(root: Path, parts: list[str]) -> Path | None:
    """The file of module ``parts`` under ``root`` (a package's ``__init__``), or None."""
    if not parts or not all(p.isidentifier() for p in parts):
        return None
    path = root.joinpath(*parts)
    for candidate in (path / "__init__.py", path.with_suffix(".py")):
        if candidate.is_file():
            return candidate
    return None


def _imports(root: Path, path: Path, text: str) -> set[Path]:
    """The package files that the module at ``path`` imports (module doc)."""
    package = list(path.relative_to(root).parent.parts)
    found: set[Path] = set()
    for match in _IMPORT.finditer(text):
        if match["plain"]:
            modules = [m.strip().split(".") for m in match["plain"].split(",")]
            targets = [m[1:] for m in modules if m[0] == root.name]
            found.update(f for t in targets if (f := _file(root, t)) is not None)
            continue
        dots, name = match["dots"], match["name"]
        if dots:
            base = package[: len(package) - (len(dots) - 1)] if len(dots) > 1 else package
        elif name.split(".")[0] == root.name:
            base, name = [], name.partition(".")[2]
        else:
            continue  # another package's
        parts = base + (name.split(".") if name else [])
        module = _file(root, parts) if parts else root / "__init__.py"
        if module is not None and module.is_file():
            found.add(module)
        names = match["names"].strip("()").replace("\n", " ")
        for item in names.split(","):
            leaf = item.split(" as ")[0].strip()
            sub = _file(root, [*parts, leaf]) if leaf else None
            if sub is not None:
                found.add(sub)
    return found


def _graph(root: Path) -> dict[Path, tuple[bytes, set[Path]]]:
    """Per ``.py`` file under ``root``: its bytes and the package files it imports (read
    once per process and root)."""
    with _LOCK:
        if root not in _GRAPHS:
            files = {p: p.read_bytes() for p in sorted(root.rglob("*.py"))}
            _GRAPHS[root] = {
                p: (data, _imports(root, p, data.decode("utf-8", "replace")))
                for p, data in files.items()
            }
        return _GRAPHS[root]


def _digest(root: Path, paths: list[Path], graph: dict[Path, tuple[bytes, set[Path]]]) -> str:
    digest = hashlib.sha256()
    for path in sorted(paths):
        data = graph[path][0]
        digest.update(path.relative_to(root).as_posix().encode() + b"\0")
        digest.update(len(data).to_bytes(8, "little") + data)
    return digest.hexdigest()[:16]


def sources_digest(root: Path | None = None) -> str:
    """SHA-256 (16 hex digits) of every ``.py`` file under ``root`` (the toolkit package by
    default): each one's path within it and its bytes, in sorted order (read now)."""
    root = ROOT if root is None else root.resolve()
    graph = {p: (p.read_bytes(), set[Path]()) for p in sorted(root.rglob("*.py"))}
    return _digest(root, list(graph), graph)


def module_digest(module: str, root: Path | None = None) -> str | None:
    """SHA-256 (16 hex digits) of the files of the package module ``module`` (dotted, as
    ``func.__module__``) and of every package file it imports, directly or through others
    (module doc), as the files stood when this process first read them; None for a module
    outside the package."""
    root = ROOT if root is None else root.resolve()
    head, _, rest = module.partition(".")
    start = _file(root, rest.split(".")) if head == root.name and rest else None
    graph = _graph(root)
    if start is None or start not in graph:
        return None
    seen, todo = {start}, [start]
    while todo:
        for other in graph[todo.pop()][1]:
            if other not in seen and other in graph:
                seen.add(other)
                todo.append(other)
    return _digest(root, list(seen), graph)
