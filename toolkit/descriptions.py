"""Robot descriptions users have: URDF files, URDF text, and xacro with ROS packages.

* ``$(find pkg)`` in xacro and ``package://pkg/...`` in the URDF resolve through, in order:
  the ``package_dirs`` given (folders holding packages, or a {name: folder} map), the
  folders of ``$ROS_PACKAGE_PATH``, and the folders met walking up from the file (a folder
  whose ``package.xml`` names the package, a sibling folder of that name with one, or a
  folder of that name holding the file, ``package.xml`` or not).
  A package found nowhere raises :class:`~toolkit.errors.ModelLoadError` naming it and the
  places searched.
* Rendered and inline URDFs go to the verified cache (:mod:`toolkit.cache`), keyed by their
  content, so that every robot keeps a file path (the viewer loads its meshes from it).

Xacro evaluates ``${...}`` expressions as Python: render only files you trust.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

from .cache import store
from .errors import InvalidParameterError, ModelLoadError
from .render import run_xacro

__all__ = ["PackageResolver", "urdf_source"]

_PACKAGE_URI = re.compile(r"package://([^/\s\"'<>]+)/")
_NAME = re.compile(r"<name>\s*([^<\s]+)\s*</name>")


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

    def _candidates(self, pkg: str) -> list[tuple[str, Path]]:
        out = []
        if pkg in self.named:
            out.append(("package_dirs map", self.named[pkg]))
        for root in self.roots:
            out += [("package_dirs", root / pkg), ("package_dirs", root)]
        for root in self.env_roots:
            out += [("ROS_PACKAGE_PATH", root / pkg), ("ROS_PACKAGE_PATH", root)]
        if self.origin is not None:
            for parent in self.origin.resolve().parents:
                out += [("upward search", parent), ("upward search", parent / pkg)]
        return out

    def find(self, pkg: str) -> Path:
        """The folder of package ``pkg``."""
        searched = []
        origin = self.origin.resolve() if self.origin is not None else None
        for how, folder in self._candidates(pkg):
            inside = origin is not None and folder in origin.parents
            if how == "package_dirs map":
                if folder.is_dir():
                    return folder
            elif _package_name(folder) == pkg:
                return folder
            elif folder.name == pkg and folder.is_dir() and (how != "upward search" or inside):
                return folder  # a package folder without package.xml
            searched.append(f"{folder} ({how})")
        unique = list(dict.fromkeys(searched))
        places = "; ".join(unique[:8]) or "no folder (give package_dirs)"
        if len(unique) > 8:
            places += f"; ... ({len(unique) - 8} more folders up to /)"
        raise ModelLoadError(
            f"package {pkg!r} not found; searched: {places}. Pass package_dirs=[...] "
            "(folders holding packages) or set ROS_PACKAGE_PATH"
        )

    def absolute_uris(self, text: str) -> str:
        """``package://pkg/...`` rewritten to absolute paths where the package is found."""

        def replace(match: re.Match[str]) -> str:
            try:
                return str(self.find(match.group(1))) + "/"
            except ModelLoadError:
                return match.group(0)  # a mesh we cannot find: the viewer says so later

        return _PACKAGE_URI.sub(replace, text)


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
        text, name = source, "urdf"
    else:
        path = Path(source)
        if not path.is_file():
            raise ModelLoadError(f"URDF file not found: {path}")
        resolver = PackageResolver(package_dirs, path)
        name = path.name.split(".")[0]
        if path.suffix == ".xacro" or mappings:
            text = run_xacro(path, mappings, resolver.find)
        else:
            text = path.read_text(encoding="utf-8")
            if not _PACKAGE_URI.search(text):
                return path, text, name  # a plain URDF the resolver leaves as it is
    text = resolver.absolute_uris(text)
    digest = hashlib.sha256(text.encode("utf-8")).hexdigest()
    return store(f"{name}-{digest[:20]}.urdf", lambda: text), text, name


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
