"""The voxel grid of a map, its chunks, the reach filter and the tool orientations tried."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..common import renames
from ..common import validate as _validate
from ..errors import InvalidParameterError
from ..robot import Robot, as_robot

__all__ = ["Grid", "axis_frames", "first_joint_origin", "make_grid", "spread_orientations"]

MAX_VOXELS = 50_000_000  # a 1 cm map of a 1 m arm has 8 M voxels


@dataclass(frozen=True)
class Grid:
    """A box of cubic voxels in the base frame, cut into chunks of voxels (one task each).

    Attributes:
        lower: the lowest corner of the first voxel [m].
        voxel: the edge of a voxel [m].
        shape: voxels along x, y, z.
        chunk: voxels per chunk along x, y, z.
        reach_centre, reach_radius: voxels whose centre lies outside this sphere [m]
            cannot be reached and are not solved (their index is 0).
    """

    lower: tuple[float, float, float]
    voxel: float
    shape: tuple[int, int, int]
    chunk: tuple[int, int, int]
    reach_centre: tuple[float, float, float]
    reach_radius: float

    @property
    def chunk_shape(self) -> tuple[int, int, int]:
        """Chunks along x, y, z."""
        return tuple(-(-s // c) for s, c in zip(self.shape, self.chunk, strict=True))  # type: ignore[return-value]

    def centers(self) -> np.ndarray:
        """Voxel centres (nx, ny, nz, 3) [m]."""
        axes = [self.lower[k] + self.voxel * (np.arange(self.shape[k]) + 0.5) for k in range(3)]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def chunk_ids(self) -> Iterator[tuple[int, int, int]]:
        """Every chunk index, in C order."""
        yield from np.ndindex(*self.chunk_shape)

    def slices(self, idx: Sequence[int]) -> tuple[slice, slice, slice]:
        """The voxels of chunk ``idx``."""
        return tuple(  # type: ignore[return-value]
            slice(i * c, min((i + 1) * c, s))
            for i, c, s in zip(idx, self.chunk, self.shape, strict=True)
        )

    def chunk_centers(self, idx: Sequence[int]) -> np.ndarray:
        """Centres (cx, cy, cz, 3) of the voxels of chunk ``idx``."""
        s = self.slices(idx)
        axes = [
            self.lower[k] + self.voxel * (np.arange(s[k].start, s[k].stop) + 0.5) for k in range(3)
        ]
        return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)

    def in_reach(self, points: np.ndarray) -> np.ndarray:
        """Which points (.., 3) lie inside the reach sphere (grown by half a voxel diagonal)."""
        margin = self.voxel * np.sqrt(3) / 2
        distance = np.linalg.norm(points - np.array(self.reach_centre), axis=-1)
        return distance <= self.reach_radius + margin

    def as_dict(self) -> dict[str, object]:
        """Plain values (for the store's metadata)."""
        return {
            "lower": [float(v) for v in self.lower],
            "voxel": float(self.voxel),
            "shape": [int(v) for v in self.shape],
            "chunk": [int(v) for v in self.chunk],
            "reach_centre": [float(v) for v in self.reach_centre],
            "reach_radius": float(self.reach_radius),
        }


def _reach(robot: Robot, frame: str | None, seed: int) -> tuple[np.ndarray, float, np.ndarray]:
    """(centre, radius, sampled tool positions) of the sphere holding the reach: centred on
    the first moving joint's origin, 2 % larger than the farthest of 20,000 samples."""
    q = robot.random_q(20_000, seed=np.random.default_rng(seed))
    tips = robot.fk(q, frame)[:, :3, 3]
    centre = first_joint_origin(robot)
    radius = float(np.linalg.norm(tips - centre, axis=1).max()) * 1.02
    return centre, radius, tips


def first_joint_origin(robot: Robot) -> np.ndarray:
    """The origin (3,) [m] of the first moving joint at the neutral configuration (the base
    origin when nothing moves): where the reach sphere of a map is centred."""
    import pinocchio as pin

    model = robot.model
    joint = next((j for j in range(1, model.njoints) if model.joints[j].nv > 0), 0)
    data = model.createData()
    pin.forwardKinematics(model, data, robot.joints.neutral())
    return np.array(data.oMi[joint].translation) if joint else np.zeros(3)


def make_grid(
    robot: Robot,
    voxel: float,
    bounds: ArrayLike | None = None,
    *,
    frame: str | None = None,
    chunk: int = 8,
    seed: int = 0,
) -> Grid:
    """The grid of a map: ``bounds`` ((2, 3): lowest and highest corner [m]) or, by default,
    the box around the sampled reach of ``frame``, grown by one voxel."""
    robot = as_robot(robot)
    voxel = _validate.number(voxel, "voxel [m]", lower=1e-4, strict=True)
    chunk = _validate.count(chunk, "chunk", minimum=1, maximum=256)
    seed = _validate.count(seed, "seed", minimum=0, maximum=2**63 - 1)
    robot.frames.id(frame)  # validates
    centre, radius, tips = _reach(robot, frame, seed)
    if bounds is None:
        low, high = tips.min(axis=0) - voxel, tips.max(axis=0) + voxel
    else:
        box = _validate.array(bounds, "bounds", shape=(2, 3))
        low, high = box[0], box[1]
        if np.any(high <= low):
            raise InvalidParameterError(
                f"bounds: every upper corner must exceed the lower, got {box.tolist()}"
            )
    shape = tuple(
        max(int(np.ceil((h - lo) / voxel - 1e-9)), 1) for lo, h in zip(low, high, strict=True)
    )
    if int(np.prod(shape)) > MAX_VOXELS:
        raise InvalidParameterError(
            f"a {voxel:g} m voxel makes {int(np.prod(shape)):,} voxels (more than "
            f"{MAX_VOXELS:,}): choose a larger voxel or smaller bounds"
        )
    return Grid(
        tuple(float(v) for v in low),  # type: ignore[arg-type]
        float(voxel),
        shape,  # type: ignore[arg-type]
        (chunk, chunk, chunk),
        tuple(float(v) for v in centre),  # type: ignore[arg-type]
        radius,
    )


@renames.renamed(count="n")
def spread_orientations(n: int) -> np.ndarray:
    """``n`` tool orientations (K, 3, 3) spread evenly: the tool z axes (approach
    directions) on a Fibonacci sphere, each rolled about itself by the golden angle times
    its index, so that the rolls are spread too. Deterministic."""
    count = _validate.count(n, "orientations", minimum=1, maximum=10_000)
    i = np.arange(count) + 0.5
    z = 1 - 2 * i / count
    azimuth = np.pi * (1 + 5**0.5) * i
    r = np.sqrt(1 - z**2)
    approach = np.stack([r * np.cos(azimuth), r * np.sin(azimuth), z], axis=1)
    out = np.empty((count, 3, 3))
    golden = np.pi * (3 - 5**0.5)
    for k, a in enumerate(approach):
        helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        x = np.cross(helper, a)
        x /= np.linalg.norm(x)
        y = np.cross(a, x)
        roll = golden * k
        x, y = np.cos(roll) * x + np.sin(roll) * y, -np.sin(roll) * x + np.cos(roll) * y
        out[k] = np.column_stack([x, y, a])
    return out


def axis_frames(axes: np.ndarray) -> np.ndarray:
    """Rotations (N, 3, 3) whose third column is each unit vector of ``axes`` (N, 3)."""
    helper = np.where(np.abs(axes[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = np.cross(helper, axes)
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    return np.stack([x, np.cross(axes, x), axes], axis=2)
