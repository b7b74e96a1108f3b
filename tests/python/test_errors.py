"""Every error path of the package: the exception class and what the message
names. Messages are the CLI's: the same failure reads the same in both."""
from __future__ import annotations

import numpy as np
import pytest

import rtcd
from conftest import IDENTITY, cli_error

BOX = "box:0.5,0.5,0.5"


def box_arrays():
    mesh = rtcd.gen.box([0.5, 0.5, 0.5])
    return mesh.vertices.astype(np.float64), mesh.triangles.astype(np.int64)


def test_exception_hierarchy():
    assert issubclass(rtcd.Error, RuntimeError)
    for cls in (rtcd.MeshError, rtcd.ConfigError, rtcd.UsageError, rtcd.SceneError, rtcd.RecordingError):
        assert issubclass(cls, rtcd.Error) and issubclass(cls, ValueError), cls
    assert issubclass(rtcd.BackendError, rtcd.Error) and issubclass(rtcd.BackendError, RuntimeError)
    assert not issubclass(rtcd.BackendError, ValueError), "nothing wrong with the input"
    assert issubclass(rtcd.SimulationError, rtcd.Error)


# --- meshes -----------------------------------------------------------------

def test_vertices_of_the_wrong_shape():
    v, t = box_arrays()
    with pytest.raises(rtcd.UsageError, match="vertices"):
        rtcd.Mesh(v[:, :2], t)


def test_triangles_of_a_float_dtype():
    v, t = box_arrays()
    with pytest.raises(TypeError, match="triangles"):
        rtcd.Mesh(v, t.astype(np.float64))


def test_non_finite_vertex():
    v, t = box_arrays()
    v[3, 1] = np.nan
    with pytest.raises((rtcd.MeshError, rtcd.UsageError)) as caught:
        rtcd.Mesh(v, t)
    e = caught.value
    if isinstance(e, rtcd.MeshError):
        assert e.kind == "non_finite_coordinate"
        assert e.vertex == 3
        assert "vertex 3" in str(e)
    else:
        assert "vertices" in str(e)


def test_index_out_of_range():
    v, t = box_arrays()
    t[5, 2] = 8  # the box has vertices 0..7
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh(v, t)
    e = caught.value
    assert e.kind == "index_out_of_range"
    assert e.triangle == 5
    assert e.vertex == 8
    assert "triangle 5" in str(e)


def test_empty_mesh():
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    assert caught.value.kind == "empty"


def test_inverted_mesh():
    v, t = box_arrays()
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh(v, t[:, ::-1])  # every triangle faces inward
    assert caught.value.kind == "inverted"
    assert caught.value.vertex is None and caught.value.triangle is None


def test_inconsistent_winding():
    v, t = box_arrays()
    t[4] = t[4, ::-1].copy()  # one triangle turned over
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh(v, t)
    assert caught.value.kind == "inconsistent_winding"
    assert caught.value.triangle is not None
    assert f"triangle {caught.value.triangle}" in str(caught.value)


def test_missing_file(tmp_path):
    path = tmp_path / "missing.obj"
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh.load(path)
    assert caught.value.kind == "file"
    assert str(path) in str(caught.value)


