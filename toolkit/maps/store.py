"""Zarr stores of maps: one array per result, chunked like the map's tasks, a ``done`` flag
per chunk, and the map's inputs in the group's attributes.

A chunk's arrays are written first, then their SHA-256 digest (in the group's attributes,
``toolkit_digests``), and its flag last, so a run killed at any moment leaves every flagged
chunk complete; ``resume`` recomputes the others. **A damaged store is detected, never
read as data**: a flagged chunk whose arrays no longer match their digest (a deleted
chunk file that reads back as fill values, a chunk copied from another store, corrupt
bytes) is recomputed by ``resume`` and otherwise reported by a
:class:`~toolkit.errors.MapStoreError` naming it. A store whose inputs differ from the
run's (another robot, grid, orientations, seed or toolkit version) is refused, never mixed.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MapStoreError
from .grid import Grid

__all__ = ["Store", "robot_digest", "zarr_available"]


def robot_digest(robot: Any) -> str:
    """What identifies the robot in a store: its URDF text (or model), tip, joints, limits."""
    h = hashlib.sha256()
    if robot.urdf_path is not None and robot.urdf_path.is_file():
        h.update(robot.urdf_path.read_bytes())
    else:
        h.update(repr(robot.model).encode())
    h.update(repr((robot.tip, robot.joints.names, sorted(robot.params.items()))).encode())
    h.update(
        np.ascontiguousarray(robot.joints.lower).tobytes()
        + np.ascontiguousarray(robot.joints.upper).tobytes()
    )
    return h.hexdigest()


def zarr_available() -> bool:
    """True if the optional zarr package can be imported."""
    try:
        import zarr  # noqa: F401
    except ImportError:
        return False
    return True


def _plain(value: Any) -> Any:
    return json.loads(json.dumps(value))


def _claim_folder(folder: Path) -> None:
    """Refuse a folder a store must not be made in: one that exists and is not a folder,
    or holds files but is not a toolkit map store (a Zarr group whose attributes carry the
    toolkit's ``toolkit_map`` record, read without writing). A missing or empty folder, or
    a toolkit store, is fine."""
    if not folder.exists():
        return
    if not folder.is_dir():
        raise MapStoreError(f"{str(folder)!r} exists and is not a folder: choose a folder")
    with os.scandir(folder) as entries:
        names = [e.name for _, e in zip(range(4), entries, strict=False)]
    if not names:
        return
    if (folder / "zarr.json").is_file() or (folder / ".zgroup").is_file():
        import zarr

        try:
            if dict(zarr.open_group(str(folder), mode="r").attrs).get("toolkit_map"):
                return
        except Exception:  # zarr raises many kinds for a folder that is not its store
            pass
    raise MapStoreError(
        f"{str(folder)!r} holds other files ({', '.join(sorted(names)[:3])}, ...), not a "
        "toolkit map store: choose a new or empty folder (nothing was written)"
    )


class Store:
    """A map's Zarr group (``store``: a folder path or a zarr store object)."""

    def __init__(
        self,
        store: object,
        meta: Mapping[str, Any],
        arrays: Mapping[str, tuple[tuple[int, ...], tuple[int, ...], str]],
        grid: Grid,
        resume: bool,
    ) -> None:
        if not zarr_available():
            raise MapStoreError("a map store needs zarr: pip install 'manipulator-toolkit[maps]'")
        import zarr

        if isinstance(store, str | Path):
            if not str(store).strip():
                raise MapStoreError(
                    "store must name a folder for the Zarr store; an empty path would make "
                    "the working folder the store"
                )
            store = str(Path(store).expanduser())
            _claim_folder(Path(store))
        self.grid = grid
        meta = _plain(dict(meta))
        group: Any
        try:
            group = zarr.open_group(store, mode="a")
        except Exception as exc:  # zarr raises many kinds for a folder that is not a store
            raise MapStoreError(f"cannot open {store!r} as a Zarr store: {exc}") from exc
        existing: Any = dict(group.attrs).get("toolkit_map")
        if existing is not None:
            if not resume:
                raise MapStoreError(
                    f"{store!r} already holds a map: pass resume=True (--resume) to finish it, "
                    "or choose another store"
                )
            made, asked = _leaves(existing), _leaves(meta)
            differing = sorted(k for k in set(made) | set(asked) if made.get(k) != asked.get(k))
            if differing:
                detail = "; ".join(
                    f"{k}: the store was made with {_short(made.get(k))}, this run asks "
                    f"{_short(asked.get(k))}"
                    for k in differing
                )
                raise MapStoreError(
                    f"{store!r} holds another map ({detail}): use another store, or the "
                    "same settings to resume it"
                )
        elif len(list(group.array_keys())):
            raise MapStoreError(f"{store!r} holds arrays that are not a toolkit map")
        else:
            for name, (shape, chunks, dtype) in arrays.items():
                fill = 0 if np.dtype(dtype).kind in "biu" else np.nan
                _create(group, name, shape, chunks, dtype, fill)
            _create(group, "done", grid.chunk_shape, (1, 1, 1), "uint8", 0)
            group.attrs["toolkit_map"] = meta
        self.group: Any = group

    def _digest(
        self, idx: tuple[int, int, int], arrays: Mapping[str, np.ndarray] | None = None
    ) -> str | None:
        """SHA-256 of a chunk's arrays (with its index), read from the store, or cut from
        ``arrays`` (the whole arrays, already read); None if they cannot be read."""
        s = self.grid.slices(idx)
        h = hashlib.sha256(repr(tuple(int(i) for i in idx)).encode())
        try:
            for name in sorted(k for k in self.group.array_keys() if k != "done"):
                # (P, H, 3, nx, ny, nz) statistics, or (nx, ny, nz, ...) per-voxel values
                region = (slice(None),) * 3 + s if name in _LEADING else s
                source = self.group[name] if arrays is None else arrays[name]
                h.update(name.encode())
                h.update(np.ascontiguousarray(source[region]).tobytes())
        except Exception:  # corrupt bytes: zarr's codecs raise many kinds
            return None
        return h.hexdigest()

    def damaged(self, arrays: Mapping[str, np.ndarray] | None = None) -> list[tuple[int, int, int]]:
        """Flagged chunks whose arrays are missing, unreadable or not what was written
        (checked on ``arrays`` when given, else chunk by chunk in the store)."""
        flags = np.asarray(self.group["done"][...]).astype(bool)
        digests: dict[str, str] = dict(self.group.attrs).get("toolkit_digests", {})
        bad = []
        for idx in zip(*np.nonzero(flags), strict=True):
            key = ",".join(str(int(i)) for i in idx)
            if digests.get(key) is None or digests[key] != self._digest(idx, arrays):
                bad.append(tuple(int(i) for i in idx))
        return bad  # type: ignore[return-value]

    def done(self) -> np.ndarray:
        """Flags (chunk grid) of the chunks written and intact (damaged ones are redone)."""
        flags = np.asarray(self.group["done"][...]).astype(bool)
        for idx in self.damaged():
            flags[idx] = False
        return flags

    def write(self, idx: tuple[int, int, int], result: Mapping[str, np.ndarray]) -> None:
        """Write one chunk's arrays, then their digest, then its flag."""
        s = self.grid.slices(idx)
        for name, values in result.items():
            region = (slice(None),) * 3 + s if name in _LEADING else s
            self.group[name][region] = values
        digests = dict(dict(self.group.attrs).get("toolkit_digests", {}))
        digests[",".join(str(int(i)) for i in idx)] = self._digest(idx)
        self.group.attrs["toolkit_digests"] = digests
        self.group["done"][idx] = 1

    def check(self, arrays: Mapping[str, np.ndarray] | None = None) -> None:
        """Raise a MapStoreError naming the damaged chunks, if any."""
        bad = self.damaged(arrays)
        if bad:
            shown = ", ".join(str(b) for b in bad[:8]) + (" ..." if len(bad) > 8 else "")
            raise MapStoreError(
                f"the map store is damaged: {len(bad)} chunk(s) do not match what was written "
                f"(missing, altered or copied from elsewhere): {shown}; run again with "
                "resume=True (--resume) to recompute them"
            )

    def read_checked(self) -> dict[str, np.ndarray]:
        """Every array, whole, read once; each flagged chunk is verified against its digest
        on what was read, and a MapStoreError names the damaged ones."""
        try:
            arrays = {
                name: np.asarray(self.group[name][...])
                for name in self.group.array_keys()
                if name != "done"
            }
        except Exception as exc:  # corrupt bytes: name the chunks, chunk by chunk
            self.check()
            raise MapStoreError(f"the map store cannot be read: {exc}") from exc
        self.check(arrays)
        return arrays


_LEADING = {"position", "rotation", "compensated"}  # (P, H, 3, nx, ny, nz)


def _create(
    group: Any, name: str, shape: tuple[int, ...], chunks: tuple[int, ...], dtype: str, fill: float
) -> None:
    if hasattr(group, "create_array"):  # zarr 3
        group.create_array(name=name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill)
    else:  # zarr 2
        group.create_dataset(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill)


def _leaves(meta: Any, prefix: str = "") -> dict[str, Any]:
    """A map's settings as {dotted name: value}, nested mappings opened ("grid.voxel")."""
    if not isinstance(meta, dict):
        return {prefix: meta}
    out: dict[str, Any] = {}
    for key, value in meta.items():
        out.update(_leaves(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


def _short(value: Any) -> str:
    """A setting as a user reads it: numbers plainly, long values cut at a word."""
    if value is None:
        return "nothing"
    if isinstance(value, list) and all(isinstance(v, int | float) for v in value):
        return "[" + ", ".join(f"{v:g}" for v in value) + "]"
    if isinstance(value, float):
        return f"{value:g}"
    text = repr(value)
    return text if len(text) <= 120 else text[:117].rsplit(" ", 1)[0] + " ..."
