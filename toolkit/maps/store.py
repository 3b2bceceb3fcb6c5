"""Zarr stores of maps: one array per result, chunked like the map's tasks, a ``done`` flag
per chunk, and the map's inputs in the group's attributes.

A chunk's arrays are written first and its flag last, so a run killed at any moment
leaves every flagged chunk complete; ``resume`` recomputes the others. A store whose
inputs differ from the run's (another robot, grid, orientations, seed or toolkit
version) is refused, never mixed.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MapStoreError
from .grid import Grid

__all__ = ["Store", "zarr_available"]


def zarr_available() -> bool:
    """True if the optional zarr package can be imported."""
    try:
        import zarr  # noqa: F401
    except ImportError:
        return False
    return True


def _plain(value: Any) -> Any:
    return json.loads(json.dumps(value))


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
            store = str(Path(store).expanduser())
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
            differing = sorted(
                k for k in set(meta) | set(existing) if meta.get(k) != existing.get(k)
            )
            if differing:
                detail = "; ".join(
                    f"{k}: store {existing.get(k)!r:.80} != run {meta.get(k)!r:.80}"
                    for k in differing
                )
                raise MapStoreError(
                    f"{store!r} was made by another map ({detail}); refusing to mix"
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

    def done(self) -> np.ndarray:
        """Flags (chunk grid) of the chunks already written."""
        return np.asarray(self.group["done"][...]).astype(bool)

    def write(self, idx: tuple[int, int, int], result: Mapping[str, np.ndarray]) -> None:
        """Write one chunk's arrays, then its flag."""
        s = self.grid.slices(idx)
        for name, values in result.items():
            # (P, H, 3, nx, ny, nz) statistics, or (nx, ny, nz, ...) per-voxel values
            region = (slice(None),) * 3 + s if name in _LEADING else s
            self.group[name][region] = values
        self.group["done"][idx] = 1

    def read(self, name: str) -> np.ndarray:
        """A whole array."""
        return np.asarray(self.group[name][...])


_LEADING = {"position", "rotation", "compensated"}  # (P, H, 3, nx, ny, nz)


def _create(
    group: Any, name: str, shape: tuple[int, ...], chunks: tuple[int, ...], dtype: str, fill: float
) -> None:
    if hasattr(group, "create_array"):  # zarr 3
        group.create_array(name=name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill)
    else:  # zarr 2
        group.create_dataset(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill)
