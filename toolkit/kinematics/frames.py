"""A robot's frames by name (``robot.frames``): their indices in the model, the tool frame
every query defaults to, and in how many directions the joints move each one."""

from __future__ import annotations

from collections.abc import Iterator, Mapping

import numpy as np
import pinocchio as pin

from ..errors import FrameNotFoundError
from .backends import Backend
from .joints import JointLayout

__all__ = ["Frames"]


class Frames(Mapping[str, int]):
    """Every frame of the model (links, joints, fixed frames), name -> index: iterating
    gives the names in the model's order, ``frames[name]`` the index, an unknown name a
    :class:`~toolkit.errors.FrameNotFoundError` listing the valid ones."""

    def __init__(
        self, model: pin.Model, joints: JointLayout, backend: Backend, tip: str | None = None
    ) -> None:
        self._ids = {f.name: i for i, f in reversed(list(enumerate(model.frames)))}
        self._order = list(dict.fromkeys(f.name for f in model.frames))
        self._robot, self._backend, self._joints = joints.name, backend, joints
        self._ranks: dict[int, int] = {}
        if tip is None:
            tip = model.frames[len(model.frames) - 1].name
        self[tip]  # an unknown tip is refused, naming the valid frames
        self.tip: str = tip
        """The tool frame: the default ``frame`` of every query."""

    def __getitem__(self, frame: str) -> int:
        if not isinstance(frame, str) or frame not in self._ids:
            raise FrameNotFoundError(str(frame), self._ids, robot=self._robot)
        return int(self._ids[frame])

    def __contains__(self, frame: object) -> bool:
        return isinstance(frame, str) and frame in self._ids

    def __iter__(self) -> Iterator[str]:
        return iter(self._order)

    def __len__(self) -> int:
        return len(self._order)

    def get(self, frame: str, default: object = None) -> object:  # type: ignore[override]
        return self[frame] if frame in self else default

    def __repr__(self) -> str:
        return f"Frames({self._robot!r}, {len(self)} frames, tip={self.tip!r})"

    def id(self, frame: str | None) -> int:
        """Index of a frame by name; None is the tool frame (:attr:`tip`)."""
        return self[self.tip if frame is None else frame]

    def rank(self, frame: str | None = None) -> int:
        """In how many independent directions (of three translations and three rotations)
        the joints move ``frame`` (default: the tip): the largest rank of its Jacobian at 16
        random configurations. A 5-joint arm answers 5: its tool cannot take an arbitrary
        orientation at a point, only the orientations of a 5-D family."""
        fid = self.id(frame)
        rank = self._ranks.get(fid)
        if rank is None:
            q = self._joints.sample(np.random.default_rng(0), (16, self._joints.nq))
            J = self._backend.jacobian(q, fid)
            rank = self._ranks[fid] = int(max(np.linalg.matrix_rank(j, tol=1e-9) for j in J))
        return rank
