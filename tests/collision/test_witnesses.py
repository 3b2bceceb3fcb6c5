"""The pre-filter's proof of a collision by a point of a link's surface inside a solid
(``toolkit.collision.bound_kernels._witnessed``): the points lie on the surfaces, the
point-in-solid test agrees with coal's signed distance, and every collision it proves is
coal's, on the UR5 in a table, a sphere and a cylinder."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

import toolkit
import toolkit.robot
from toolkit import Scene
from toolkit.collision.bound_kernels import CLOSE, FREE, HIT
from toolkit.collision.bounds import WITNESSES
from toolkit.collision.solid_kernels import DEPTH, in_solid

SHAPES = {
    "box": (coal.Box(0.3, 0.2, 0.1), 1),
    "sphere": (coal.Sphere(0.12), 2),
    "cylinder": (coal.Cylinder(0.05, 0.3), 3),
    "capsule": (coal.Capsule(0.04, 0.2), 4),
}


def _placed(shape, kind, pose):
    """A placed box row P (1, 12), box (1, 15) and radius (1, 3) of ``shape`` at ``pose``, as
    :class:`toolkit.collision.bounds.Bounds` packs them (the shape's frame is its box's)."""
    shape.computeLocalAABB()
    low, high = np.asarray(shape.aabb_local.min_), np.asarray(shape.aabb_local.max_)
    box = np.zeros((1, 15))
    box[0, 12:] = (high - low) / 2
    P = np.zeros((1, 12))
    P[0, :3] = pose.act((high + low) / 2)
    P[0, 3:] = pose.rotation.ravel()
    inner = {1: box[0, 12:].min(), 2: getattr(shape, "radius", 0.0)}.get(kind, 0.0)
    return P, box, np.array([[np.linalg.norm(box[0, 12:]), inner, float(kind)]])


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_a_point_is_inside_a_solid_as_coal_measures_it(name):
    """At 4,000 points near a placed solid, ``in_solid`` says inside exactly where coal's
    signed distance to a tiny sphere there is below -DEPTH (up to 1e-9 m of rounding)."""
    shape, kind = SHAPES[name]
    pose = pin.SE3(pin.exp3(np.array([0.3, -0.7, 0.4])), np.array([0.2, -0.1, 0.5]))
    P, box, radius = _placed(shape, kind, pose)
    rng = np.random.default_rng(3)
    local = rng.uniform(-1.3, 1.3, (4000, 3)) * box[0, 12:]  # about the shape's box
    points = local @ pose.rotation.T + P[0, :3]
    dot = coal.Sphere(1e-9)
    request = coal.DistanceRequest()
    request.enable_signed_distance = True
    inside, depth = [], []
    for x in points:
        result = coal.DistanceResult()
        d = coal.distance(shape, coal.Transform3s(pose.rotation, pose.translation), dot,
                          coal.Transform3s(np.eye(3), x), request, result)  # fmt: skip
        depth.append(d)
        inside.append(in_solid(P, box, radius, 0, *x))
    inside, depth = np.array(inside), np.array(depth)
    sure = np.abs(depth + DEPTH) > 1e-7  # away from the test's own boundary
    assert inside.sum() > 300 and (~inside).sum() > 300
    assert np.array_equal(inside[sure], depth[sure] < -DEPTH)


def test_no_solid_no_point_inside():
    """A mesh or a plane (kind 0) holds no point: the test never proves against them."""
    P, box, radius = _placed(coal.Box(1.0, 1.0, 1.0), 1, pin.SE3.Identity())
    radius[0, 2] = 0.0
    assert not in_solid(P, box, radius, 0, 0.0, 0.0, 0.0)


@pytest.fixture(scope="module")
def ur5():
    return toolkit.load_example("ur5")


def test_the_points_lie_on_the_links_surfaces_and_their_spheres_hold_them(ur5):
    """Every point of every link's surface points is within 1 um of its mesh (coal), in its
    cover sphere, and a link has at most WITNESSES; the meshes have some."""
    checker = toolkit.robot.checker_for(ur5, None)
    bounds, geom = checker.bounds, checker.geom
    cstart, csphere, _ = bounds.covers()
    wstart, wpoint = bounds.witnesses()
    dot = coal.Sphere(1e-6)
    counted = 0
    for g in range(checker.robot_count):
        obj = geom.geometryObjects[g]
        M = obj.placement  # joint frame -> the shape's
        first, last = int(wstart[cstart[g]]), int(wstart[cstart[g + 1]])
        assert last - first <= WITNESSES
        for s in range(cstart[g], cstart[g + 1]):
            pts = wpoint[wstart[s] : wstart[s + 1]]
            assert (np.linalg.norm(pts - csphere[s, :3], axis=1) <= csphere[s, 3] + 1e-9).all()
        for x in wpoint[first:last]:
            local = M.actInv(x)
            result, at = coal.CollisionResult(), coal.Transform3s(np.eye(3), local)
            coal.collide(obj.geometry, coal.Transform3s(), dot, at, coal.CollisionRequest(), result)
            assert result.isCollision(), (obj.name, local)
        counted += last - first
    assert counted > 100


def _cell() -> Scene:
    return (
        Scene()
        .add_box("table", [1.6, 1.6, 0.04], [0.0, 0.0, -0.021], support=True)
        .add_sphere("ball", 0.12, [0.35, 0.2, 0.35])
        .add_cylinder("post", 0.05, 0.8, [-0.3, 0.35, 0.4])
    )


def test_every_collision_the_points_prove_is_coals(ur5):
    """On the UR5 in a table, a sphere and a cylinder, 4,000 random configurations: every one
    the pre-filter calls colliding collides for coal on every pair, the batch answer is
    coal's, and the surface points decide most of the colliding ones (without them coal
    decided them: the share of HIT falls)."""
    scene = _cell()
    checker = toolkit.robot.checker_for(ur5, scene)
    Q = ur5.random_q(4000, seed=31)
    state = checker.bounds.decide(Q)
    exact = checker._exact_many(Q)
    assert exact[state == HIT].all()
    assert not exact[state == FREE].any()
    assert np.array_equal(checker.in_collision_many(Q), exact)
    bounds = checker.bounds
    kept = bounds._covers
    assert kept is not None
    bounds._covers = (*kept[:3], np.zeros_like(kept[3]), np.zeros((0, 3)))
    try:
        without = bounds.decide(Q)
    finally:
        bounds._covers = kept
    assert (state == HIT).sum() > 0.6 * exact.sum()
    assert (without == HIT).sum() < 0.2 * exact.sum()
    assert ((without == CLOSE) & (state == HIT)).sum() == (state == HIT).sum() - (
        without == HIT
    ).sum()


@pytest.mark.parametrize("edge", [0.1, 1.0, 5.0])
def test_a_box_s_surface_points_lie_on_every_face_and_are_capped(edge):
    """A box link's points: on its surface (a coordinate at a face, within rounding), on
    all six faces, at most the cap, also for a box far larger than the spacing (its cut
    coarsened from its area first, not cut to millions of pieces)."""
    from toolkit.collision.covers import surface_points

    half = edge / 2
    points = surface_points(coal.Box(edge, edge, edge), 0.015, 512)
    assert 0 < len(points) <= 512
    on = np.isclose(np.abs(points), half, rtol=0, atol=1e-12)
    assert on.any(axis=1).all() and (np.abs(points) <= half + 1e-12).all()
    faces = {(axis, sign) for p, o in zip(points, on, strict=True) for axis in np.flatnonzero(o)
             for sign in [np.sign(p[axis])]}  # fmt: skip
    assert len(faces) == 6
