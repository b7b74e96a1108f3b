"""The experiments from Python: validation runs, simulations, backends and
knobs, each checked against what the CLI reports."""
from __future__ import annotations

import ast
import csv
import json
import math
import pydoc
import subprocess

import numpy as np
import pytest

import rtcd
from conftest import REPO

STUB = REPO / "python" / "rtcd" / "__init__.pyi"


def key_paths(value, prefix: str = "") -> set[str]:
    """Every key of a JSON-like value, nested keys as a.b.c."""
    if not isinstance(value, dict):
        return set()
    out = set()
    for key, inner in value.items():
        out.add(prefix + key)
        out |= key_paths(inner, prefix + key + ".")
    return out


def test_validate_matches_the_cli(cli):
    mine = rtcd.validate(family="convex", backend="embree", pairs=20, oracles=False)
    done = subprocess.run([str(cli), "validate", "--json", "--family", "convex", "--backend", "embree",
                           "--pairs", "20", "--no-oracles"], capture_output=True, text=True, timeout=120, check=True)
    theirs = json.loads(done.stdout)
    assert isinstance(mine, list) and len(mine) == 1 and len(theirs) == 1
    assert key_paths(mine[0]) == key_paths(theirs[0])
    # Same seed, same pairs: the same counts.
    for key in ("deep_origins", "missed", "pairs", "false_rays", "far_outside_origins", "family", "backend", "mode"):
        assert mine[0][key] == theirs[0][key], key
    assert mine[0]["pairs"] == 20 and mine[0]["deep_origins"] > 0


def test_families():
    families = rtcd.families()
    assert "convex" in families and "concave" in families
    assert len(set(families)) == len(families)


def test_simulation_steps(scenes_dir):
    sim = rtcd.Simulation(scenes_dir / "avalanche_small.json", backend="embree")
    assert sim.backend == "embree"
    assert sim.steps_done == 0
    assert isinstance(sim.step(4), dict)
    sim.step(6)
    assert sim.steps_done == 10
    poses = sim.poses
    assert poses.ndim == 2 and poses.shape[1] == 7 and poses.dtype == np.float64
    # The scene's 3 x 3 x 3 blobs, and the ground if it is listed as a body.
    assert len(poses) == len(sim.labels) and len(poses) in (27, 28)
    assert "blob#0" in sim.labels and "blob#26" in sim.labels
    assert np.all(np.isfinite(poses))
    np.testing.assert_allclose(np.linalg.norm(poses[:, 3:], axis=1), 1.0, atol=1e-6)
    assert sim.velocities.shape == (len(poses), 6)
    assert math.isfinite(sim.record["kinetic_energy"]) and sim.record["kinetic_energy"] > 0
    assert isinstance(sim.state_hash(), int)


def test_contacts_number_bodies_as_poses(scenes_dir):
    """Simulation.contacts and pairs number bodies as poses and labels do:
    a contact lies on its source body, within a blob's radius of
    poses[source_body]; the ground is Simulation.GROUND."""
    sim = rtcd.Simulation(scenes_dir / "avalanche_small.json", backend="embree")
    sim.step(120)
    c = sim.contacts.contacts
    ground = rtcd.Simulation.GROUND
    assert (c.target_body == ground).any(), "blobs rest on the ground"
    between = (c.source_body != ground) & (c.target_body != ground)
    assert between.any(), "and on each other"
    count = len(sim.poses)
    assert np.all((c.source_body < count) | (c.source_body == ground))
    assert np.all((c.target_body < count) | (c.target_body == ground))
    assert np.all((sim.pairs < count) | (sim.pairs == ground))
    # A contact point lies on its body: within the farthest vertex of
    # blob_902, scaled by 0.25, from the mesh file's origin (the pose).
    vertices = np.array([[float(x) for x in line.split()[1:4]]
                         for line in (scenes_dir.parent / "meshes" / "blob_902.obj").read_text().splitlines()
                         if line.startswith("v ")])
    radius = 0.25 * np.linalg.norm(vertices, axis=1).max()
    assert 0.3 < radius < 0.35
    src = c.source_body != ground
    reach = np.linalg.norm(c.origin[src] - sim.poses[c.source_body[src], :3], axis=1)
    assert reach.max() <= radius
    reach = np.linalg.norm(c.origin[between] - sim.poses[c.target_body[between], :3], axis=1)
    assert reach.max() <= radius, "the target holds the point"


