"""The references of rtcd.oracle on cases whose answers are known."""
from __future__ import annotations

import math

import numpy as np
import pytest

import rtcd
from conftest import IDENTITY, pose

oracle = rtcd.oracle


@pytest.fixture(scope="module")
def unit_cube() -> rtcd.Mesh:
    return rtcd.gen.box([0.5, 0.5, 0.5])


def deep_of(rays: dict) -> np.ndarray:
    """Origins the reference is sure are inside: inside and beyond the margin."""
    deep = rays["inside"] & ~rays["near_surface"]
    if "deep" in rays:
        np.testing.assert_array_equal(rays["deep"], deep)
    return deep


def test_exact_inside_and_distance(unit_cube):
    exact = oracle.Exact(unit_cube)
    assert exact.closed
    points = np.array([[0, 0, 0], [0.4, 0.1, -0.2], [0.6, 0, 0], [0, 0, 2], [-0.49, 0.49, 0.49]])
    np.testing.assert_array_equal(exact.inside(points), [True, True, False, False, True])
    # Unsigned distance to the surface.
    np.testing.assert_allclose(exact.distance(points), [0.5, 0.1, 0.1, 1.5, 0.01], atol=1e-9)


def test_exact_first_hit(unit_cube):
    exact = oracle.Exact(unit_cube)
    origins = np.array([[0, 0, 0], [-2, 0.1, 0.2], [0, 0, 2]])
    directions = np.array([[1, 0, 0], [1, 0, 0], [0, 0, 1]])
    t, triangle = exact.first_hit(origins, directions)
    np.testing.assert_allclose(t[:2], [0.5, 1.5], atol=1e-9)
    normals = unit_cube.triangle_normals
    np.testing.assert_allclose(normals[triangle[0]], [1, 0, 0], atol=1e-6)   # leaves by the +x face
    np.testing.assert_allclose(normals[triangle[1]], [-1, 0, 0], atol=1e-6)  # enters by the -x face
    assert triangle[2] == -1 and not np.isfinite(t[2]), "the third ray misses"


def test_exact_rays_of_the_cube_case(unit_cube):
    """A's four +x corners are 0.1 inside B (half extent 0.6, at x = 1)."""
    b = rtcd.gen.box([0.6, 0.6, 0.6])
    rays = oracle.Exact(b).rays_from(unit_cube, IDENTITY, pose((1, 0, 0)), margin=1e-5)
    deep = deep_of(rays)
    assert len(deep) == len(unit_cube.vertices), "one row per ray origin: the source's vertices"
    np.testing.assert_array_equal(np.flatnonzero(deep), np.flatnonzero(unit_cube.vertices[:, 0] == 0.5))
    np.testing.assert_allclose(rays["depth"][deep], 0.1 * math.sqrt(3), atol=1e-6)
    assert np.all(rays["depth"][~deep] == -1.0)
    # Their true penetration: 0.1 to B's nearest faces, and where it lies.
    np.testing.assert_allclose(rays["penetration"][deep], 0.1, atol=1e-7)  # float coordinates
    assert np.all(rays["penetration"][~deep] == -1.0)
    corner = np.array([[-0.5, 0.5, 0.5]])  # A's corner (0.5, 0.5, 0.5) in B's frame
    np.testing.assert_allclose(oracle.Exact(b).distance(corner), [0.1], atol=1e-7)
    assert np.min(np.abs(oracle.Exact(b).closest_point(corner) - corner).sum(axis=1)) == pytest.approx(0.1, abs=1e-7)
    # The other way: none of B's corners is inside A.
    back = oracle.Exact(unit_cube).rays_from(b, pose((1, 0, 0)), IDENTITY, margin=1e-5)
    assert not np.any(deep_of(back))


def test_exact_edge_depths():
    """Bars laid crosswise, B sunk 0.01: B's lower long edges cross A 0.01 deep."""
    a, b = rtcd.gen.box([0.5, 0.05, 0.05]), rtcd.gen.box([0.05, 0.5, 0.05])
    depths = oracle.Exact(a).edge_depths(b, pose((0, 0, 0.09)), IDENTITY)
    assert len(depths) == len(rtcd.Shape(b).edges)
    crossing = depths > 0
    assert crossing.sum() >= 2
    np.testing.assert_allclose(depths[crossing], 0.01, atol=1e-6)


def test_fcl_collide_and_distance(unit_cube):
    big = rtcd.gen.box([0.6, 0.6, 0.6])
    a, b = oracle.Fcl(unit_cube), oracle.Fcl(big)
    touching = a.collide(IDENTITY, b, pose((1, 0, 0)))
    assert touching["colliding"]
    apart = a.collide(IDENTITY, b, pose((2, 0, 0)))
    assert not apart["colliding"]
    assert a.distance(IDENTITY, b, pose((2, 0, 0))) == pytest.approx(0.9, abs=1e-5)
    with_points = a.collide(IDENTITY, b, pose((1, 0, 0)), contacts=True)
    assert len(with_points["depth"]) > 0
    assert with_points["position"].shape == (len(with_points["depth"]), 3)


def test_fcl_agrees_with_rtcd_on_shapes():
    sphere, box = rtcd.Shape.sphere(0.5), rtcd.Shape.box([0.5, 0.5, 0.5])
    fs, fb = oracle.Fcl(sphere), oracle.Fcl(box)
    for x, expected in [(0.9, True), (1.1, False)]:
        mine = rtcd.query(sphere, box, IDENTITY, pose((x, 0, 0)), backend="embree")
        assert bool(mine.pairs.colliding[0]) == expected
        assert fs.collide(IDENTITY, fb, pose((x, 0, 0)))["colliding"] == expected
    assert fs.distance(IDENTITY, fb, pose((1.1, 0, 0))) == pytest.approx(0.1, abs=1e-4)


def test_gimpact_collides_the_cube_pair(unit_cube):
    a, b = oracle.Gimpact(unit_cube), oracle.Gimpact(rtcd.gen.box([0.6, 0.6, 0.6]))
    hit = a.collide(IDENTITY, b, pose((1, 0, 0)))
    assert hit["colliding"]
    assert len(hit["depth"]) > 0 and np.all(hit["depth"] > 0)
    assert not a.collide(IDENTITY, b, pose((2, 0, 0)))["colliding"]


def test_ccd_penetration_of_two_spheres():
    s = rtcd.Shape.sphere(0.5)
    result = oracle.ccd_penetration(s, IDENTITY, s, pose((0.9, 0, 0)))
    assert result["colliding"]
    assert result["depth"] == pytest.approx(0.1, abs=1e-3)
    apart = oracle.ccd_penetration(s, IDENTITY, s, pose((1.1, 0, 0)))
    assert not apart["colliding"]
