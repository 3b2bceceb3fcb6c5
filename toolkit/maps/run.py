"""Running a map's chunks: in local processes (one per core, one chunk at a time each), in
this process (each chunk spread over every core by the compiled engine), or on a
``dask.distributed`` cluster (one chunk per task); this process writes each finished
chunk to the store at once, with a progress line."""

from __future__ import annotations

import multiprocessing
import os
import sys
import threading
import time
import uuid
from collections.abc import Callable, Mapping
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from typing import Any

import numpy as np

from .. import _validate
from ..errors import InvalidParameterError, MapStoreError
from .compute import accuracy_chunk, reach_chunk
from .grid import Grid
from .store import Store

__all__ = ["run_chunks"]

Spec = Mapping[str, tuple[tuple[int, ...], tuple[int, ...], str]]
_KINDS: dict[str, Callable[..., dict[str, np.ndarray]]] = {
    "reachability": reach_chunk,
    "backlash_accuracy": accuracy_chunk,
}


def _task(kind: str, target: Any, grid: Grid, idx: tuple[int, int, int], settings: Any) -> Any:
    """One chunk on a Dask worker, on as many cores as the worker has threads."""
    try:
        from distributed import get_worker

        threads: int | None = get_worker().state.nthreads
    except (ImportError, ValueError, AttributeError):
        threads = 1
    return idx, _KINDS[kind](target, grid, idx, settings, threads)


class _Progress:
    def __init__(self, total: int, solves: Mapping[tuple[int, int, int], int], show: bool) -> None:
        self.total, self.solves, self.show = total, solves, show
        self.done, self.solved, self.start = 0, 0, time.perf_counter()

    def step(self, idx: tuple[int, int, int]) -> None:
        self.done += 1
        self.solved += self.solves[idx]
        if self.show:
            elapsed = time.perf_counter() - self.start
            rate = self.solved / elapsed if elapsed > 0 else 0.0
            sys.stderr.write(
                f"\rmap: {self.done}/{self.total} chunks, {self.solved:,} IK solves, "
                f"{rate:,.0f} solves/s, {elapsed:.0f} s"
            )
            sys.stderr.flush()

    def close(self) -> None:
        if self.show and self.total:
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
    *,
    store: object = None,
    client: Any = None,
    resume: bool = False,
    progress: bool = False,
    per_voxel: int = 1,
    workers: int | None = None,
) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """The map's arrays, and run figures (chunks computed, IK solves, seconds)."""
    if resume and store is None:
        raise InvalidParameterError("resume needs the store of the run to finish (store=...)")
    if workers is not None:  # checked before any work
        workers = _validate.count(workers, "workers", maximum=1024)
    saved = Store(store, meta, spec, grid, resume) if store is not None else None
    arrays = None if saved is not None else _allocate(spec)
    done = saved.done() if saved is not None else np.zeros(grid.chunk_shape, dtype=bool)
    todo = [idx for idx in grid.chunk_ids() if not done[idx]]
    solves = {idx: int(grid.in_reach(grid.chunk_centers(idx)).sum()) * per_voxel for idx in todo}
    bar = _Progress(len(todo), solves, progress)
    start = time.perf_counter()

    def keep(idx: tuple[int, int, int], result: Mapping[str, np.ndarray]) -> None:
        if saved is not None:
            saved.write(idx, result)
        else:
            _put(arrays, grid, idx, result)
        bar.step(idx)

    local = _workers(workers, len(todo))
    try:  # this process writes every chunk, whoever computed it
        if client is not None:
            _distributed(client, kind, target, grid, settings, todo, keep)
        elif local > 1:
            _processes(local, kind, target, grid, settings, todo, keep)
        else:
            for idx in todo:
                keep(idx, _KINDS[kind](target, grid, idx, settings))
    finally:
        bar.close()
    figures = {
        "chunks": float(len(todo)),
        "solves": float(sum(solves.values())),
        "seconds": time.perf_counter() - start,
        "workers": float(local if client is None else len(client.scheduler_info()["workers"])),
    }
    if saved is not None:
        missing = int((~np.asarray(saved.group["done"][...]).astype(bool)).sum())
        if missing:
            raise MapStoreError(f"{missing} chunk(s) of the map were not written")
        saved.check()
        arrays = {name: saved.read(name) for name in spec}
    assert arrays is not None
    return arrays, figures


def _workers(workers: int | None, chunks: int) -> int:
    """Local processes: as given, or (None) one per core when there are at least four
    chunks per core (below that, starting the processes costs more than it saves)."""
    if workers is not None:
        return workers
    cores = os.cpu_count() or 1
    return cores if cores > 1 and chunks >= 4 * cores else 1


_WORKER: dict[str, Any] = {}


def _start_worker(kind: str, target: Any, grid: Grid, settings: Any, parent: int) -> None:
    """A local worker process: its inputs once, one core for the compiled kernels, and a
    watch that ends it when its parent is gone (killed with SIGKILL, say)."""
    import numba

    numba.set_num_threads(1)
    _WORKER.update(kind=kind, target=target, grid=grid, settings=settings)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(0)

    threading.Thread(target=watch, daemon=True, name="parent-watch").start()


def _worker_chunk(idx: tuple[int, int, int]) -> tuple[tuple[int, int, int], Any]:
    w = _WORKER
    return idx, _KINDS[w["kind"]](w["target"], w["grid"], idx, w["settings"])


def _processes(
    workers: int,
    kind: str,
    target: Any,
    grid: Grid,
    settings: Any,
    todo: list[tuple[int, int, int]],
    keep: Callable[[tuple[int, int, int], Mapping[str, np.ndarray]], None],
) -> None:
    """Every chunk in a pool of local processes (one core each); this process writes."""
    context = multiprocessing.get_context("spawn")  # no fork of numba's threads
    with ProcessPoolExecutor(
        workers, mp_context=context, initializer=_start_worker,
        initargs=(kind, target, grid, settings, os.getpid()),
    ) as pool:  # fmt: skip
        futures = [pool.submit(_worker_chunk, idx) for idx in todo]
        try:
            for future in as_completed(futures):
                idx, result = future.result()
                keep(idx, result)
        except BrokenProcessPool as exc:
            raise MapStoreError(
                "a local worker process died; the chunks finished before are kept in the "
                "store (if any): run again with resume=True to finish"
            ) from exc
        except BaseException:
            for future in futures:
                future.cancel()
            raise


def _distributed(
    client: Any,
    kind: str,
    target: Any,
    grid: Grid,
    settings: Any,
    todo: list[tuple[int, int, int]],
    keep: Callable[[tuple[int, int, int], Mapping[str, np.ndarray]], None],
) -> None:
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
    shared = client.scatter(target, broadcast=True)
    run = f"{kind}-{uuid.uuid4().hex[:12]}"
    futures = [
        client.submit(_task, kind, shared, grid, idx, settings, pure=False, key=f"map-{run}-{idx}")
        for idx in todo
    ]
    for future in as_completed(futures):
        idx, result = future.result()
        keep(tuple(idx), result)
