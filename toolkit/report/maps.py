"""Report section of the workspace maps: a coarse UR5 reachability map alone in space and
on a table (self-collision and the table), the Katana 6M180's reach with and without its
floor, and its backlash-accuracy map at 0.5 kg ([P1]'s question asked over the
workspace)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from .. import maps
from ..collision import Scene
from ..papers.backlash import Backlash
from ..robot import Robot, load, load_example
from .checks import Section, save_figure

__all__ = ["maps_section"]


def maps_section() -> Section:
    """Workspace maps: UR5 reachability (10 cm, 20 orientations), Katana backlash (0.5 kg)."""
    sec = Section("Workspace maps: reachability (UR5) and backlash accuracy (Katana 6M180)")
    ur5 = load_example("ur5")
    alone, reach = _ur5_maps(sec, ur5)
    _katana_floor(sec)
    layer = Backlash(load("katana_6m180"), payload=0.5)
    accuracy = maps.backlash_accuracy(
        layer, voxel=0.05, orientations=6, position_only=True, payloads=(0.5,),
        compensate=True, workers=1,
    )  # fmt: skip
    assert accuracy.compensated_max is not None  # compensate=True
    worst = float(np.nanmax(accuracy.compensated_max))
    sec.check(
        "Katana 6M180, 0.5 kg: compensation removes the backlash error in every voxel where "
        "the compensated command is inside the limits",
        worst,
        1e-9,
        " m",
    )
    reached = reach.index > 0
    reached_alone = alone.index > 0
    errors = accuracy.p95[0, 0][accuracy.reachable]
    radial = np.linalg.norm(accuracy.centers[..., :2], axis=-1)[accuracy.reachable]
    finite = np.isfinite(errors)
    trend = float(np.corrcoef(radial[finite], errors[finite])[0, 1])
    sec.markdown += [
        f"UR5: {reach.index.size:,} voxels of 10 cm; alone in space {int(reached_alone.sum()):,} "
        f"are reached in at least one of 20 tool orientations (mean index "
        f"{alone.index[reached_alone].mean():.2f}, {alone.figures['seconds']:.1f} s); standing "
        f"on a table, without hitting it or itself, {int(reached.sum()):,} (mean index "
        f"{reach.index[reached].mean():.2f}, {reach.figures['solves']:,.0f} IK solves, "
        f"{reach.figures['seconds']:.1f} s). Katana 6M180 with 0.5 kg: over "
        f"{int(accuracy.reachable.sum()):,} reached voxels of 5 cm (6 IK solutions each), the "
        f"95th-percentile tool position error from backlash ranges "
        f"{1e3 * np.nanmin(errors):.1f}-{1e3 * np.nanmax(errors):.1f} mm (delta = "
        f"{layer.delta[0]:g} rad, k_H = {layer.k_h[0]:g}); its correlation with the horizontal "
        f"distance from the base axis (the lever of gravity on the shoulder) is {trend:.2f}.",
    ]

    def draw_reach(path: Path) -> None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 4, figsize=(19.5, 4.6), layout="constrained")
        maps.draw_slices(alone, heights=[0.5], axes=axes[:2], title=" ")
        maps.draw_slices(reach, heights=[0.5], axes=axes[2:], title=" ")
        labels = ["alone in space"] * 2 + ["on a table, collision-free"] * 2
        for ax, what in zip(axes, labels, strict=True):
            ax.set_title(f"{ax.get_title()}\n{what}", fontsize=10)
        axes[0].figure.suptitle("UR5: reachability index, voxel 0.1 m", fontsize=10)
        save_figure(axes[0], path, dpi=90)

    def draw_accuracy(path: Path) -> None:
        axes = maps.draw_slices(accuracy, heights=[0.2])
        save_figure(axes[0], path, dpi=90)

    sec.figures += [("map_ur5_reach.png", draw_reach), ("map_katana_backlash.png", draw_accuracy)]
    return sec


def _ur5_maps(sec: Section, ur5: Robot) -> tuple[maps.ReachabilityMap, maps.ReachabilityMap]:
    """The UR5's map alone in space and on a table (collision-free), checked."""
    table = Scene().add_box("table", [1.6, 1.6, 0.04], [0.0, 0.0, -0.021], support=True)
    alone = maps.reachability(ur5, voxel=0.1, orientations=20, workers=1, collision_free=False)
    reach = maps.reachability(ur5, voxel=0.1, orientations=20, workers=1, scene=table)
    _check_landing(sec, ur5, reach)
    _check_collisions(sec, ur5, reach, table)
    return alone, reach


def _katana_floor(sec: Section) -> None:
    """The Katana on the floor of its template reaches no voxel below it."""
    katana = load("katana_6m180")
    k_alone = maps.reachability(
        katana, voxel=0.1, position_only=True, workers=1, collision_free=False
    )
    k_floor = maps.reachability(katana, voxel=0.1, position_only=True, workers=1)
    below = k_floor.centers[..., 2] < 0.0
    sec.check(
        "Katana 6M180 on its floor (self-collision and the template's floor): reached voxels "
        f"below the floor (without collisions: {int((k_alone.index[below] > 0).sum())})",
        float((k_floor.index[below] > 0).sum()),
        0.0,
    )


def _check_collisions(
    sec: Section, robot: object, reach: maps.ReachabilityMap, scene: Scene
) -> None:
    """No reached voxel's best q hits the robot itself or the table (checked again on a
    fresh copy of the robot, so a checker built once for the map is not trusted)."""
    import pickle

    fresh = pickle.loads(pickle.dumps(robot))
    q = reach.best_q[reach.index > 0]
    sec.check(
        "UR5 on a table: reached voxels whose best q collides with the robot or the table "
        "(a fresh checker)",
        float(np.sum(fresh.in_collision(q, scene))),
        0.0,
    )


def _check_landing(sec: Section, robot: object, reach: maps.ReachabilityMap) -> None:
    """Every reached voxel's best q, through Pinocchio directly, lands on its centre in its
    orientation."""
    model = robot.model  # type: ignore[attr-defined]
    data = model.createData()
    fid = robot.frames.id(None)  # type: ignore[attr-defined]
    worst = 0.0
    for ijk in np.argwhere(reach.index > 0):
        i = tuple(ijk)
        pin.framesForwardKinematics(model, data, reach.best_q[i])
        pose = data.oMf[fid]
        worst = max(
            worst,
            float(np.linalg.norm(pose.translation - reach.centers[i])),
            float(np.abs(pose.rotation - reach.best_rotation[i]).max()),
        )
    sec.check(
        "UR5 reachability map: every reached voxel's q puts the tool on the voxel centre in "
        "its orientation (independent Pinocchio FK)",
        worst,
        1e-5,
    )