def test_unparsable_file(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text("garbage\n")
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh.load(path)
    assert caught.value.kind == "file"
    assert str(path) in str(caught.value)


def test_defect_file_names_the_file(data_dir):
    path = data_dir / "defects" / "inverted_cube.off"
    with pytest.raises(rtcd.MeshError) as caught:
        rtcd.Mesh.load(path)
    assert caught.value.kind == "inverted"
    assert str(caught.value).startswith(str(path) + ": ")


# --- configuration and backends ----------------------------------------------

def test_unknown_backend():
    with pytest.raises(rtcd.BackendError, match="nope"):
        rtcd.NarrowPhase(backend="nope")


def test_unknown_keyword():
    with pytest.raises(rtcd.ConfigError, match="foo"):
        rtcd.NarrowPhase(foo=1)
    with pytest.raises(rtcd.ConfigError, match="foo"):
        rtcd.query(rtcd.Shape.sphere(1), rtcd.Shape.sphere(1), backend="embree", foo=1)


@pytest.mark.parametrize("knobs, named", [
    (dict(displacement_threshold=-1), "displacement_threshold"),
    (dict(distance_extension=float("inf")), "distance_extension"),
    (dict(max_walk_steps=2.5), "max_walk_steps"),
    (dict(max_walk_steps=0), "max_walk_steps"),
    (dict(mode="sideways"), "sideways"),
])
def test_knob_out_of_range(knobs, named):
    with pytest.raises(rtcd.ConfigError, match=named):
        rtcd.NarrowPhase("embree", **knobs)


def test_switch_given_a_string():
    with pytest.raises((TypeError, rtcd.ConfigError), match="predictive"):
        rtcd.NarrowPhase("embree", predictive="yes")


# --- calls ------------------------------------------------------------------

@pytest.fixture
def rig():
    """A narrow phase with two cube bodies (ids a, b) and their shape ids."""
    narrow = rtcd.NarrowPhase("embree")
    shape = narrow.add_shape(rtcd.gen.box([0.5, 0.5, 0.5]))
    a = narrow.add_body(shape)
    b = narrow.add_body(shape, [0.9, 0, 0, 1, 0, 0, 0])
    return narrow, shape, a, b


@pytest.mark.parametrize("bad", [
    [np.nan, 0, 0, 1, 0, 0, 0],
    [0, 0, 0, 1, 0, np.inf, 0],
    [0, 0, 0, 1, 0, 0],
    [0, 0, 0, 1, 0, 0, 0, 0],
])
def test_bad_pose(rig, bad):
    narrow, shape, a, b = rig
    with pytest.raises(rtcd.UsageError, match="pose"):
        narrow.set_pose(b, bad)
    with pytest.raises(rtcd.UsageError, match="pose"):
        narrow.add_body(shape, bad)
    with pytest.raises(rtcd.UsageError, match="pose"):
        rtcd.query(rtcd.Shape.sphere(1), rtcd.Shape.sphere(1), IDENTITY, bad, backend="embree")


@pytest.mark.parametrize("bad", [np.array([0, 1, 2]), np.zeros((2, 3), dtype=np.uint32),
                                 np.zeros((1, 2, 2), dtype=np.uint32)])
def test_pairs_of_the_wrong_shape(rig, bad):
    narrow, shape, a, b = rig
    with pytest.raises(rtcd.UsageError, match="pairs"):
        narrow.detect(bad)


def test_pairs_of_unknown_bodies(rig):
    narrow, shape, a, b = rig
    with pytest.raises(rtcd.UsageError, match="99"):
        narrow.detect(np.array([[a, 99]], dtype=np.uint32))
    with pytest.raises(rtcd.UsageError):
        narrow.detect(np.array([[a, -1]], dtype=np.int64))
    with pytest.raises(rtcd.UsageError, match="one body"):
        narrow.detect(np.array([[a, a]]))
    with pytest.raises(rtcd.UsageError):
        narrow.detect(np.array([[a, b], [b, a]]))  # one pair twice


def test_removed_body(rig):
    narrow, shape, a, b = rig
    assert len(narrow.detect(np.array([[a, b]])).contacts) > 0
    narrow.remove_body(b)
    with pytest.raises(rtcd.UsageError, match=f"body {b}"):
        narrow.detect(np.array([[a, b]]))
    with pytest.raises(rtcd.UsageError):
        narrow.set_pose(b, IDENTITY)


def test_unknown_shape(rig):
    narrow, shape, a, b = rig
    with pytest.raises(rtcd.UsageError, match="shape"):
        narrow.add_body(shape + 5)
    with pytest.raises(rtcd.UsageError):
        narrow.add_bodies(shape + 5, np.tile(IDENTITY, (2, 1)))


def test_set_poses_of_mismatched_lengths(rig):
    narrow, shape, a, b = rig
    with pytest.raises(rtcd.UsageError, match="poses"):
        narrow.set_poses([a, b], np.tile(IDENTITY, (3, 1)))
    with pytest.raises(rtcd.UsageError, match="pose"):
        narrow.set_poses([a, b], np.zeros((2, 6)))


# --- experiments and simulations ---------------------------------------------

def test_unknown_family():
    with pytest.raises((rtcd.UsageError, rtcd.ConfigError), match="nope"):
        rtcd.validate(family="nope", pairs=1, oracles=False)


def test_missing_scene(tmp_path):
    path = tmp_path / "missing.json"
    with pytest.raises(rtcd.SceneError, match="missing.json"):
        rtcd.Simulation(path)


def test_scene_of_the_wrong_shape():
    with pytest.raises(rtcd.SceneError, match="bodies"):
        rtcd.Simulation({"effects": ["gravity"], "bodies": "x"})


def test_bad_sampling_density():
    with pytest.raises(rtcd.UsageError, match="sampling density"):
        rtcd.Shape.sphere(1.0, sampling_density=-1.0)
    with pytest.raises(rtcd.UsageError, match="radius"):
        rtcd.Shape.sphere(-1.0)


# --- the CLI's messages ------------------------------------------------------

def raised(call) -> rtcd.Error:
    with pytest.raises(rtcd.Error) as caught:
        call()
    return caught.value


@pytest.fixture
def bad_obj(tmp_path):
    path = tmp_path / "bad.obj"
    path.write_text("garbage\n")
    return path


def test_messages_are_the_clis(cli, tmp_path, bad_obj, data_dir):
    missing_mesh, missing_scene = tmp_path / "missing.obj", tmp_path / "missing.json"
    inverted = data_dir / "defects" / "inverted_cube.off"
    cases = [
        (lambda: rtcd.NarrowPhase(backend="nope"), ["query", BOX, BOX, "--backend", "nope"]),
        (lambda: rtcd.NarrowPhase("embree", displacement_threshold=-1),
         ["query", BOX, BOX, "--displacement-threshold", "-1"]),
        (lambda: rtcd.NarrowPhase("embree", max_walk_steps=2.5), ["query", BOX, BOX, "--max-walk-steps", "2.5"]),
        (lambda: rtcd.NarrowPhase("embree", mode="sideways"), ["query", BOX, BOX, "--mode", "sideways"]),
        (lambda: rtcd.Mesh.load(missing_mesh), ["query", str(missing_mesh), BOX]),
        (lambda: rtcd.Mesh.load(bad_obj), ["query", str(bad_obj), BOX]),
        (lambda: rtcd.Mesh.load(inverted), ["query", str(inverted), BOX]),
        (lambda: rtcd.validate(family="nope", pairs=1, oracles=False), ["validate", "--family", "nope"]),
        (lambda: rtcd.Simulation(missing_scene), ["run", str(missing_scene), "--steps", "1"]),
    ]
    for call, args in cases:
        assert str(raised(call)) == cli_error(*args), " ".join(args)
