"""A corpus of real descriptions nobody here wrote: every ``.urdf`` and ``.urdf.xacro``
shipped by ``rtb-data`` (a test-only dependency) loads, or raises a ``ToolkitError`` that
names the cause; every loaded robot's FK agrees with yourdfpy on the rendered URDF."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yourdfpy

import toolkit
from toolkit.errors import ModelLoadError

rtbdata = pytest.importorskip("rtbdata", reason="rtb-data is in the test extra")
ROOT = Path(rtbdata.__file__).parent
FILES = sorted(p for p in ROOT.rglob("*") if p.name.endswith((".urdf", ".urdf.xacro")))

# what cannot load, and the words the error must carry (the cause, not just "invalid")
EXPECTED_FAILURES = {
    "data/test.urdf": "XML_ERROR_PARSING_TEXT",  # the file holds the word "hello"
    # macro files without a robot of their own
    "hokuyo_ust-10lx_mount.urdf.xacro": "No name given for the robot",
    "microstrain_imu.urdf.xacro": "No name given for the robot",
    # their package (a laser driver) is not shipped
    "sick_lms1xx_mount.urdf.xacro": "package 'lms1xx' not found",
    "sick_s300_mount.urdf.xacro": "package 'lms1xx' not found",
}


def _expected_failure(path: Path) -> str | None:
    rel = path.relative_to(ROOT).as_posix()
    return EXPECTED_FAILURES.get(rel) or EXPECTED_FAILURES.get(path.name)


def test_the_corpus_is_there():
    assert len(FILES) >= 35  # 38 in rtb-data 2.0.0, 29 of them .urdf.xacro or in xacro/
    assert sum(p.name.endswith(".urdf.xacro") for p in FILES) >= 25


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_loads_or_names_the_cause_and_fk_agrees_with_yourdfpy(path):
    cause = _expected_failure(path)
    if cause is not None:
        with pytest.raises(ModelLoadError, match=cause):
            toolkit.load_urdf(path)
        return
    robot = toolkit.load_urdf(path)
    assert robot.nq >= 1
    # the tip is carried by a moving joint: FK must change somewhere
    rendered = yourdfpy.URDF.load(
        str(robot.urdf_path),
        build_scene_graph=True,
        load_meshes=False,
        build_collision_scene_graph=False,
    )
    assert set(rendered.actuated_joint_names) >= set(robot.joints.names)
    root = rendered.base_link
    rng = np.random.default_rng(len(path.name))
    poses = []
    for _ in range(5):
        q = robot.random_q(seed=rng)
        values = robot.joints.angles(q)
        rendered.update_cfg(dict(zip(robot.joints.names, values, strict=True)))
        theirs = rendered.get_transform(robot.tip, root)
        ours = robot.fk(q)
        np.testing.assert_allclose(ours, theirs, atol=1e-9, err_msg=robot.tip)
        poses.append(ours[:3, 3])
    assert np.ptp(np.array(poses), axis=0).max() > 1e-6, "the tip never moves"
