"""Written by the landed version (commit ba39789) before the package was reorganised:
what tests/test_legacy.py loads with the code of today. Run from the repository root
with that version installed; kept for reference (it is not a test)."""

import pathlib
import pickle
import shutil

import numpy as np

import toolkit
from toolkit import backlash, maps

out = pathlib.Path("tests/data/legacy")
robot = toolkit.load("katana_6m180")
scene = toolkit.Scene().add_box("table", size=(0.5, 0.5, 0.02), pose=(0.6, 0, 0.1))
objs = {
    "robot": robot,
    "layer": backlash.Backlash(robot, delta=0.035, k_h=0.2, payload=0.5),
    "options": toolkit.IKOptions(tol=1e-7, restarts=7),
    "result": robot.ik(robot.fk([0.1, 0.5, 0.3, -0.8, 0.2])),
    "batch": robot.ik_batch(
        robot.fk(np.array([[0.1, 0.5, 0.3, -0.8, 0.2]])), mask=[1, 1, 1, 1, 1, 0]
    ),
    "scene": scene,
    "q": np.array([0.1, 0.5, 0.3, -0.8, 0.2]),
    "fk": robot.fk([0.1, 0.5, 0.3, -0.8, 0.2]),
}
(out / "objects.pkl").write_bytes(pickle.dumps(objs, protocol=4))
store = out / "katana_map.zarr"
shutil.rmtree(store, ignore_errors=True)
m = maps.reachability(
    robot,
    voxel=0.15,
    position_only=True,
    orientations=2,
    store=str(store),
    collision_free=False,
    workers=1,
)
np.save(out / "katana_map_index.npy", m.index)
print(m.index.shape, np.nanmean(m.index), type(scene))
