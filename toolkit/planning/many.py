"""Many planning problems at once (a dataset of problems, a benchmark): each planned by
``Robot.plan`` in a pool of forked processes or of threads, the results in the problems'
order."""

from __future__ import annotations

import multiprocessing
import os
import threading
from collections.abc import Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from typing import Any

from ..common import validate as _validate
from ..errors import InvalidParameterError, ToolkitError
from ..kinematics import serial
from .requests import MotionRequest
from .results import PlanResult

__all__ = ["plan_many"]


def _call(robot: Any, problem: object, scene: Any, seed: int, options: dict[str, Any]) -> Any:
    """One problem's plan: a MotionRequest, a mapping of ``Robot.plan``'s keywords, or a
    (start, goal) pair; the pool's ``scene`` and options unless the problem gives its own."""
    opts = {"seed": seed, **options}
    if isinstance(problem, MotionRequest):
        return problem.plan(robot, scene, **opts)
    if isinstance(problem, Mapping):
        kw = {"scene": scene, **opts, **problem}
        if "start" not in kw:
            raise InvalidParameterError("a problem mapping needs 'start' (and 'goal' or 'pose')")
        return robot.plan(**kw)
    if isinstance(problem, tuple | list) and len(problem) == 2:
        return robot.plan(problem[0], problem[1], scene=scene, **opts)
    raise InvalidParameterError(
        f"a problem is a MotionRequest, a mapping of Robot.plan's keywords or a (start, goal) "
        f"pair, got {problem!r:.80}"
    )


def plan_many(
    robot: Any, problems: Sequence[object], *, scene: Any = None, workers: int | None = None,
    seed: int = 0, pool: str | None = None, **options: Any,
) -> list[PlanResult]:  # fmt: skip
    """The plans of ``problems`` (each a :class:`~toolkit.planning.MotionRequest`, a mapping
    of :meth:`toolkit.Robot.plan`'s keywords, or a (start, goal) pair) in their order,
    planned ``workers`` at a time (default: one per core) in a ``pool`` of ``"fork"``-ed
    processes (the default where processes can fork) or of ``"threads"`` (the default
    elsewhere: the compiled search releases the interpreter's lock).
    ``scene`` and ``options`` (``time_limit``, ``hold``, ``resolution``, ...) apply to
    every problem that does not give its own; problem i is seeded ``seed + i`` unless it
    gives a seed, so the answers do not depend on ``workers`` or ``pool``. A problem
    refused (a start in collision, say) raises, naming its index."""
    if isinstance(problems, str | bytes) or not isinstance(problems, Sequence):
        raise InvalidParameterError(f"problems must be a sequence, got {problems!r:.80}")
    seed = _validate.count(seed, "seed", minimum=0, maximum=2**62)
    count = len(problems)
    if workers is None:
        workers = os.cpu_count() or 1
    workers = _validate.count(workers, "workers", minimum=1, maximum=256)
    forks = "fork" in multiprocessing.get_all_start_methods()
    pool = ("fork" if forks else "threads") if pool is None else pool
    _validate.one_of(pool, "pool", ("fork", "threads") if forks else ("threads",))

    job = (robot, problems, scene, seed, options)
    if workers == 1 or count <= 1:
        return [_one(job, i) for i in range(count)]
    if pool == "threads":
        with ThreadPoolExecutor(max_workers=min(workers, count)) as threads:
            return list(threads.map(lambda i: _serial(job, i), range(count)))
    with _FORK_LOCK:  # the forked workers inherit the job (nothing of it is pickled)
        _JOB[0] = job
        try:
            context = multiprocessing.get_context("fork")
            with ProcessPoolExecutor(max_workers=min(workers, count), mp_context=context) as forked:
                return list(forked.map(_forked, range(count)))
        finally:
            _JOB[0] = None


_JOB: list[Any] = [None]
_FORK_LOCK = threading.Lock()


def _one(job: tuple[Any, ...], i: int) -> PlanResult:
    robot, problems, scene, seed, options = job
    try:
        result: PlanResult = _call(robot, problems[i], scene, seed + i, options)
    except ToolkitError as exc:  # the same error, its message naming the problem (errors
        exc.args = (f"problem {i}: {exc}", *exc.args[1:])  # with other constructors too)
        raise
    return result


def _forked(i: int) -> PlanResult:
    """Problem i in a forked worker, from the job its parent set before forking; its
    compiled batches on its own core (a forked child launches no thread pool)."""
    return _serial(_JOB[0], i)


def _serial(job: tuple[Any, ...], i: int) -> PlanResult:
    """Problem i with its compiled batches on the calling thread's core."""
    with serial():
        return _one(job, i)
