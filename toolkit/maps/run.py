"""Running a map's chunks: in a pool of threads of this process (one chunk at a time each,
its compiled kernels on one core without the GIL, so every core works; no process is
started, so a plain script without a main guard, stdin, a REPL or a notebook all work), in
this thread alone (``workers=1``: each chunk spread over every core by the compiled
engine), or on a ``dask.distributed`` cluster (one chunk per task); this thread writes
each finished chunk to the store at once, with a progress line. The figures count the IK
solves actually run."""

from __future__ import annotations

import os
import sys
import time
import uuid
from collections.abc import Callable, Mapping
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from ..common import validate as _validate
from ..errors import InvalidParameterError, MapStoreError
from ..kinematics import serial
from .compute import SOLVES, accuracy_chunk, inverse_chunk, reach_chunk
from .grid import Grid
from .store import Store

__all__ = ["MapRun", "Progress", "run_chunks"]


@dataclass(frozen=True)
class MapRun:
    """How a map runs (never what it computes, so never part of a store's identity).

    Attributes:
        store: a Zarr folder or store object every finished chunk is written to (None:
            kept in memory).
        client: a ``dask.distributed.Client`` whose workers compute the chunks (None: this
            machine).
        resume: finish a killed run from ``store``.
        progress: print a progress line.
        workers: local threads (None: one per core when there are several chunks).
        chunk: voxels per chunk edge (a chunk is one task).
    """

    store: str | Path | object = None
    client: Any = None
    resume: bool = False
    progress: bool = False
    workers: int | None = None
    chunk: int = 8

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        store, client = self.store, self.client
        if not (store is None or isinstance(store, str | os.PathLike) or _store_like(store)):
            raise InvalidParameterError(
                f"store must be a folder path or a Zarr store object, got {store!r:.80}"
            )
        if client is not None and not (hasattr(client, "submit") and hasattr(client, "scatter")):
            raise InvalidParameterError(
                f"client must be a dask.distributed.Client or None, got {client!r:.80}"
            )
        set_(self, "chunk", _validate.count(self.chunk, "chunk", minimum=1, maximum=256))
        set_(self, "resume", _validate.flag(self.resume, "resume"))
        set_(self, "progress", _validate.flag(self.progress, "progress"))
        if self.workers is not None:
            set_(self, "workers", _validate.count(self.workers, "workers", maximum=1024))
        if self.resume and self.store is None:
            raise InvalidParameterError("resume needs the store of the run to finish (store=...)")

    @classmethod
    def build(cls, run: MapRun | None, overrides: Mapping[str, object], where: str) -> MapRun:
        """``run`` (default: all defaults) with keyword ``overrides`` of its fields; any
        other keyword is refused, naming the function ``where`` and the fields."""
        if run is not None and not isinstance(run, MapRun):
            raise InvalidParameterError(f"run must be a toolkit.maps.MapRun, got {run!r:.80}")
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(overrides) - set(names))
        if unknown:
            raise InvalidParameterError(
                f"{where}() got unknown keyword(s) {unknown}; its run settings are {names}"
            )
        base = {name: getattr(run or cls(), name) for name in names}
        return cls(**{**base, **overrides})


def _store_like(value: object) -> bool:
    """A Zarr store object: a zarr 3 ``Store``, or a mapping of keys to bytes (zarr 2, and
    a dict as an in-memory store)."""
    if isinstance(value, Mapping) or type(value).__name__.endswith("Store"):
        return True
    return (
        hasattr(value, "__getitem__")
        and hasattr(value, "__setitem__")
        and not isinstance(value, list | np.ndarray)
    )


@dataclass(frozen=True)
class _Job:
    """The chunks to compute: the map's kind, its robot (or layer), grid and settings."""

    kind: str
    target: Any
    grid: Grid
    settings: Any
    todo: list[tuple[int, int, int]]


Spec = Mapping[str, tuple[tuple[int, ...], tuple[int, ...], str]]
_KINDS: dict[str, Callable[..., dict[str, np.ndarray]]] = {
    "reachability": reach_chunk,
    "backlash_accuracy": accuracy_chunk,
    "inverse_reachability": inverse_chunk,
}


def _task(kind: str, target: Any, grid: Grid, idx: tuple[int, int, int], settings: Any) -> Any:
    """One chunk on a Dask worker, on as many cores as the worker has threads."""
    try:
        from distributed import get_worker

        threads: int | None = get_worker().state.nthreads
    except (ImportError, ValueError, AttributeError):
        threads = 1
    return idx, _KINDS[kind](target, grid, idx, settings, threads)


LOG_EVERY = 30.0
"""[s] How often a log (standard error not a terminal) gets a progress line: at most this
far apart, and at every tenth of the work and at its end."""


class Progress:
    """A progress line on standard error: redrawn in place on a terminal; in a log file a
    line every :data:`LOG_EVERY` seconds or tenth of the work, and one at the end (a build
    of minutes is not silent in CI); ``label``: what runs, ``unit``: what ``total`` counts."""

    def __init__(self, total: int, show: bool, label: str = "map", unit: str = "chunks") -> None:
        self.total, self.show, self.label, self.unit = total, show, label, unit
        self.done, self.solved, self.start = 0, 0, time.perf_counter()
        self.tty = show and sys.stderr.isatty()
        self.logged, self.tenth = self.start, 0

    def step(self, solves: int) -> None:
        self.done += 1
        self.solved += solves
        if not self.show:
            return
        now = time.perf_counter()
        tenth = 10 * self.done // max(self.total, 1)
        due = self.done == self.total or now - self.logged >= LOG_EVERY or tenth > self.tenth
        if not (self.tty or due):
            return
        elapsed = now - self.start
        rate = self.solved / elapsed if elapsed > 0 else 0.0
        line = (f"{self.label}: {self.done}/{self.total} {self.unit}, {self.solved:,} IK "
                f"solves, {rate:,.0f} solves/s, {elapsed:.0f} s")  # fmt: skip
        sys.stderr.write(f"\r{line}" if self.tty else f"{line}\n")
        sys.stderr.flush()
        self.logged, self.tenth = now, tenth

    def close(self) -> None:
        if self.show and self.total and self.tty:
            sys.stderr.write("\n")


