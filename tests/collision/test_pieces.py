"""A mesh as a few convex pieces (toolkit.collision.pieces): the pieces hold every triangle,
their least distance never exceeds coal's distance of the meshes and is close to it, and
the exact certificate's lower bounds take it where the whole hulls overlap."""

from __future__ import annotations

import coal
import numpy as np
import pinocchio as pin
import pytest

import toolkit
from toolkit.collision import pieces
from toolkit.planning.sweep import SLACK, SLACK_SHARE
from toolkit.robot import checker_for
from toolkit.robot.plans import certain_test

UR10 = toolkit.load_example("ur10")


def _mesh(vertices: np.ndarray, triangles: np.ndarray) -> coal.BVHModelOBBRSS:
    mesh = coal.BVHModelOBBRSS()
    mesh.beginModel(len(triangles), len(vertices))
    for v in vertices:
        mesh.addVertex(v)
    for t in triangles:
        mesh.addTriangle(*(vertices[i] for i in t))
    mesh.endModel()
    return mesh


def _meshes() -> list[tuple[str, object]]:
    checker = checker_for(UR10, toolkit.Scene())
    return [(o.name, o.geometry) for o in checker.geom.geometryObjects[: checker.robot_count]
            if isinstance(o.geometry, coal.BVHModelBase)]  # fmt: skip


@pytest.mark.parametrize(("name", "mesh"), _meshes())
def test_every_triangle_lies_in_a_piece(name, mesh):
    """Each triangle's corners and centre are inside one of the mesh's pieces (coal's
    distance from a point to it is 0): the pieces hold the mesh."""
    split = pieces.pieces_of(mesh)
    assert split is not None and len(split.hulls) == pieces.PIECES, name
    vertices = np.asarray(mesh.vertices())
    point = coal.Sphere(1e-9)
    request, at = coal.DistanceRequest(), coal.Transform3s()
    for i in range(0, mesh.num_tris, 7):
        t = mesh.tri_indices(i)
        corners = vertices[[t[0], t[1], t[2]]]
        for p in [*corners, corners.mean(axis=0)]:
            gaps = []
            for hull in split.hulls:
                result = coal.DistanceResult()
                coal.distance(point, coal.Transform3s(np.eye(3), p), hull, at, request, result)
                gaps.append(result.min_distance)
            assert min(gaps) <= 1e-7, (name, i)
        # and within its piece's ball
    assert np.all(np.isfinite(split.radii)) and np.all(split.radii > 0)


def test_the_pieces_distance_is_a_lower_bound_of_the_meshes_and_close_to_it():
    """Every pair of the UR10's own meshes at 60 random configurations: the pieces' least
    distance never exceeds coal's distance of the meshes (less the certificate's slack),
    and is at least 0.9 of it at the median over the pairs apart."""
    checker = checker_for(UR10, toolkit.Scene())
    geom, model = checker.geom, UR10.model
    data, gdata = model.createData(), pin.GeometryData(geom)
    split = [pieces.pieces_of(o.geometry) for o in geom.geometryObjects]
    ratios = []
    for q in UR10.random_q(60, seed=4):
        pin.updateGeometryPlacements(model, data, geom, gdata, q)
        for k, pair in enumerate(geom.collisionPairs):
            a, b = split[pair.first], split[pair.second]
            if a is None or b is None:
                continue
            lower = pieces.pieces_distance(a, gdata.oMg[pair.first], b, gdata.oMg[pair.second])
            exact = pin.computeDistance(geom, gdata, k).min_distance
            assert lower <= max(exact, 0.0) + SLACK + SLACK_SHARE * abs(exact)
            if exact > 1e-3:
                ratios.append(lower / exact)
    assert len(ratios) > 200 and np.median(ratios) >= 0.9


def test_meshes_the_pieces_cannot_hold_have_none_and_other_shapes_are_one_piece():
    """A mesh of fewer triangles than pieces, of more than MOST, or a flat one (a group whose
    hull coal cannot make), has no pieces (the meshes' own distance is asked); a box is one
    piece, itself, always asked (no ball)."""
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    assert pieces.pieces_of(_mesh(square, np.array([[0, 1, 2], [0, 2, 3]]))) is None
    grid = np.array([[x, y, 0.0] for x in range(6) for y in range(6)])
    flat = [[6 * x + y, 6 * x + y + 1, 6 * x + y + 7] for x in range(5) for y in range(5)]
    assert pieces.pieces_of(_mesh(grid, np.array(flat))) is None
    rng = np.random.default_rng(1)  # a mesh of more triangles than MOST: none either
    cloud = rng.normal(size=(200, 3))
    many = rng.integers(0, 200, size=(pieces.MOST + 1, 3))
    assert pieces.pieces_of(_mesh(cloud, many)) is None
    box = coal.Box(0.1, 0.2, 0.3)
    one = pieces.pieces_of(box)
    assert one is not None and one.hulls == [box] and np.isinf(one.radii).all()


def test_the_certificate_takes_the_pieces_where_the_hulls_overlap(monkeypatch):
    """The UR10's two pairs left to the exact certificate (base against upper arm, forearm
    against wrist 2: their whole hulls overlap): the lower bounds at 40 random
    configurations never exceed coal's distance, and coal's distance of the meshes is asked
    for few of them (the pieces answer the rest)."""
    checker = checker_for(UR10, toolkit.Scene())
    test = certain_test(UR10, checker)
    assert test is not None and test.deferred.size == 2
    parts = checker.parts
    asked = []
    real = pin.computeDistance

    def counted(*args):
        asked.append(1)
        return real(*args)

    Q = UR10.random_q(40, seed=9)
    exact = np.array([parts.distances(q, test.deferred) for q in Q])
    monkeypatch.setattr(pin, "computeDistance", counted)
    lower = np.array([parts.lower_bounds(q, test.deferred, np.full(2, 0.5)) for q in Q])
    assert (lower <= exact + SLACK + SLACK_SHARE * np.abs(exact)).all()
    assert len(asked) < 0.25 * lower.size


def test_a_shape_met_again_through_a_new_checker_is_not_split_again(monkeypatch):
    """A robot's links are one set of coal objects in every scene's checker: their pieces
    and hulls are made once a process (kept_for, by coal's own address), not per checker."""
    made = []
    real = pieces._split
    monkeypatch.setattr(pieces, "_split", lambda *a: made.append(1) or real(*a))
    monkeypatch.setattr(pieces, "_BY_SHAPE", {})
    monkeypatch.setattr(pieces, "_KEPT", {})
    scenes = (toolkit.Scene(), toolkit.Scene().add_box("b", [0.1] * 3, [2, 2, 2]))
    shapes = [checker_for(UR10, s).geom.geometryObjects[1].geometry for s in scenes]
    first = [pieces.kept_for(s, "pieces_of", pieces.pieces_of) for s in shapes]
    assert first[0] is first[1] and len(made) == 1
