"""The render cache: verified before use, healed when wrong, private, concurrent-safe."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import toolkit
from toolkit.common import cache


@pytest.fixture
def fresh_cache(tmp_path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("TOOLKIT_CACHE_DIR", str(folder))
    return folder


def _tool_point(robot: toolkit.Robot) -> np.ndarray:
    return robot.fk(np.zeros(robot.nq))[:3, 3]


def test_entries_are_private_and_carry_a_digest(fresh_cache):
    path = toolkit.urdf_path("katana_6m180", a2=0.2111)
    assert path.parent == fresh_cache
    assert (fresh_cache.stat().st_mode & 0o077) == 0
    side = path.with_name(path.name + ".sha256").read_text()
    import hashlib

    assert hashlib.sha256(path.read_bytes()).hexdigest() == side


def test_a_planted_wrong_but_valid_file_is_replaced(fresh_cache):
    """Another model's valid URDF planted at the entry (the a2 = 0.5 attack) is detected."""
    good = toolkit.load("katana_6m180", a2=0.2333)
    path = toolkit.urdf_path("katana_6m180", a2=0.2333)
    path.write_text(toolkit.urdf_text("katana_6m180", a2=0.5))  # valid, wrong
    again = toolkit.load("katana_6m180", a2=0.2333)
    np.testing.assert_allclose(_tool_point(again), _tool_point(good), atol=1e-12)
    assert path.read_text() == toolkit.urdf_text("katana_6m180", a2=0.2333)


def test_a_truncated_entry_heals(fresh_cache):
    path = toolkit.urdf_path("scara", a=0.41)
    path.write_bytes(path.read_bytes()[:200])
    robot = toolkit.load("scara", a=0.41)  # no parse error: the entry is rewritten
    assert robot.nq == 3 and path.read_text() == toolkit.urdf_text("scara", a=0.41)


def test_a_symlink_at_the_entry_is_not_followed(fresh_cache, tmp_path):
    path = toolkit.urdf_path("spherical", b=0.33)
    victim = tmp_path / "victim.txt"
    victim.write_text("keep me")
    path.unlink()
    path.symlink_to(victim)
    robot = toolkit.load("spherical", b=0.33)
    assert robot.nq == 3
    assert victim.read_text() == "keep me"
    assert not path.is_symlink()


def test_a_folder_open_to_others_is_not_trusted(tmp_path, monkeypatch):
    """A world-writable folder (a fallback someone else prepared) is not used as is."""
    open_folder = tmp_path / "open"
    open_folder.mkdir()
    os.chmod(open_folder, 0o777)
    assert not cache.is_private(open_folder)
    monkeypatch.setattr(cache.tempfile, "gettempdir", lambda: str(tmp_path))
    victim = tmp_path / f"manipulator-toolkit-{os.getuid()}"
    victim.mkdir(mode=0o777)
    os.chmod(victim, 0o777)
    folder = cache.fallback_dir()
    assert folder != victim and cache.is_private(folder)


def test_a_fallback_folder_owned_by_someone_else_does_not_lock_us_out(tmp_path, monkeypatch):
    if os.getuid() != 0:
        pytest.skip("needs root to create a folder owned by another user")  # CI runs as root
    monkeypatch.setattr(cache.tempfile, "gettempdir", lambda: str(tmp_path))
    theirs = tmp_path / f"manipulator-toolkit-{os.getuid()}"
    theirs.mkdir(mode=0o700)
    os.chown(theirs, 12345, 12345)
    folder = cache.fallback_dir()
    assert folder != theirs and cache.is_private(folder)


def test_a_read_only_cache_still_works(tmp_path, monkeypatch):
    folder = tmp_path / "ro"
    monkeypatch.setenv("TOOLKIT_CACHE_DIR", str(folder))
    first = toolkit.urdf_path("cartesian", c=0.27)
    assert first.parent == folder
    # make the folder unwritable (root ignores modes: a file where the folder was)
    os.chmod(folder, 0o500)
    try:
        assert toolkit.urdf_path("cartesian", c=0.27) == first  # a valid entry is read
        if os.access(folder, os.W_OK):
            monkeypatch.setenv("TOOLKIT_CACHE_DIR", str(tmp_path / "file"))
            (tmp_path / "file").write_text("not a folder")
        other = toolkit.urdf_path("cartesian", c=0.28)  # a new entry goes elsewhere
        assert other.is_file() and other.parent != folder
        assert toolkit.load("cartesian", c=0.28).nq == 3
    finally:
        os.chmod(folder, 0o700)


_RENDER = """
import sys, toolkit
path = toolkit.urdf_path("bending", n=7, links=2)
print(path)
"""


@pytest.mark.slow
def test_eight_processes_render_one_valid_file(fresh_cache):
    env = {**os.environ, "TOOLKIT_CACHE_DIR": str(fresh_cache)}
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", _RENDER], stdout=subprocess.PIPE, text=True, env=env
        )
        for _ in range(8)
    ]
    outs = [p.communicate(timeout=120)[0].strip() for p in procs]
    assert all(p.returncode == 0 for p in procs)
    assert len(set(outs)) == 1
    path = Path(outs[0])
    assert path.read_text() == toolkit.urdf_text("bending", n=7, links=2)
    leftovers = [p.name for p in fresh_cache.iterdir() if p.name.endswith(".tmp")]
    assert not leftovers


def test_a_cache_file_swapped_after_the_check_is_never_built(monkeypatch, tmp_path):
    """The audit's race: with a shared cache folder another user swaps the verified file
    between the check and Pinocchio's open. The model is built from the text this process
    rendered, never from the path."""
    from toolkit.robot import loading as loaders

    planted = (
        '<robot name="planted"><link name="a"/><link name="tool"/><joint name="j" '
        'type="revolute"><parent link="a"/><child link="tool"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    real = loaders.urdf_path

    def swapped(name, **params):
        path = real(name, **params)
        path.write_text(planted)  # the other user wins the race
        return path

    monkeypatch.setattr(loaders, "urdf_path", swapped)
    robot = toolkit.load("katana_6m180")
    assert robot.nq == 5 and "link3" in list(robot.frames)
