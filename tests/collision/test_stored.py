"""A robot's sphere covers kept on disk between processes (toolkit.collision.stored): read
back equal, made again where the entry is damaged, planted or in a folder others can
write, and keyed by everything they are made from."""

from __future__ import annotations

import os

import numpy as np
import pytest

import toolkit
from toolkit.collision import Checker, bounds, stored
from toolkit.common import cache


@pytest.fixture
def folders(tmp_path, monkeypatch):
    """The preferred cache folder and the fallback, both in tmp_path; a count of the
    covers made (not read)."""
    preferred, fallback = tmp_path / "cache", tmp_path / "fallback"
    fallback.mkdir(mode=0o700)
    monkeypatch.setenv("TOOLKIT_CACHE_DIR", str(preferred))
    monkeypatch.setattr(cache, "fallback_dir", lambda: fallback)
    made = []
    real = bounds.shape_covers

    def counted(*args):
        made.append(1)
        return real(*args)

    monkeypatch.setattr(bounds, "shape_covers", counted)
    return preferred, fallback, made


def _covers() -> tuple[np.ndarray, ...]:
    """The UR5's packed covers as a new process makes them (the robot loaded anew)."""
    robot = toolkit.load_example("ur5")
    return Checker(robot, toolkit.Scene()).bounds._packed_covers()[:5]


def _entry(folder):
    (entry,) = folder.glob("covers-*.npz")
    return entry


def _same(a, b) -> None:
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x, y)


def test_covers_are_read_back_equal_and_not_made_again(folders):
    preferred, _, made = folders
    first = _covers()
    assert len(made) == 1 and _entry(preferred).stat().st_mode & 0o077 == 0
    again = _covers()
    assert len(made) == 1  # read from the store
    _same(first, again)


def test_a_damaged_or_planted_entry_is_made_again(folders):
    preferred, _, made = folders
    first = _covers()
    entry = _entry(preferred)
    data = bytearray(entry.read_bytes())
    data[len(data) // 2] ^= 0xFF
    entry.write_bytes(bytes(data))  # damaged: its sidecar no longer matches
    _same(first, _covers())
    assert len(made) == 2
    # planted: arrays of the wrong shapes, with a sidecar that matches them
    import hashlib
    import io

    out = io.BytesIO()
    np.savez(out, cstart=np.zeros(3, np.int64), csphere=np.zeros((1, 4)),
             hold=np.zeros((1, 4)), wstart=np.zeros(2, np.int64),
             wpoint=np.zeros((0, 3)))  # fmt: skip
    entry.write_bytes(out.getvalue())
    entry.with_name(entry.name + ".sha256").write_text(hashlib.sha256(out.getvalue()).hexdigest())
    _same(first, _covers())
    assert len(made) == 3


def test_an_entry_in_a_folder_others_can_write_is_never_read(folders):
    preferred, fallback, made = folders
    first = _covers()
    os.chmod(preferred, 0o755)
    _same(first, _covers())
    assert len(made) == 2  # not read from the open folder
    assert list(fallback.glob("covers-*.npz"))  # kept in the private fallback instead
    _same(first, _covers())
    assert len(made) == 2


def test_the_key_follows_the_shapes():
    robot = toolkit.load_example("ur5")
    checker = Checker(robot, toolkit.Scene())
    geom, count = checker.geom, checker.robot_count
    key = stored.covers_key(geom, count)
    assert key is not None and key == stored.covers_key(geom, count)
    assert stored.covers_key(geom, count - 1) != key
    obj = geom.geometryObjects[1]
    moved = obj.placement.copy()
    moved.translation = moved.translation + np.array([0.0, 0.0, 1e-9])
    obj.placement = moved
    assert stored.covers_key(geom, count) != key
    obj.meshPath = ""  # a mesh that names no file: not kept
    assert stored.covers_key(geom, count) is None
