"""Rendering: committed URDFs equal fresh renders, the cache, argument validation."""

from __future__ import annotations

import os

import numpy as np
import pytest

import toolkit
from toolkit.common.cache import cache_dir
from toolkit.descriptions import committed_urdf_path, resolve_arguments, templates_dir


def test_available_models_lists_katanas():
    names = toolkit.available_models()
    assert {"katana_6m180", "katana_6m90a", "katana_6m90b"} <= set(names)
    assert names == sorted(names)


@pytest.mark.parametrize("name", toolkit.available_models())
def test_committed_urdf_equals_fresh_render(name):
    committed = committed_urdf_path(name).read_text(encoding="utf-8")
    assert toolkit.urdf_text(name) == committed, (
        f"urdf/{name}.urdf is stale: regenerate with `toolkit urdf --all -o urdf`"
    )


@pytest.mark.parametrize("name", toolkit.available_models())
def test_every_model_loads_with_its_tip(name):
    robot = toolkit.load(name)
    assert robot.tip in list(robot.frames)
    T = robot.fk(robot.joints.neutral())
    np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)


def test_templates_found():
    folder = templates_dir()
    assert (folder / "katana.urdf.xacro").is_file()
    assert (folder / "common.xacro").is_file()


def test_cache_written_once_and_reused():
    params = {"a2": 0.2345}
    path = toolkit.urdf_path("katana_6m180", **params)
    assert path.parent == cache_dir()
    assert path.read_text(encoding="utf-8") == toolkit.urdf_text("katana_6m180", **params)
    stamp = path.stat().st_mtime_ns
    assert toolkit.urdf_path("katana_6m180", **params) == path
    assert path.stat().st_mtime_ns == stamp  # not rewritten
    assert not list(path.parent.glob("*.tmp"))  # atomic write left no temporary file
    # a different argument set is a different cache entry
    assert toolkit.urdf_path("katana_6m180", a2=0.2346) != path


def test_cache_key_ignores_spelling_of_defaults():
    # passing a default value explicitly renders the same robot under the same key
    explicit = toolkit.urdf_path("katana_6m180", a3=0.139)
    assert explicit == toolkit.urdf_path("katana_6m180", a3="0.139")


def test_overrides_reach_the_model():
    robot = toolkit.load("katana_6m90b", a2=0.3, j2_upper=1.0, m_link2=2.0)
    assert robot.joints.upper[1] == pytest.approx(1.0)
    link2 = robot.model.getJointId("joint2")
    assert robot.model.inertias[link2].mass == pytest.approx(2.0)
    T = robot.fk(np.zeros(6), "link3")
    assert T[0, 3] == pytest.approx(0.3)
    assert "a2=0.3" in toolkit.urdf_text("katana_6m90b", a2=0.3)


def test_defaults_resolved_per_variant():
    assert resolve_arguments("katana_6m180")["a5"] == pytest.approx(0.1555)
    assert resolve_arguments("katana_6m90a")["a5"] == pytest.approx(0.1505)
    assert resolve_arguments("katana_6m90a")["j1_lower"] == pytest.approx(np.radians(-169.5))


@pytest.mark.parametrize(
    ("params", "message"),
    [
        ({"a2": -0.1}, "'a2' must be > 0"),
        ({"a3": 0}, "'a3' must be > 0"),
        ({"m_link4": -1}, "'m_link4' must be > 0"),
        ({"j3_lower": 2.5}, "lower limit j3_lower=2.5 must be below upper limit j3_upper"),
        ({"j1_upper": -3.0}, "lower limit j1_lower"),
        ({"wingspan": 1.0}, "unknown argument 'wingspan'; valid arguments: a2"),
        ({"variant": "6m90a"}, "fixed"),
        ({"a2": float("nan")}, "finite"),
        ({"a2": "long"}, "must be a number"),
        ({"a2": True}, "must be a number"),
        ({"j6_lower": 0.0}, "unknown argument 'j6_lower'"),
    ],
)
def test_invalid_arguments_raise_before_pinocchio(params, message):
    with pytest.raises(toolkit.InvalidParameterError, match=message):
        toolkit.load("katana_6m180", **params)


