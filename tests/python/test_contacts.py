"""Contacts of hand-computed cases, checked column by column."""
from __future__ import annotations

import json
import math
import subprocess

import numpy as np
import pytest

import rtcd
from conftest import IDENTITY, pose, rotation_matrix, transform

VERTEX, EDGE, SPHERE = 0, 1, 2
FULL, ITERATIVE = 0, 1  # PairResult.mode
# The limits the hand-computed cube case was worked out for, and the thesis'
# ray contacts it measures (depth along each corner's diagonal).
CUBE_KNOBS = dict(distance_extension=0.1, displacement_threshold=0.05, max_walk_steps=32, nearest_surface=False)


def cube_case(backend: str) -> rtcd.StepResult:
    """Cube A (half extent 0.5) at the origin, cube B (0.6) at x = 1: A's four
    +x corners are 0.1 inside B's -x face."""
    a = rtcd.gen.box([0.5, 0.5, 0.5])
    b = rtcd.gen.box([0.6, 0.6, 0.6])
    return rtcd.query(a, b, [0, 0, 0, 1, 0, 0, 0], [1, 0, 0, 1, 0, 0, 0], backend=backend, **CUBE_KNOBS)


# OpenCL (PoCL on the CPU) is slow to start: this is the one test that uses it.
@pytest.mark.parametrize("backend", ["basic", "embree", "opencl"])
def test_cube_corners_in_a_bigger_cube(backend: str):
    r = cube_case(backend)
    c = r.contacts
    assert len(c) <= 5
    assert bool(r.pairs.colliding[0])
    assert r.pairs.max_depth[0] == pytest.approx(0.1 * math.sqrt(3), abs=1e-6)

    vertex = c.kind == VERTEX
    assert vertex.sum() == 4
    assert np.all(c.source[vertex] == 0), "the corners are A's"
    origin = c.origin[vertex]
    np.testing.assert_allclose(origin[:, 0], 0.5, atol=1e-7)
    np.testing.assert_allclose(np.abs(origin[:, 1:]), 0.5, atol=1e-7)
    # Each corner's inward ray runs toward A's centre: -(1, ±1, ±1)/√3, the
    # signs of y and z opposite to the corner's.
    expected = -np.column_stack([np.ones(4), np.sign(origin[:, 1]), np.sign(origin[:, 2])]) / math.sqrt(3)
    np.testing.assert_allclose(c.direction[vertex], expected, atol=1e-6)
    np.testing.assert_allclose(c.depth[vertex], 0.1 * math.sqrt(3), atol=1e-6)
    np.testing.assert_allclose(c.projected_depth[vertex], 0.1, atol=1e-6)
    np.testing.assert_allclose(c.normal[vertex], np.tile([-1.0, 0, 0], (4, 1)), atol=1e-6)
    np.testing.assert_allclose(c.push[vertex], np.tile([-0.1, 0, 0], (4, 1)), atol=1e-6)
    # Four distinct corners.
    assert len({tuple(np.sign(o[1:])) for o in origin}) == 4

    # B's edge across A's +x face may be reported from its middle.
    edge = c.kind == EDGE
    assert edge.sum() <= 1
    assert np.all(c.source[edge] == 1)
    np.testing.assert_allclose(c.origin[edge], np.tile([0.4, 0, 0], (edge.sum(), 1)), atol=1e-6)
    np.testing.assert_allclose(c.depth[edge], 0.1, atol=1e-6)
    np.testing.assert_allclose(c.push[edge], np.tile([0.1, 0, 0], (edge.sum(), 1)), atol=1e-6)
    assert vertex.sum() + edge.sum() == len(c), "no other kind of contact"


def test_cube_case_json_is_the_clis(cli, tmp_path):
    """StepResult.to_json() prints what `rtcd query --json` prints."""
    a, b = rtcd.gen.box([0.5, 0.5, 0.5]), rtcd.gen.box([0.6, 0.6, 0.6])
    a.save_obj(tmp_path / "a.obj")
    b.save_obj(tmp_path / "b.obj")
    r = rtcd.query(a, b, IDENTITY, [1, 0, 0, 1, 0, 0, 0], backend="embree", **CUBE_KNOBS)
    done = subprocess.run(
        [str(cli), "query", str(tmp_path / "a.obj"), str(tmp_path / "b.obj"), "--pose-b", "1 0 0 1 0 0 0",
         "--backend", "embree", "--distance-extension", "0.1", "--displacement-threshold", "0.05",
         "--max-walk-steps", "32", "--no-nearest-surface", "--json"], capture_output=True, text=True, timeout=60, check=True)
    expected = json.loads(done.stdout)
    mine = r.to_json(0)
    assert set(mine) == set(expected)
    assert mine["colliding"] == expected["colliding"]
    assert mine["max_depth"] == pytest.approx(expected["max_depth"], abs=1e-12)
    assert len(mine["contacts"]) == len(expected["contacts"])
    for got, want in zip(mine["contacts"], expected["contacts"]):
        assert set(got) == set(want)
        for key in ("kind", "source", "vertex", "triangle"):
            assert got[key] == want[key], key
        assert got["depth"] == pytest.approx(want["depth"], abs=1e-12)