def _put(
    arrays: dict[str, np.ndarray] | None,
    grid: Grid,
    idx: tuple[int, int, int],
    result: Mapping[str, np.ndarray],
) -> None:
    """A chunk's values into the whole arrays (statistics carry three leading axes)."""
    assert arrays is not None
    s = grid.slices(idx)
    for name, values in result.items():
        arrays[name][(slice(None),) * 3 + s if arrays[name].ndim == 6 else s] = values


def _allocate(spec: Spec) -> dict[str, np.ndarray]:
    return {
        name: np.full(shape, 0 if np.dtype(dtype).kind in "biu" else np.nan, dtype=dtype)
        for name, (shape, _, dtype) in spec.items()
    }


def run_chunks(
    kind: str,
    target: Any,
    grid: Grid,
    settings: Any,
    spec: Spec,
    meta: Mapping[str, Any],
    run: MapRun,
) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """The map's arrays, and run figures (chunks computed, IK solves, seconds)."""
    store, client = run.store, run.client
    saved = Store(store, meta, spec, grid, run.resume) if store is not None else None
    arrays = None if saved is not None else _allocate(spec)
    done = saved.done() if saved is not None else np.zeros(grid.chunk_shape, dtype=bool)
    todo = [idx for idx in grid.chunk_ids() if not done[idx]]
    bar = Progress(len(todo), run.progress)
    start = time.perf_counter()

    def keep(idx: tuple[int, int, int], result: Mapping[str, np.ndarray]) -> None:
        values = dict(result)
        solves = int(values.pop(SOLVES, 0))  # the solves this chunk actually ran
        if saved is not None:
            saved.write(idx, values)
        else:
            _put(arrays, grid, idx, values)
        bar.step(solves)

    local = _workers(run.workers, len(todo))
    job = _Job(kind, target, grid, settings, todo)
    try:  # this process writes every chunk, whoever computed it
        if client is not None:
            _distributed(client, job, keep)
        elif local > 1:
            _thread_pool(local, job, keep)
        else:
            for idx in todo:
                keep(idx, _KINDS[kind](target, grid, idx, settings))
    finally:
        bar.close()
    figures = {
        "chunks": float(len(todo)),
        "solves": float(bar.solved),
        "seconds": time.perf_counter() - start,
        "workers": float(local if client is None else len(client.scheduler_info()["workers"])),
    }
    if saved is not None:
        missing = int((~np.asarray(saved.group["done"][...]).astype(bool)).sum())
        if missing:
            raise MapStoreError(f"{missing} chunk(s) of the map were not written")
        stored = saved.read_checked()  # one read, verified against the chunks' digests
        arrays = {name: stored[name] for name in spec}
    assert arrays is not None
    return arrays, figures


def _workers(workers: int | None, chunks: int) -> int:
    """Local threads: as given, or (None) one per core when there are several chunks."""
    if workers is not None:
        return workers
    cores = os.cpu_count() or 1
    return cores if cores > 1 and chunks >= 2 else 1


def _serial_chunk(kind: str, target: Any, grid: Grid, idx: tuple[int, int, int], s: Any) -> Any:
    with serial():  # this thread's kernels on one core, without the launch lock
        return idx, _KINDS[kind](target, grid, idx, s)


Keep = Callable[[tuple[int, int, int], Mapping[str, np.ndarray]], None]


def _thread_pool(workers: int, job: _Job, keep: Keep) -> None:
    """Every chunk in a pool of threads of this process; this thread writes them."""
    kind, target, grid, s = job.kind, job.target, job.grid, job.settings
    with ThreadPoolExecutor(workers, thread_name_prefix="toolkit-map") as pool:
        futures = [pool.submit(_serial_chunk, kind, target, grid, idx, s) for idx in job.todo]
        try:
            for future in as_completed(futures):
                idx, result = future.result()
                keep(idx, result)
        except BaseException:  # Ctrl-C or an error: no new chunk starts
            for future in futures:
                future.cancel()
            raise


def _distributed(client: Any, job: _Job, keep: Keep) -> None:
    """Every chunk as a task of ``client``; workers get the robot (or layer) by pickling,
    once each, never as a path on this machine."""
    try:
        from distributed import Client, as_completed
    except ImportError as exc:
        raise InvalidParameterError(
            "client= needs dask.distributed: pip install 'manipulator-toolkit[maps]'"
        ) from exc
    if not isinstance(client, Client):
        raise InvalidParameterError(f"client must be a dask.distributed.Client, got {client!r:.80}")
    shared = client.scatter(job.target, broadcast=True)
    run = f"{job.kind}-{uuid.uuid4().hex[:12]}"
    futures = [
        client.submit(
            _task, job.kind, shared, job.grid, idx, job.settings, pure=False, key=f"map-{run}-{idx}"
        )
        for idx in job.todo
    ]
    for future in as_completed(futures):
        idx, result = future.result()
        keep(tuple(idx), result)
