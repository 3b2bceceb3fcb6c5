"""Robot descriptions users have: URDF files, URDF text, and xacro with ROS packages.

* ``$(find pkg)`` in xacro and ``package://pkg/...`` in the URDF resolve through, in order:
  the ``package_dirs`` given (folders holding packages, or a {name: folder} map), the
  folders of ``$ROS_PACKAGE_PATH``, and the folders met walking up from the file (a folder
  whose ``package.xml`` names the package, or a folder named like the package: one holding
  the file, or a sibling of one of the file's folders, ``package.xml`` or not).
* **The upward search trusts only your own folders.** xacro runs a package's ``${...}``
  expressions as Python, so a package planted by another user must never be picked up.
  The walk up from the file stops at the first folder that is owned by someone other than
  you or root, or that others can write (``/tmp``: anyone may create ``/tmp/<pkg>``), and
  it never climbs above your own folders (past the last folder you own) or your home; a
  candidate package folder must pass the same test. The error of a package not found says
  where the search stopped and why.
  A package found nowhere raises :class:`~toolkit.errors.ModelLoadError` naming it, the
  places searched, and the ``package_dirs={name: folder}`` form that fixes it.
* Rendered and inline URDFs go to the verified cache (:mod:`toolkit.common.cache`), keyed by their
  content, so that every robot keeps a file path (the viewer loads its meshes from it).

Xacro evaluates ``${...}`` expressions as Python: render only files you trust.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

from ..common import cache
from ..errors import InvalidParameterError, ModelLoadError
from .render import run_xacro

__all__ = [
    "MAX_FILE_BYTES",
    "MAX_LINKS",
    "PackageResolver",
    "check_size",
    "read_description",
    "relative_meshes",
    "urdf_source",
]

MAX_LINKS = 1000
"""The most links a description may have (humanoids have about 100; Pinocchio's parser
recurses once per level and crashes the process near 4,000)."""
_LINK_TAG = re.compile(r"<link\b")

MAX_FILE_BYTES = 64 * 2**20
"""The largest description file read (64 MiB; the largest real URDF we know is ~2 MiB)."""
_ENCODING = re.compile(rb"""^\s*<\?xml[^>]*encoding=["']([A-Za-z0-9._\-]+)["']""")
_ROBOT_NAME = re.compile(r"""<robot\b[^>]*\bname\s*=\s*["']([^"']+)["']""")

_PACKAGE_URI = re.compile(r"package://([^/\s\"'<>]+)/")
_MESH_FILE = re.compile(r"""(<mesh\b[^>]*?\bfilename\s*=\s*)(["'])([^"']*)\2""")
_NAME = re.compile(r"<name>\s*([^<\s]+)\s*</name>")


def untrusted(folder: Path) -> str | None:
    """Why ``folder`` may hold files planted by another user, or None if it cannot: it must
    be owned by this user or root and closed to writes by group and others."""
    try:
        info = os.stat(folder)
    except OSError as exc:
        return f"cannot be read ({exc.strerror})"
    if hasattr(os, "getuid") and info.st_uid not in (os.getuid(), 0):
        return f"owned by another user (uid {info.st_uid})"
    if info.st_mode & 0o022:
        return "writable by others"
    return None


def _upward(origin: Path) -> tuple[list[Path], str]:
    """The folders above ``origin`` the upward search may use, and where it stopped."""
    uid = os.getuid() if hasattr(os, "getuid") else None
    try:
        home: Path | None = Path.home().resolve()
    except (RuntimeError, KeyError):  # no home: no home bound
        home = None
    out: list[Path] = []
    own = False
    for parent in origin.resolve().parents:
        why = untrusted(parent)
        if why is None and own and uid is not None and os.stat(parent).st_uid != uid:
            why = "above your own folders"
        if why is not None:
            return out, f"{parent}: {why}"
        own = own or (uid is not None and os.stat(parent).st_uid == uid)
        out.append(parent)
        if parent == home:
            return out, f"{parent}: your home folder"
    return out, ""


def read_description(path: Path) -> str:
    """The text of a URDF/xacro file: at most :data:`MAX_FILE_BYTES`, decoded as its XML
    declaration says (UTF-8 by default, a byte-order mark honoured), leading blank lines
    dropped; a clear :class:`~toolkit.errors.ModelLoadError` otherwise."""
    try:
        size = path.stat().st_size
        if size > MAX_FILE_BYTES:
            raise ModelLoadError(
                f"{path}: {size:,} bytes, more than the {MAX_FILE_BYTES:,} a description may have"
            )
        data = path.read_bytes()
    except OSError as exc:
        raise ModelLoadError(f"cannot read {path}: {exc.strerror or exc}") from None
    declared = _ENCODING.match(data)
    encoding = declared.group(1).decode("ascii") if declared else "utf-8-sig"
    try:
        return data.decode(encoding).lstrip()
    except (LookupError, UnicodeDecodeError) as exc:
        raise ModelLoadError(f"{path}: not readable as {encoding} text ({exc})") from None


def check_size(text: str, where: object) -> None:
    """Refuse URDF text beyond the documented limits before any parser sees it."""
    if len(text) > MAX_FILE_BYTES:
        raise ModelLoadError(
            f"{where}: {len(text):,} characters, more than the {MAX_FILE_BYTES:,} a description "
            "may have"
        )
    links = len(_LINK_TAG.findall(text))
    if links > MAX_LINKS:
        raise ModelLoadError(
            f"{where}: {links:,} links, more than the {MAX_LINKS:,} a description may have"
        )


def robot_name(text: str, default: str = "urdf") -> str:
    """The ``<robot name="...">`` of URDF text (``default`` if none)."""
    found = _ROBOT_NAME.search(text)
    return found.group(1) if found else default


def _package_name(folder: Path) -> str | None:
    try:
        found = _NAME.search((folder / "package.xml").read_text(encoding="utf-8"))
    except OSError:
        return None
    return found.group(1) if found else None


class PackageResolver:
    """Where ROS packages live, for ``$(find pkg)`` and ``package://pkg/`` (module doc)."""

    def __init__(
        self,
        package_dirs: Sequence[str | Path] | Mapping[str, str | Path] | None,
        origin: Path | None,
    ) -> None:
        self.named: dict[str, Path] = {}
        self.roots: list[Path] = []
        if isinstance(package_dirs, Mapping):
            for key, value in package_dirs.items():
                if not isinstance(key, str) or not isinstance(value, str | Path):
                    raise InvalidParameterError(
                        "package_dirs as a map takes {package name: folder}, got "
                        f"{key!r:.60}: {value!r:.60}"
                    )
            self.named = {str(k): Path(v) for k, v in package_dirs.items()}
        elif package_dirs is not None:
            if isinstance(package_dirs, str | Path):
                package_dirs = [package_dirs]
            try:
                self.roots = [Path(p) for p in package_dirs]
            except TypeError:
                raise InvalidParameterError(
                    "package_dirs must be folders or a {name: folder} map, "
                    f"got {package_dirs!r:.100}"
                ) from None
        env = os.environ.get("ROS_PACKAGE_PATH", "")
        self.env_roots = [Path(p) for p in env.split(os.pathsep) if p]
        self.origin = origin

    def _candidates(self, pkg: str) -> tuple[list[tuple[str, Path]], str]:
        out = []
        if pkg in self.named:
            out.append(("package_dirs map", self.named[pkg]))
        for root in self.roots:
            out += [("package_dirs", root / pkg), ("package_dirs", root)]
        for root in self.env_roots:
            out += [("ROS_PACKAGE_PATH", root / pkg), ("ROS_PACKAGE_PATH", root)]
        stop = ""
        if self.origin is not None:
            parents, stop = _upward(self.origin)
            for parent in parents:
                out += [("upward search", parent), ("upward search", parent / pkg)]
        return out, stop

    def find(self, pkg: str) -> Path:
        """The folder of package ``pkg``."""
        searched, skipped = [], []
        candidates, stop = self._candidates(pkg)
        for how, folder in candidates:
            if how == "package_dirs map":
                if folder.is_dir():
                    return folder
                searched.append(f"{folder} ({how})")
                continue
            if how == "upward search" and folder.is_dir():
                why = untrusted(folder)
                if why is not None:
                    skipped.append(f"{folder} ({why})")
                    continue
            if _package_name(folder) == pkg:
                return folder
            if folder.name == pkg and folder.is_dir() and how == "upward search":
                return folder  # a package folder without package.xml
            searched.append(f"{folder} ({how})")
        raise ModelLoadError(_not_found(pkg, searched, skipped, stop))

    def absolute_uris(self, text: str) -> str:
        """``package://pkg/...`` rewritten to absolute paths where the package is found."""

        def replace(match: re.Match[str]) -> str:
            try:
                return str(self.find(match.group(1))) + "/"
            except ModelLoadError:
                return match.group(0)  # a mesh we cannot find: the viewer says so later

        return _PACKAGE_URI.sub(replace, text)


def _not_found(pkg: str, searched: list[str], skipped: list[str], stop: str) -> str:
    unique = list(dict.fromkeys(searched))
    places = "; ".join(unique[:8]) or "no folder"
    if len(unique) > 8:
        places += f"; ... ({len(unique) - 8} more)"
    message = f"package {pkg!r} not found; searched: {places}."
    if skipped:
        message += f" Skipped as another user could have planted them: {'; '.join(skipped)}."
    if stop:
        message += f" The upward search stopped at {stop}."
    return message + (
        f" Pass package_dirs={{{pkg!r}: '/path/to/{pkg}'}} (or package_dirs=[folders holding "
        "packages]) or set ROS_PACKAGE_PATH"
    )


def urdf_source(
    source: str | Path,
    package_dirs: Sequence[str | Path] | Mapping[str, str | Path] | None,
    args: Mapping[str, object] | None,
) -> tuple[Path, str, str]:
    """(a URDF file to build from, its text, a default name) for a ``.urdf`` or ``.xacro``
    path, or URDF text."""
    if not isinstance(source, str | Path):
        raise InvalidParameterError(f"source must be a path or URDF text, got {source!r:.100}")
    mappings = _mappings(args)
    if isinstance(source, str) and "<robot" in source:
        resolver = PackageResolver(package_dirs, None)
        text, name = source, robot_name(source)
    else:
        path = Path(source)
        if not path.is_file():
            raise ModelLoadError(f"URDF file not found: {path}")
        resolver = PackageResolver(package_dirs, path)
        name = path.name.split(".")[0]
        rendered = path.suffix == ".xacro" or bool(mappings)
        text = run_xacro(path, mappings, resolver.find) if rendered else read_description(path)
        rooted = relative_meshes(text, path.resolve().parent)
        if not rendered and rooted == text and not _PACKAGE_URI.search(text):
            return path, text, name  # a plain URDF the resolver leaves as it is
        text = rooted
    text = resolver.absolute_uris(text)
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    return cache.store(f"{name}-{digest[:20]}.urdf", lambda: text), text, name


def relative_meshes(text: str, folder: Path) -> str:
    """Mesh file names written relative to the description (``meshes/part.stl``, as many
    exported descriptions have them) made absolute from the description's own ``folder``,
    as ROS tools, yourdfpy and Pinocchio given the folder resolve them (not from the
    working folder). URIs (``package://``, ``file://``) and absolute paths stay as they
    are."""

    def replace(match: re.Match[str]) -> str:
        name = match.group(3)
        if not name or "://" in name or os.path.isabs(name) or name.startswith(("$", "~")):
            return match.group(0)
        absolute = os.path.normpath(folder / name)
        return f"{match.group(1)}{match.group(2)}{absolute}{match.group(2)}"

    return _MESH_FILE.sub(replace, text)


def _mappings(args: Mapping[str, object] | None) -> dict[str, str]:
    if args is None:
        return {}
    if not isinstance(args, Mapping):
        raise InvalidParameterError(f"args must map xacro argument names to values, got {args!r}")
    out = {}
    for key, value in args.items():
        if not isinstance(key, str) or not re.fullmatch(r"[A-Za-z_][\w\-]*", key):
            raise InvalidParameterError(f"xacro argument names are identifiers, got {key!r}")
        if not isinstance(value, str | int | float) or isinstance(value, bool):
            raise InvalidParameterError(f"xacro argument {key!r}: a number or text, got {value!r}")
        out[key] = str(value)
    return out