def parse_obj(path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of an OBJ file, polygons fanned as (c0, ck, ck+1)."""
    vertices, triangles = [], []
    for line in path.read_text().splitlines():
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        if words[0] == "v":
            vertices.append([float(w) for w in words[1:4]])
        elif words[0] == "f":
            corners = [int(w.split("/")[0]) - 1 for w in words[1:]]
            for k in range(1, len(corners) - 1):
                triangles.append([corners[0], corners[k], corners[k + 1]])
    return np.array(vertices), np.array(triangles)


def test_mesh_ids_are_the_files(meshes_dir):
    path = meshes_dir / "box.obj"
    vertices, triangles = parse_obj(path)
    mesh = rtcd.Mesh.load(path)
    np.testing.assert_array_equal(mesh.vertices, vertices.astype(np.float32))
    np.testing.assert_array_equal(mesh.triangles, triangles)
    assert len(mesh) == len(triangles)

    # A turned a quarter about z and moved; B 1 along A's x: A's +x corners,
    # its file's vertices 0..3, are inside B.
    q = (math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4))
    pose_a = pose((0.3, -0.2, 0.1), q)
    pose_b = pose(pose_a[:3] + rotation_matrix(q) @ [1.0, 0, 0], q)
    r = rtcd.query(mesh, rtcd.gen.box([0.6, 0.6, 0.6]), pose_a, pose_b, backend="embree", **CUBE_KNOBS)
    c = r.contacts
    mine = (c.kind == VERTEX) & (c.source == 0)
    assert mine.sum() == 4
    ids = c.vertex[mine]
    assert set(ids.tolist()) == set(np.flatnonzero(vertices[:, 0] == 0.5).tolist())
    np.testing.assert_allclose(c.origin[mine], transform(pose_a, vertices[ids]), atol=1e-6)
    # Edge contacts name their vertex ids in the file's numbering too.
    assert np.all(c.edge[mine, 0] == ids) and np.all(c.edge[mine, 1] == ids)


@pytest.mark.parametrize("mode", ["full", "iterative", "auto"])
def test_bars_laid_crosswise(mode: str):
    """Two bars crossing like a plus sign, B sunk 0.01 into A: no vertex is
    inside the other bar; the crossing edges push A down and B up by 0.01."""
    a = rtcd.gen.box([0.5, 0.05, 0.05])
    b = rtcd.gen.box([0.05, 0.5, 0.05])
    at = [0, 0, 0.09, 1, 0, 0, 0]
    # A first step 7.5 mm deep, then B sinks to 1 cm: judged on the second,
    # which walks in the walking modes.
    narrow = rtcd.NarrowPhase("embree", mode=mode)
    body_a = narrow.add_body(narrow.add_shape(a), IDENTITY)
    body_b = narrow.add_body(narrow.add_shape(b), [0, 0, 0.0925, 1, 0, 0, 0])
    assert bool(narrow.detect([[body_a, body_b]]).pairs.colliding[0])
    narrow.set_pose(body_b, at)
    r = narrow.detect([[body_a, body_b]])
    assert r.pairs.mode[0] == (FULL if mode == "full" else ITERATIVE)
    c = r.contacts
    assert bool(r.pairs.colliding[0])
    assert r.pairs.max_depth[0] == pytest.approx(0.01, abs=1e-6)
    assert np.count_nonzero(c.kind == VERTEX) == 0, "no vertex is inside"
    assert len(c) > 0 and np.all(c.kind == EDGE)
    assert np.all(c.edge[:, 0] < c.edge[:, 1])
    np.testing.assert_array_equal(c.vertex, c.edge[:, 0])
    np.testing.assert_allclose(c.depth, 0.01, atol=1e-6)
    from_a, from_b = c.source == 0, c.source == 1
    assert from_a.sum() >= 2, "A's two upper long edges"
    assert from_b.sum() >= 2, "B's two lower long edges"
    np.testing.assert_allclose(c.push[from_a], np.tile([0, 0, -0.01], (from_a.sum(), 1)), atol=1e-6)
    np.testing.assert_allclose(c.push[from_b], np.tile([0, 0, 0.01], (from_b.sum(), 1)), atol=1e-6)
    np.testing.assert_allclose(c.origin[from_a, 2], 0.05, atol=1e-6)
    np.testing.assert_allclose(c.origin[from_b, 2], 0.04, atol=1e-6)
    assert r.stats["edge_contacts"] == len(c)

    # Edge tests off: what no vertex ray sees is not seen.
    blind = rtcd.query(a, b, IDENTITY, at, backend="embree", mode=mode, edge_contacts=False)
    assert not bool(blind.pairs.colliding[0])
    assert len(blind.contacts) == 0
    assert blind.stats["edges_tested"] == 0


def test_sphere_in_a_box_face():
    """A sphere (radius 0.5) at the origin, a box (0.5) at x = 0.9: the
    sphere's cap beyond x = 0.4 is inside the box, 0.1 deep at most."""
    r = rtcd.query(rtcd.Shape.sphere(0.5), rtcd.Shape.box([0.5, 0.5, 0.5]), IDENTITY, [0.9, 0, 0, 1, 0, 0, 0],
                   backend="embree")
    c = r.contacts
    assert bool(r.pairs.colliding[0])
    assert r.pairs.max_depth[0] == pytest.approx(0.1, abs=1e-6)
    sphere_side = c.source == 0
    assert sphere_side.sum() > 0
    assert np.all(c.depth[sphere_side] > 0)
    assert np.all(c.origin[sphere_side, 0] > 0.4 - 1e-6)
    assert np.all(c.depth <= 0.1 + 1e-6)
