"""Pairs of links worth never checking, found over random configurations (the MoveIt setup
assistant's method), optionally written as an SRDF."""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..common import renames
from ..common import validate as _validate
from ..errors import InvalidParameterError
from .checker import Checker, CollisionSubject

__all__ = ["disabled_pairs"]


@renames.renamed(samples="n")
def disabled_pairs(
    robot: CollisionSubject,
    n: int = 2000,
    *,
    seed: int = 0,
    srdf: str | Path | None = None,
) -> list[tuple[str, str, str]]:
    """Pairs of links worth never checking, found as the MoveIt setup assistant does:
    over ``n`` random configurations, pairs that never collide ("Never") and pairs
    that always do ("Always"); adjacent links are left out of the checks anyway. Returns
    (link1, link2, reason) tuples; with ``srdf``, also writes them there as an SRDF whose
    ``<disable_collisions>`` ``load_urdf(..., srdf=)`` honours.

    Pairs that never collided in the samples may still collide in a configuration not
    drawn: more samples make that rarer (MoveIt's default is 10,000)."""
    if not isinstance(robot, CollisionSubject):
        raise InvalidParameterError(f"robot must be a toolkit Robot, got {robot!r:.100}")
    samples = _validate.count(n, "n (samples)", minimum=10, maximum=10_000_000)
    seed = _validate.count(seed, "seed", minimum=0, maximum=2**63 - 1)
    checker = Checker(robot, None, srdf=False)
    hits = np.zeros(len(checker.parts.first), dtype=np.int64)
    for q in robot.random_q(samples, seed=seed):
        hits += checker.pair_flags(q)
    by_links: dict[tuple[str, str], list[int]] = {}
    for k in range(len(hits)):
        a, b = sorted(checker.pair_names(k))
        by_links.setdefault((a, b), []).append(int(hits[k]))
    out = []
    for (a, b), counts in sorted(by_links.items()):
        if a == b:
            continue
        if max(counts) == 0:
            out.append((a, b, "Never"))
        elif max(counts) == samples:
            out.append((a, b, "Always"))
    if srdf is not None:
        if not isinstance(srdf, str | Path):
            raise InvalidParameterError(f"srdf must be a file path, got {srdf!r:.100}")
        lines = [f"<robot name={quoteattr(robot.name)}>"]
        lines += [
            f"  <disable_collisions link1={quoteattr(a)} link2={quoteattr(b)} "
            f"reason={quoteattr(why)}/>"
            for a, b, why in out
        ]
        Path(srdf).write_text("\n".join([*lines, "</robot>", ""]), encoding="utf-8")
    return out