def test_a_ball_falls():
    """A scene as a dict: one ball under gravity, nothing else."""
    scene = {"effects": ["gravity"], "ground": False,
             "bodies": [{"name": "ball", "sphere": 0.2, "pose": {"position": [0, 0, 1]}}]}
    sim = rtcd.Simulation(scene, backend="embree")
    sim.step(30)
    assert sim.labels == ["ball"]
    z, vz = sim.poses[0, 2], sim.velocities[0, 2]
    assert z < 1.0 and vz < 0, "it falls"
    # Half a second of free fall (1/60 s steps): about g t^2 / 2 = 1.2 m.
    assert 1.0 - z == pytest.approx(0.5 * 9.81 * 0.5 ** 2, rel=0.1)


def test_same_scene_same_hash(scenes_dir):
    hashes = []
    for _ in range(2):
        sim = rtcd.Simulation(scenes_dir / "avalanche_small.json", backend="embree")
        sim.step(3)
        hashes.append(sim.state_hash())
    assert hashes[0] == hashes[1]


def test_run_writes_its_files(scenes_dir, tmp_path):
    summary = rtcd.run(scenes_dir / "avalanche_small.json", backend="embree", steps=5, out=tmp_path, plots=False)
    assert isinstance(summary, dict) and summary
    assert json.loads((tmp_path / "summary.json").read_text())["scene"]
    with open(tmp_path / "steps.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 5
    assert all(math.isfinite(float(row["kinetic_energy"])) for row in rows)


def test_backends():
    listed = {b["name"]: b for b in rtcd.backends()}
    assert {"basic", "embree"} <= listed.keys()
    assert listed["embree"]["usable"] and listed["basic"]["usable"]
    assert all(isinstance(b["devices"], str) for b in listed.values())
    assert rtcd.NarrowPhase("embree").name == "embree"
    assert rtcd.NarrowPhase("auto").name == "embree", "auto picks the fastest usable backend"


def narrow_phase_keywords() -> set[str]:
    """The keyword-only arguments of NarrowPhase.__init__ in the stub."""
    tree = ast.parse(STUB.read_text())
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "NarrowPhase")
    init = next(n for n in cls.body if isinstance(n, ast.FunctionDef) and n.name == "__init__")
    return {a.arg for a in init.args.kwonlyargs}


# A value of each knob other than its default, to see it arrive.
KNOB_VALUES = {"max_walk_steps": 17, "displacement_threshold": 0.01, "distance_extension": 0.03, "predictive": False,
               "verify_walks": False, "edge_contacts": False, "edges_beside_contacts": False, "edges_both_sides": False,
               "edge_retest_motion": 0.004, "trace_separated_pairs": False,
               "nearest_surface": False, "projected": False, "mode": "iterative"}


def test_knobs_are_narrow_phase_keywords():
    names = [k["name"] for k in rtcd.knobs()]
    assert set(names) == narrow_phase_keywords() - {"threads"}
    assert set(names) == KNOB_VALUES.keys()
    for name in names:
        narrow = rtcd.NarrowPhase("embree", **{name: KNOB_VALUES[name]})
        assert narrow.config[name] == KNOB_VALUES[name], name


def test_knobs_are_the_clis(cli):
    """rtcd knobs prints the same table the package returns."""
    done = subprocess.run([str(cli), "knobs"], capture_output=True, text=True, timeout=60, check=True)
    for knob in rtcd.knobs():
        assert f"| `{knob['name']}` |" in done.stdout, knob["name"]


def test_switches_say_what_off_does(cli):
    """A switch's `off` is what the command line's --no-NAME help begins with."""
    done = subprocess.run([str(cli), "validate", "--help"], capture_output=True, text=True, timeout=60, check=True)
    for knob in rtcd.knobs():
        if knob["type"] != "flag":
            assert knob["off"] is None, knob["name"]
            continue
        option = "--no-" + knob["name"].replace("_", "-")
        line = next(line for line in done.stdout.splitlines() if line.strip().startswith(option + " "))
        assert line.strip()[len(option):].lstrip().startswith(knob["off"]), knob["name"]


def test_help_names_every_knob():
    text = pydoc.render_doc(rtcd.NarrowPhase, renderer=pydoc.plaintext)
    for knob in rtcd.knobs():
        assert knob["name"] in text, knob["name"]
