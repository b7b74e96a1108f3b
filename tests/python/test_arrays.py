"""Which arrays are views into the library's data and which are copies, and
which layouts of input arrays are read correctly."""
from __future__ import annotations

import gc

import numpy as np
import pytest

import rtcd
from conftest import IDENTITY, pose

MESH_VIEWS = ["vertices", "triangles", "vertex_normals", "triangle_normals", "neighbors"]

# A unit cube's corners and its 12 outward-wound triangles.
CUBE_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                          [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float64) * 0.3 + 0.1
CUBE_TRIANGLES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                           [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


@pytest.mark.parametrize("name", MESH_VIEWS)
def test_mesh_arrays_are_read_only_views(name: str):
    mesh = rtcd.gen.icosphere(1.0, 1)
    first, second = getattr(mesh, name), getattr(mesh, name)
    assert not first.flags.writeable
    with pytest.raises(ValueError):
        first[0, 0] = first[0, 1]
    assert np.shares_memory(first, second), "two reads are views of the same data"
    assert first.shape == ((len(mesh.vertices), 3) if name.startswith("vert") else (len(mesh), 3))


def test_mesh_dtypes():
    mesh = rtcd.gen.icosphere(1.0, 1)
    assert mesh.vertices.dtype == np.float32
    assert mesh.triangles.dtype == np.uint32
    assert mesh.vertex_normals.dtype == np.float32
    assert mesh.triangle_normals.dtype == np.float32
    assert mesh.neighbors.dtype == np.int32
    # A closed mesh: every triangle has three neighbours.
    assert np.all(mesh.neighbors >= 0) and np.all(mesh.neighbors < len(mesh))


@pytest.mark.parametrize("name", MESH_VIEWS)
def test_a_view_keeps_its_mesh_alive(name: str):
    mesh = rtcd.gen.concave_blob(300, 3)
    view = getattr(mesh, name)
    expected = view.copy()
    del mesh
    gc.collect()
    # Allocate meshes of the same size, which would reuse freed memory.
    others = [rtcd.gen.concave_blob(300, 4 + k) for k in range(4)]
    np.testing.assert_array_equal(view, expected)
    assert len(others) == 4


def test_float64_input_becomes_float32():
    mesh = rtcd.Mesh(CUBE_VERTICES, CUBE_TRIANGLES)
    assert mesh.vertices.dtype == np.float32
    np.testing.assert_array_equal(mesh.vertices, np.float32(CUBE_VERTICES))
    np.testing.assert_array_equal(mesh.triangles, CUBE_TRIANGLES)
    assert len(mesh) == 12
    assert mesh.convex


def test_input_arrays_are_copied():
    vertices, triangles = CUBE_VERTICES.astype(np.float32), CUBE_TRIANGLES.astype(np.uint32)
    mesh = rtcd.Mesh(vertices, triangles)
    vertices[:] = 0
    triangles[:] = 0
    np.testing.assert_array_equal(mesh.vertices, np.float32(CUBE_VERTICES))
    np.testing.assert_array_equal(mesh.triangles, CUBE_TRIANGLES)


class FakeTrimesh:
    """Stands in for trimesh.Trimesh: anything with .vertices and .faces."""

    def __init__(self, vertices, faces):
        self.vertices = vertices
        self.faces = faces


def test_mesh_from_an_object_with_vertices_and_faces():
    mesh = rtcd.Mesh(FakeTrimesh(CUBE_VERTICES, CUBE_TRIANGLES))
    direct = rtcd.Mesh(CUBE_VERTICES, CUBE_TRIANGLES)
    np.testing.assert_array_equal(mesh.vertices, direct.vertices)
    np.testing.assert_array_equal(mesh.triangles, direct.triangles)
    np.testing.assert_array_equal(mesh.triangle_normals, direct.triangle_normals)


def test_shape_of_a_mesh_shares_its_data():
    mesh = rtcd.gen.concave_blob(300, 5)
    shape = rtcd.Shape(mesh)
    assert shape.kind == "mesh"
    assert np.shares_memory(shape.mesh.vertices, mesh.vertices)
    # A mesh's ray origins are its vertices (ids as given), its inward
    # directions the reversed vertex normals, its edges each triangle edge once.
    np.testing.assert_array_equal(shape.origins, mesh.vertices)
    np.testing.assert_allclose(shape.directions, -mesh.vertex_normals, atol=1e-7)
    assert not shape.origins.flags.writeable
    edges = shape.edges
    assert edges.shape == (len(mesh) * 3 // 2, 2)  # closed: each edge in two triangles
    assert np.all(edges[:, 0] < edges[:, 1])


def cube_query() -> rtcd.StepResult:
    a, b = rtcd.gen.box([0.5, 0.5, 0.5]), rtcd.gen.box([0.6, 0.6, 0.6])
    return rtcd.query(a, b, IDENTITY, [1, 0, 0, 1, 0, 0, 0], backend="embree", mode="full")


def test_step_arrays_are_cached_copies():
    first, second = cube_query(), cube_query()
    depth = first.contacts.depth
    assert len(depth) >= 4
    assert first.contacts.depth is depth, "built once, then cached"
    np.testing.assert_array_equal(first.contacts["depth"], depth)
    expected = second.contacts.depth.copy()
    depth[:] = -1.0  # the caller owns its copy
    np.testing.assert_array_equal(second.contacts.depth, expected)
    assert np.all(first.contacts.depth == -1.0)
    assert not np.shares_memory(depth, second.contacts.depth)


def test_rays_are_contacts_then_predictive():
    r = rtcd.query(rtcd.gen.box([0.5, 0.5, 0.5]), rtcd.gen.icosphere(0.5, 2), IDENTITY, [0.98, 0, 0, 1, 0, 0, 0],
                   backend="embree", mode="full")
    n, m = len(r.contacts), len(r.predictive)
    assert n > 0 and m > 0, "the case has both kinds"
    assert len(r.rays) == n + m
    assert set(r.rays.keys()) == set(r.contacts.keys())
    np.testing.assert_array_equal(r.rays.depth, np.concatenate([r.contacts.depth, r.predictive.depth]))
    assert not np.any(r.contacts.predictive) and np.all(r.predictive.predictive)
    assert np.all(r.predictive.depth == 0) and np.all(r.predictive.distance >= 0)
    # Every column is one row per ray (edge, and the vectors, two-dimensional).
    for key in r.rays.keys():
        assert len(r.rays[key]) == n + m, key


def three_pairs():
    """Three cube pairs far apart, each sunk by a different depth, as the
    thesis' ray contacts measure it (along each corner's diagonal)."""
    narrow = rtcd.NarrowPhase("embree", mode="full", nearest_surface=False)
    sa, sb = narrow.add_shape(rtcd.gen.box([0.5, 0.5, 0.5])), narrow.add_shape(rtcd.gen.box([0.6, 0.6, 0.6]))
    rows = []
    for k, sink in enumerate([0.05, 0.1, 0.15]):
        a = narrow.add_body(sa, pose((10.0 * k, 0, 0)))
        b = narrow.add_body(sb, pose((10.0 * k + 1.1 - sink, 0, 0)))
        rows.append((a, b))
    return narrow, np.array(rows, dtype=np.uint32)


def test_pairs_arrays_of_any_layout():
    narrow, pairs = three_pairs()
    reference = narrow.detect(pairs)
    np.testing.assert_allclose(reference.pairs.max_depth, np.array([0.05, 0.1, 0.15]) * np.sqrt(3), atol=1e-5)
    wide = np.zeros((3, 4), dtype=np.uint32)
    wide[:, 0], wide[:, 2] = pairs[:, 0], pairs[:, 1]
    layouts = {
        "uint32": pairs,
        "int64": pairs.astype(np.int64),
        "fortran": np.asfortranarray(pairs),
        "transposed": np.ascontiguousarray(pairs.T).T,
        "strided": wide[:, ::2],
        "list": pairs.tolist(),
    }
    assert not layouts["strided"].flags.c_contiguous and not layouts["transposed"].flags.c_contiguous
    for name, array in layouts.items():
        r = narrow.detect(array)
        np.testing.assert_array_equal(r.pairs.a, pairs[:, 0], err_msg=name)
        np.testing.assert_array_equal(r.pairs.b, pairs[:, 1], err_msg=name)
        np.testing.assert_array_equal(r.pairs.max_depth, reference.pairs.max_depth, err_msg=name)
    # Rows in input order, whatever the order.
    backwards = narrow.detect(pairs[::-1])
    np.testing.assert_array_equal(backwards.pairs.a, pairs[::-1, 0])
    np.testing.assert_array_equal(backwards.pairs.max_depth, reference.pairs.max_depth[::-1])


def test_pairs_index_their_contacts():
    narrow, pairs = three_pairs()
    r = narrow.detect(pairs)
    p, c = r.pairs, r.contacts
    assert len(p) == 3 and p.a.dtype == np.uint32 and p.colliding.dtype == np.bool_
    assert p.contact_count.sum() == len(c)
    for i in range(3):
        rows = slice(p.first_contact[i], p.first_contact[i] + p.contact_count[i])
        assert np.all(c.pair[rows] == i)
        np.testing.assert_array_equal(c.source_body[rows], np.where(c.source[rows] == 0, p.a[i], p.b[i]))
        np.testing.assert_array_equal(c.target_body[rows], np.where(c.source[rows] == 0, p.b[i], p.a[i]))
        assert c.depth[rows].max() == p.max_depth[i]


def test_set_poses_takes_a_k_by_7_array():
    narrow, pairs = three_pairs()
    bodies = pairs[:, 1]
    # Each B slid 0.02 deeper; the poses as rows of a wider float64 array.
    rows = np.zeros((3, 8))
    rows[:, :7] = [pose((10.0 * k + 1.1 - sink - 0.02, 0, 0)) for k, sink in enumerate([0.05, 0.1, 0.15])]
    narrow.set_poses(bodies, rows[:, :7])
    r = narrow.detect(pairs)
    np.testing.assert_allclose(r.pairs.max_depth, np.array([0.07, 0.12, 0.17]) * np.sqrt(3), atol=1e-5)
    # add_bodies places k bodies from one (k, 7) array.
    ids = narrow.add_bodies(narrow.add_shape(rtcd.gen.box([0.5, 0.5, 0.5])), rows[:, :7] + [0, 50, 0, 0, 0, 0, 0])
    assert ids.dtype == np.uint32 and len(ids) == 3 and len(set(ids.tolist()) | set(pairs.ravel().tolist())) == 9
