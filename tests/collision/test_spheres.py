"""Sphere covers of collision shapes (toolkit.collision.sphere_model): every point of every
surface inside a sphere, checked on points drawn on the shapes themselves (the meshes'
own triangles, the primitives' true surfaces), at random configurations."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

import toolkit
from toolkit.collision import sphere_model
from toolkit.collision.checker import robot_geometry
from toolkit.collision.covers import cover as _cover
from toolkit.collision.covers import surface_triangles

RNG = np.random.default_rng(7)


def _on_triangles(tris: np.ndarray, per: int) -> np.ndarray:
    """``per`` random points on each triangle (barycentric), edges and corners included."""
    u = RNG.random((len(tris), per, 2))
    flip = u.sum(axis=2) > 1
    u[flip] = 1 - u[flip]
    a, b, c = tris[:, None, 0], tris[:, None, 1], tris[:, None, 2]
    inner = a + u[..., :1] * (b - a) + u[..., 1:] * (c - a)
    return np.concatenate([inner.reshape(-1, 3), tris.reshape(-1, 3)])


def _covered(points: np.ndarray, centers: np.ndarray, radii: np.ndarray) -> np.ndarray:
    d = np.linalg.norm(points[:, None, :] - centers[None], axis=2)
    return (d <= radii[None] * (1 + 1e-12) + 1e-12).any(axis=1)


@pytest.mark.parametrize("name", ["panda", "ur5", "katana_6m180"])
def test_every_point_of_every_surface_is_inside_a_sphere_at_random_configurations(name):
    robot = toolkit.load(name) if name.startswith("katana") else toolkit.load_example(name)
    model = sphere_model(robot, per_shape=6)
    geom, _ = robot_geometry(robot)
    data, gdata = robot.model.createData(), pin.GeometryData(geom)
    for q in robot.random_q(3, seed=5):
        pin.forwardKinematics(robot.model, data, q)
        pin.updateGeometryPlacements(robot.model, data, geom, gdata)
        world = model.world(robot.model, q)
        for k, obj in enumerate(geom.geometryObjects):
            tris = surface_triangles(obj.geometry)
            if tris is None:
                continue
            M = gdata.oMg[k]  # the shape's pose by Pinocchio's geometry placements
            points = _on_triangles(tris, 8) @ M.rotation.T + M.translation
            mine = np.array([s == obj.name for s in model.shapes])
            assert _covered(points, world[mine], model.radii[mine]).all(), obj.name


@pytest.mark.parametrize(
    "shape",
    ["box", "cylinder", "capsule", "cone"],
)
def test_a_primitives_true_surface_is_covered(shape):
    import coal

    made = {"box": lambda: coal.Box(0.3, 0.1, 0.05),
            "cylinder": lambda: coal.Cylinder(0.05, 0.4),
            "capsule": lambda: coal.Capsule(0.05, 0.3),
            "cone": lambda: coal.Cone(0.08, 0.2)}  # fmt: skip
    primitive = made[shape]()
    centers, radii = _cover(surface_triangles(primitive), 6, np.random.default_rng(0))
    n = 20_000
    if shape == "box":  # points on the six faces
        h = np.asarray(primitive.halfSide)
        P = RNG.uniform(-h, h, (n, 3))
        axis = RNG.integers(3, size=n)
        P[np.arange(n), axis] = np.sign(RNG.random(n) - 0.5) * h[axis]
    else:  # points on the side, the ends (a capsule's caps) of the true shape
        r, half = primitive.radius, primitive.halfLength
        t, z = RNG.uniform(0, 2 * math.pi, n), RNG.uniform(-half, half, n)
        rr = r * (half - z) / (2 * half) if shape == "cone" else np.full(n, r)
        P = np.column_stack([rr * np.cos(t), rr * np.sin(t), z])
        if shape == "capsule":
            d = RNG.normal(size=(n, 3))
            d = r * d / np.linalg.norm(d, axis=1, keepdims=True)
            up = np.array([0.0, 0.0, half])
            P = np.concatenate([P, d + up, d - up])
    assert _covered(P, centers, radii).all()


def test_a_convex_hull_without_faces_is_held_by_one_sphere():
    import coal

    points = [np.array([x, y, z], dtype=float) for x in (0, 0.1) for y in (0, 0.2)
              for z in (0, 0.3)]  # fmt: skip
    hull = coal.ConvexBase.convexHull(points, False, "")
    pieces = surface_triangles(hull)
    centers, radii = _cover(pieces, 6, np.random.default_rng(0))
    assert len(radii) == 1
    inside = RNG.uniform(0, 1, (5000, 3)) * [0.1, 0.2, 0.3]  # the hull is this box
    assert _covered(inside, centers, radii).all()


def test_more_spheres_fit_closer():
    panda = toolkit.load_example("panda")
    few, many = sphere_model(panda, per_shape=2), sphere_model(panda, per_shape=16)
    assert len(many) > len(few)
    assert np.median(list(many.excess.values())) < np.median(list(few.excess.values()))
    assert all(v >= 1.0 for v in many.excess.values())  # the union holds the shape's shell


def test_bad_requests_are_refused():
    panda = toolkit.load_example("panda")
    for bad in (0, 1000, -1, "8"):
        with pytest.raises(toolkit.ToolkitError, match="per_shape"):
            sphere_model(panda, per_shape=bad)
    with pytest.raises(toolkit.ToolkitError, match="seed"):
        sphere_model(panda, seed=-1)
