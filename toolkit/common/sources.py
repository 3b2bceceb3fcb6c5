"""Digests of source files: what a compiled kernel was made from.

A compiled kernel holds the machine code of every kernel it calls and the constants it
reads, from any module; numba's cache knows only the kernel's own file, by its time stamp.
A kernel's cache entry is therefore stamped with :func:`kernel_digest`: the bytes of the
files of the kernel and of every kernel it calls, directly or through others, and the
values of the constants they read from other modules, found by following the globals its
code reads (a module's attributes it names, closures and defaults too). A change to a file
no kernel it reaches is in (the compiler's set-up, the robot's face, another concept's
kernels) recompiles nothing; a change to its own file or a callee's recompiles it; an
installation of the same sources elsewhere or anew (new time stamps) loads what is cached.

:func:`module_digest` is the coarser digest by imports (kept for what is not a kernel:
the sphere covers' store): the bytes of every package file a module imports (an import
read from the files' text, ``from .x import y`` and ``import toolkit.x`` alike, at any
indentation; a name imported from a package counts the package's ``__init__`` and, where
it is a submodule, that file). :func:`sources_digest` covers every file of the package.
"""

from __future__ import annotations

import builtins
import dis
import hashlib
import re
import threading
import types
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["kernel_digest", "kernel_sources", "module_digest", "read_file", "sources_digest"]

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


_EXTERNAL = ("numpy", "math", "cmath", "numba", "operator", "builtins", "llvmlite")
"""Modules whose functions a kernel calls as numba's own (their versions, not their files,
make the machine code: numba's is in the cache folder's name)."""
_FILES: dict[str, bytes] = {}


def read_file(name: str) -> bytes | None:
    """The bytes of the file at ``name`` as this process first read them (None: it cannot
    be read). A kernel's file is read when the kernel is made (:mod:`toolkit.common.
    compiler`), when Python has just read its code."""
    with _LOCK:
        if name not in _FILES:
            try:
                _FILES[name] = Path(name).read_bytes()
            except OSError:
                return None
        return _FILES[name]


def _codes(code: types.CodeType) -> list[types.CodeType]:
    """``code`` and every code object nested in it (its inner functions' and lambdas')."""
    found, todo = [], [code]
    while todo:
        c = todo.pop()
        found.append(c)
        todo.extend(k for k in c.co_consts if isinstance(k, types.CodeType))
    return found


_READ: dict[types.CodeType, list[tuple[str, Any]] | None] = {}


def _read_once(func: types.FunctionType) -> list[tuple[str, Any]] | None:
    """:func:`_read`, once per process for a function's code (a kernel's digest follows
    the callees every other kernel's does: 6 ms a kernel, read afresh each time)."""
    if func.__closure__ or func.__defaults__:
        return _read(func)  # its values are its own, not its code's
    with _LOCK:
        if func.__code__ in _READ:
            return _READ[func.__code__]
    found = _read(func)
    with _LOCK:
        return _READ.setdefault(func.__code__, found)


def _read(func: types.FunctionType) -> list[tuple[str, Any]] | None:
    """(name, object) of every global ``func``'s code reads (a module's attributes named
    in the code, with the module's name before them), its closures' and its defaults'
    values; None where a global it reads does not exist (numba refuses it too)."""
    missing = object()
    read: list[tuple[str, Any]] = []
    for code in _codes(func.__code__):
        for ins in dis.get_instructions(code):
            if ins.opname not in ("LOAD_GLOBAL", "LOAD_NAME"):
                continue
            name = str(ins.argval)
            obj = func.__globals__.get(name, getattr(builtins, name, missing))
            if obj is missing:
                return None
            read.append((name, obj))
            if isinstance(obj, types.ModuleType):
                read.extend((f"{name}.{attr}", getattr(obj, attr)) for attr in code.co_names
                            if hasattr(obj, attr) and not attr.startswith("__"))  # fmt: skip
    for k, cell in enumerate(func.__closure__ or ()):
        try:
            read.append((f"<closure {k}>", cell.cell_contents))
        except ValueError:  # a cell not filled yet: nothing numba could read either
            return None
    read.extend((f"<default {k}>", v) for k, v in enumerate(func.__defaults__ or ()))
    return read


def _value(obj: Any) -> str | None:
    """A constant's exact text (None for anything that is not one)."""
    if obj is None or isinstance(obj, (bool, int, float, complex, str, bytes, np.generic)):
        return f"{type(obj).__name__}:{obj!r}"
    if isinstance(obj, tuple):
        items = [_value(v) for v in obj]
        return None if None in items else f"tuple:({','.join(items)})"  # type: ignore[arg-type]
    if isinstance(obj, np.ndarray):
        data = hashlib.sha256(np.ascontiguousarray(obj).tobytes()).hexdigest()
        return f"array:{obj.dtype.str}:{obj.shape}:{data}"
    return None


def kernel_sources(func: Any) -> tuple[list[str], list[str]] | None:
    """What the kernel ``func`` (a Python function, or a numba dispatcher's ``py_func``)
    compiles from (module doc): the files of it and of every function it reaches through
    the globals it reads (paths within the package, else whole), and the values of the
    constants among those globals (classes and numba's, numpy's and math's functions by
    name), each list sorted. None where that cannot be followed (a global that does not
    exist, a file that cannot be read)."""
    func = getattr(func, "py_func", func)
    files: set[str] = set()
    values: set[str] = set()
    seen: set[int] = set()
    todo = [func]
    while todo:
        f = todo.pop()
        if id(f) in seen:
            continue
        seen.add(id(f))
        read = _read_once(f)
        if read is None or read_file(f.__code__.co_filename) is None:
            return None
        files.add(f.__code__.co_filename)
        for name, obj in read:
            target = getattr(obj, "py_func", obj)  # a numba dispatcher: its function
            if isinstance(target, types.FunctionType):
                module = str(getattr(target, "__module__", "") or "")
                if module.split(".")[0] not in _EXTERNAL:
                    todo.append(target)
                    continue
            if isinstance(obj, types.ModuleType):
                continue  # its attributes the code names are read beside it
            text = _value(obj)
            if text is None:  # a class, numba's or numpy's function: by its name
                kind = obj if isinstance(obj, type) else type(obj)
                label = getattr(obj, "__name__", "")
                text = f"{kind.__module__}.{kind.__qualname__}:{label}"
            values.add(f"{f.__qualname__}:{name}={text}")
    return sorted(_label(f) for f in files), sorted(values)


def kernel_digest(func: Any) -> str | None:
    """SHA-256 (16 hex digits) of :func:`kernel_sources`: each file's name and its bytes as
    this process first read them, and each constant's value; None where those cannot be
    followed (the caller falls back to a coarser digest)."""
    found = kernel_sources(func)
    if found is None:
        return None
    files, values = found
    digest = hashlib.sha256()
    for name in files:
        data = read_file(str(ROOT / name) if not Path(name).is_absolute() else name)
        digest.update(name.encode() + b"\0")
        digest.update(len(data or b"").to_bytes(8, "little") + (data or b""))
    for text in values:
        digest.update(text.encode() + b"\0")
    return digest.hexdigest()[:16]


def _label(name: str) -> str:
    """A file's name in a digest: its path within the package (the same wherever it is
    installed), else its whole path."""
    path = Path(name).resolve()
    return path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else str(path)