def test_unknown_model_lists_valid_names():
    with pytest.raises(toolkit.UnknownModelError, match="katana_6m180") as err:
        toolkit.urdf_text("katana_7m")
    assert err.value.valid == toolkit.available_models()


def test_model_arguments_lists_user_arguments():
    args = toolkit.model_arguments("katana_6m90a")
    assert {"a2", "a3", "a4", "a5", "j6_lower", "m_gripper"} <= set(args)
    assert "variant" not in args
    assert "j6_lower" not in toolkit.model_arguments("katana_6m180")


def test_read_only_cache_falls_back(tmp_path, monkeypatch):
    locked = tmp_path / "locked"
    locked.mkdir()
    os.chmod(locked, 0o500)
    monkeypatch.setenv("TOOLKIT_CACHE_DIR", str(locked / "sub"))
    try:
        if os.access(locked, os.W_OK):  # root ignores permissions: use a file as the folder
            os.chmod(locked, 0o700)
            (locked / "sub").write_text("not a folder")
        path = toolkit.urdf_path("katana_6m180", a2=0.2222)
        assert path.is_file() and locked not in path.parents
    finally:
        os.chmod(locked, 0o700)


def test_default_values_passed_explicitly_render_the_same_text():
    explicit = toolkit.urdf_text("bending", links=1, n=5)
    assert explicit == toolkit.urdf_text("bending")
    assert "with default arguments" in explicit
    assert "with n=3" in toolkit.urdf_text("bending", n=3, links=1)


def _chain_text(n: int) -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(n + 1))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(n)
    )
    return f'<robot name="long">{links}{joints}</robot>'


BOMB = """<?xml version="1.0"?>
<robot name="bomb" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:macro name="b" params="n">
    <xacro:if value="${n > 0}">
      <xacro:b n="${n - 1}"/><xacro:b n="${n - 1}"/>
    </xacro:if>
  </xacro:macro>
  <link name="base"/>
  <xacro:b n="40"/>
</robot>
"""


def test_a_description_beyond_the_link_limit_is_refused_before_parsing(tmp_path):
    """4,000 links crashed the process (SIGSEGV) inside Pinocchio's recursive parser."""
    from toolkit.descriptions import MAX_LINKS

    path = tmp_path / "long.urdf"
    path.write_text(_chain_text(4000))
    with pytest.raises(toolkit.ModelLoadError, match=f"more than the {MAX_LINKS:,}"):
        toolkit.load_urdf(path)
    assert toolkit.load_urdf(_chain_text(50)).nq == 50


def test_a_description_beyond_the_size_limit_is_refused(tmp_path, monkeypatch):
    from toolkit.descriptions import files as descriptions

    monkeypatch.setattr(descriptions, "MAX_FILE_BYTES", 2000)
    path = tmp_path / "big.urdf"
    path.write_text(_chain_text(30))
    with pytest.raises(toolkit.ModelLoadError, match="bytes, more than"):
        toolkit.load_urdf(path)


def test_a_xacro_macro_bomb_stops_and_frees_the_lock(tmp_path, monkeypatch):
    """2^40 expansions hung while holding the xacro lock; the budget stops it, and the next
    render (another thread's, a catalogue model) goes on."""
    from toolkit.descriptions import render

    monkeypatch.setattr(render, "XACRO_SECONDS", 1.0)
    path = tmp_path / "bomb.urdf.xacro"
    path.write_text(BOMB)
    with pytest.raises(toolkit.RenderError, match=r"expansion of .* stopped"):
        toolkit.load_urdf(path)
    assert toolkit.load("scara").nq == 3
    assert len(toolkit.urdf_text("cartesian", a=0.7)) > 100
