#!/usr/bin/env python3
"""Writes the committed seed corpora under fuzz/corpus/ (deterministic:
rerunning it rewrites the same bytes). Usage: python3 fuzz/make_corpus.py

mesh_pair seeds are encoded the way FuzzedDataProvider decodes them: integers
are taken from the END of the input, most significant byte first, in the
order fuzz/mesh_pair.cpp reads them. Keep Seed below in step with it."""

import json
import struct
from pathlib import Path

HERE = Path(__file__).resolve().parent
CORPUS = HERE / "corpus"


class Seed:
    """Values in the order the harness consumes them; bytes() lays them out."""

    def __init__(self):
        self.consumed = []  # bytes in consumption order

    def range(self, lo, hi, value, bits):
        # FuzzedDataProvider::ConsumeIntegralInRange: as many bytes as the
        # range needs, first byte consumed is the most significant.
        assert lo <= value <= hi, (lo, value, hi)
        span, offset, n = hi - lo, 0, 0
        while offset < bits and (span >> offset) > 0:
            n, offset = n + 1, offset + 8
        r = value - lo
        self.consumed += [(r >> (8 * (n - 1 - i))) & 0xFF for i in range(n)]
        return self

    def flag(self, v):
        return self.range(0, 255, int(bool(v)), 8)

    def u32(self, v):
        return self.range(0, 2**32 - 1, v, 32)

    def u64(self, v):
        return self.range(0, 2**64 - 1, v, 64)

    def bytes(self):
        return bytes(reversed(self.consumed))


class MeshPair(Seed):
    """The reads of fuzz/mesh_pair.cpp, by name."""

    def __init__(self, raw=False):
        super().__init__()
        self.raw = raw
        self.flag(raw)

    def coord(self, v):
        if self.raw:
            return self.u32(struct.unpack("<I", struct.pack("<f", v))[0])
        q = round(v * 256)
        assert q == v * 256, "lattice coordinates are multiples of 1/256"
        return self.range(-2048, 2047, q, 16)

    def position(self, v):
        if self.raw:
            return self.u64(struct.unpack("<Q", struct.pack("<d", v))[0])
        q = round(v * 256)
        assert q == v * 256
        return self.range(-4096, 4095, q, 16)

    def quat(self, w, x, y, z):
        for c in (w, x, y, z):
            if self.raw:
                self.u64(struct.unpack("<Q", struct.pack("<d", float(c)))[0])
            else:
                self.range(-128, 127, c, 8)
        return self

    def pose(self, p, q=(1, 0, 0, 0)):
        for c in p:
            self.position(c)
        return self.quat(*q)

    def head(self, kind, allow_zero_area=False):
        return self.range(0, 9, kind, 8).flag(allow_zero_area)

    def raw_mesh(self, positions, triangles, allow_zero_area=False):
        self.head(0, allow_zero_area)
        self.range(3, 64, len(positions), 32).range(1, 128, len(triangles), 32)
        for p in positions:
            for c in p:
                self.coord(c)
        for t in triangles:
            for i in t:
                self.range(0, 63, i, 8)
        return self

    def moves(self, moves):
        """After a generator: no moves (flag off) or [(vertex, (dx, dy, dz) * 16)]."""
        self.flag(bool(moves))
        if moves:
            self.range(0, 8, len(moves), 8)
            for v, d in moves:
                self.range(0, 255, v, 8)
                for c in d:
                    self.coord(c)
        return self

    def box(self, h, moves=()):
        self.head(3)
        for c in h:
            self.coord(c)
        return self.moves(moves)

    def icosphere(self, radius, level, moves=()):
        self.head(4).coord(radius).range(0, 1, level, 8)
        return self.moves(moves)

    def torus(self, minor, major_minus_minor, nu, nv, moves=()):
        self.head(5).coord(minor).coord(major_minus_minor).range(3, 8, nu, 8).range(3, 8, nv, 8)
        return self.moves(moves)

    def blob(self, triangles, seed, radius, moves=()):
        self.head(6).range(4, 64, triangles // 2, 8).u32(seed).coord(radius)
        return self.moves(moves)

    def sheet(self, n, size, amplitude, moves=()):
        self.head(7).range(1, 7, n, 8).coord(size).coord(amplitude)
        return self.moves(moves)

    def u_shape(self, scale, half_depth, moves=()):
        self.head(8).coord(scale).coord(half_depth)
        return self.moves(moves)

    def sphere(self, radius, density_quarters=0):
        self.head(9).flag(True).coord(radius)
        if not self.raw:
            self.range(0, 3, density_quarters, 8)
        return self

    def box_volume(self, h):
        self.head(9).flag(False)
        for c in h:
            self.coord(c)
        return self

    MODES = {"full": 0, "iterative": 1, "auto": 2}

    def config(self, mode="auto", walk=32, extension=0.1, threshold_fraction=0.5, predictive=True,
               projected=True):
        self.range(1, 4096, walk, 32)
        self.range(0, 1 << 20, round(extension * 4096), 32)
        self.range(0, 65535, round(threshold_fraction * 65535), 16)
        self.range(0, 2, self.MODES[mode], 8).flag(predictive).flag(projected)
        return self

    def steps(self, moves):
        """moves: for each step after the first, B's (dx, dy, dz) and (rx, ry, rz) in 1/1024 and 1/512."""
        self.range(2, 3, len(moves) + 1, 8)
        for d, r in moves:
            for c in d + r:
                self.range(-128, 127, c, 8)
        return self


TETRA_P = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
TETRA_T = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
JITTER = [((10, -10, 5), (0, 0, 0)), ((10, -10, 5), (3, -2, 1))]


def mesh_pair_seeds():
    s = {}
    # The README's boxes: B's corners inside A's faces.
    s["boxes_full"] = (MeshPair().box((0.5, 0.5, 0.5)).box((0.625, 0.625, 0.625))
                       .pose((0, 0, 0)).pose((1, 0, 0)).config("full").steps(JITTER[:1]))
    # Two concave blobs resting in contact, stepped iteratively.
    s["blobs_auto"] = (MeshPair().blob(128, 1, 1.0).blob(128, 2, 1.0)
                       .pose((0, 0, 0)).pose((1.3125, 0.25, 0), (16, 2, 3, 1)).config("auto").steps(JITTER))
    s["icosphere_torus_iterative"] = (MeshPair().icosphere(1.0, 1).torus(0.25, 0.75, 8, 6)
                                      .pose((0, 0, 0)).pose((1.0, 0, 0.125), (8, 3, 0, 0))
                                      .config("iterative", walk=8, extension=0.25).steps(JITTER))
    # Hand-made tetrahedron against a wavy open sheet (boundary edges).
    s["tetra_sheet"] = (MeshPair().raw_mesh([tuple(c * 2 for c in p) for p in TETRA_P], TETRA_T)
                        .sheet(6, 4.0, 0.25).pose((0.25, 0.25, -0.5), (8, 1, 1, 0)).pose((0, 0, 0))
                        .config("full", predictive=True).steps(JITTER))
    s["u_shape_sphere"] = (MeshPair().u_shape(1.0, 0.5).sphere(0.5, 2)
                           .pose((0, 0, 0)).pose((0, 0.5, 0)).config("auto", extension=0.5).steps(JITTER))
    s["box_volume_moved_icosphere"] = (MeshPair().box_volume((0.5, 1.0, 0.25))
                                       .icosphere(1.0, 1, moves=[(3, (2, 0, 0)), (17, (0, -4, 1))])
                                       .pose((0, 0, 0), (8, 0, 0, 3)).pose((0.75, 0.5, 0))
                                       .config("full", projected=False).steps(JITTER))
    # Zero-area triangle kept: a flat tetrahedron face folded in.
    s["zero_area_kept"] = (MeshPair().raw_mesh(TETRA_P + [(0.5, 0, 0)], [(0, 2, 4), (4, 2, 1), (0, 4, 1)] + TETRA_T[1:],
                                               allow_zero_area=True)
                           .box((0.5, 0.5, 0.5)).pose((0, 0, 0)).pose((0.5, 0.5, 0.5)).config("full").steps(JITTER))
    # Raw floats: the same boxes at a far-away position.
    s["boxes_raw_far"] = (MeshPair(raw=True).box((0.5, 0.5, 0.5)).box((0.625, 0.625, 0.625))
                          .pose((1e6, -3e5, 2.5e4)).pose((1e6 + 1, -3e5, 2.5e4), (0.9, 0.1, 0.3, 0.2))
                          .config("auto").steps(JITTER))
    return {k: v.bytes() for k, v in s.items()}


# Unit cube as in rtcd::gen::box: vertex i has x = +-0.5 by bit 0, y by bit 1, z by bit 2.
CUBE_P = [((i & 1) - 0.5, ((i >> 1) & 1) - 0.5, ((i >> 2) & 1) - 0.5) for i in range(8)]
CUBE_Q = [(1, 3, 7, 5), (0, 4, 6, 2), (2, 6, 7, 3), (0, 1, 5, 4), (4, 5, 7, 6), (0, 2, 3, 1)]
CUBE_T = [t for q in CUBE_Q for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]


def fmt(v):
    return f"{v:g}"


def mesh_file_seeds():
    EXT = {".obj": 0, ".off": 1, ".ply": 2, ".stl": 3}
    s = {}
    obj_quads = "# cube\n" + "".join(f"v {' '.join(map(fmt, p))}\n" for p in CUBE_P) + \
        "".join(f"f {' '.join(str(i + 1) for i in q)}\n" for q in CUBE_Q)
    s["cube_quads.obj"] = (EXT[".obj"], obj_quads)
    obj_tris = "o tetra\n" + "".join(f"v {' '.join(map(fmt, p))}\n" for p in TETRA_P) + \
        "".join(f"f {' '.join(str(i + 1) for i in t)}\n" for t in TETRA_T)
    s["tetra.obj"] = (EXT[".obj"], obj_tris)
    off = f"OFF\n8 12 0\n" + "".join(f"{' '.join(map(fmt, p))}\n" for p in CUBE_P) + \
        "".join(f"3 {' '.join(map(str, t))}\n" for t in CUBE_T)
    s["cube.off"] = (EXT[".off"], off)
    ply_head = ("ply\nformat {} 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                "element face 12\nproperty list uchar int vertex_indices\nend_header\n")
    ply_ascii = ply_head.format("ascii") + "".join(f"{' '.join(map(fmt, p))}\n" for p in CUBE_P) + \
        "".join(f"3 {' '.join(map(str, t))}\n" for t in CUBE_T)
    s["cube_ascii.ply"] = (EXT[".ply"], ply_ascii)
    ply_bin = ply_head.format("binary_little_endian").encode() + \
        b"".join(struct.pack("<3f", *p) for p in CUBE_P) + b"".join(struct.pack("<B3i", 3, *t) for t in CUBE_T)
    s["cube_binary.ply"] = (EXT[".ply"], ply_bin)

    def normal(t):
        a, b, c = (CUBE_P[i] for i in t)
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])

    stl_ascii = "solid cube\n" + "".join(
        f" facet normal {' '.join(map(fmt, normal(t)))}\n  outer loop\n" +
        "".join(f"   vertex {' '.join(map(fmt, CUBE_P[i]))}\n" for i in t) + "  endloop\n endfacet\n"
        for t in CUBE_T) + "endsolid cube\n"
    s["cube_ascii.stl"] = (EXT[".stl"], stl_ascii)
    stl_bin = b"rtcd fuzz seed: binary STL cube".ljust(80, b" ") + struct.pack("<I", len(CUBE_T)) + b"".join(
        struct.pack("<3f", *normal(t)) + b"".join(struct.pack("<3f", *CUBE_P[i]) for i in t) + b"\0\0"
        for t in CUBE_T)
    s["cube_binary.stl"] = (EXT[".stl"], stl_bin)
    # A zero-area triangle, loaded with allow_zero_area (bit 2 of the first byte).
    zero = "".join(f"v {' '.join(map(fmt, p))}\n" for p in TETRA_P + [(0.5, 0, 0)]) + \
        "".join(f"f {' '.join(str(i + 1) for i in t)}\n" for t in [(0, 2, 4), (4, 2, 1), (0, 4, 1)] + TETRA_T[1:])
    s["zero_area.obj"] = (4 | EXT[".obj"], zero)
    # The checker's defect classes (data/defects/), one of them welded (bit 3).
    for path in sorted((HERE.parent / "data" / "defects").glob("*.off")):
        s["defect_" + path.name] = (EXT[".off"], path.read_bytes())
    s["defect_pinch_split_welded.off"] = (8 | EXT[".off"], (HERE.parent / "data/defects/pinch_split.off").read_bytes())
    out = {}
    for name, (selector, body) in s.items():
        out[name] = bytes([selector]) + (body if isinstance(body, bytes) else body.encode())
    return out


def pose(p, q=(1, 0, 0, 0)):
    return list(p) + list(q)


def pose_sequence_seeds():
    s = {}
    s["one_step.json"] = [{"pose_a": pose((0, 0, 0)), "pose_b": pose((1.2, 0.1, 0))}]
    s["approach.json"] = [{"pose_a": pose((0, 0, 0)), "pose_b": pose((2.0 - 0.2 * i, 0.1, 0))} for i in range(6)]
    s["jitter_rotate.json"] = [
        {"pose_a": pose((0, 0, 0), (0.9238795, 0, 0.3826834, 0)),
         "pose_b": pose((1.3 + 0.001 * i, 0.05, -0.02), (1, 0, 0, 0.001 * i))} for i in range(4)]
    s["far_away.json"] = [{"pose_a": pose((1e7, -1e7, 5e6)), "pose_b": pose((1e7 + 1.1, -1e7, 5e6))},
                          {"pose_a": pose((1e7, -1e7, 5e6)), "pose_b": pose((1e7 + 1.0, -1e7, 5e6))}]
    text = {k: json.dumps(v) + "\n" for k, v in s.items()}
    # Number spellings JSON allows: integers, exponents, negative zero.
    text["spellings.json"] = ('[{"pose_a": [0, -0.0, 0e0, 1, 0, 0, 0],\n'
                              '  "pose_b": [1.2E0, 1e-1, -0, 1.0, 0.0, 0.0, 0.0]}]\n')
    return {k: v.encode() for k, v in text.items()}


def scene_seeds():
    """The committed scenes and the inline scenes of tests/sim/sim_test.cpp."""
    import re
    seeds = {p.name: p.read_bytes() for p in sorted((HERE.parent / "data" / "scenes").glob("*.json"))}
    tests = (HERE.parent / "tests" / "sim" / "sim_test.cpp").read_text()
    for n, m in enumerate(re.finditer(r'scene_from\(R"\((\{.*?\})\)"\)', tests, re.S), 1):
        seeds[f"test_{n}.json"] = m.group(1).encode()
    return seeds


def recording_seeds():
    """Small recordings in the format of sim/include/rtcd/sim/recording.hpp:
    bodies appearing over time, pairs joining and leaving."""
    scene = json.dumps({"time_step": 0.01, "steps": 3, "effects": ["gravity", "contacts", "predictive"],
                        "bodies": [{"sphere": 0.5, "count": 3,
                                    "grid": {"cells": [3, 1, 1], "spacing": [0.9, 1, 1]}}]}).encode()

    def text(b):
        return struct.pack("<I", len(b)) + b

    def listed(fmt, values):
        return struct.pack("<I", len(values)) + b"".join(struct.pack(fmt, v) for v in values)

    def step(n, kinds, bodies, pairs, left, joined):
        out = b"STEP" + struct.pack("<QdIIIId", n, 0.01 * (n + 1), bodies, pairs, 2 * pairs, 1, 1.5)
        out += struct.pack("<5d", 1e-4, 2e-4, 3e-4, 0, 6e-4)
        out += listed("<I", kinds)
        poses = []
        for b in range(bodies):
            poses += [0.9 * b, 0.01 * n, 0.5, 0.0, 0.0, 0.0, 1.0]
        out += listed("<f", poses)
        out += listed("<Q", left) + listed("<Q", joined)
        return out

    def key(a, b):
        return a << 32 | b

    head = b"RTCDREC1" + text(b"fuzz/scene.json") + text(scene)
    ground = 0xFFFFFFFF
    steps = (step(0, [ground, 0, 0, 0], 4, 3, [], [key(0, 1), key(0, 2), key(1, 2)]) +
             step(1, [], 4, 3, [key(0, 2)], [key(2, 3)]) +
             step(2, [], 4, 1, [key(0, 1), key(2, 3)], []))
    return {"three_steps.rtcdrec": head + steps, "header_only.rtcdrec": head}


def main():
    for harness, seeds in (("mesh_pair", mesh_pair_seeds()), ("mesh_file", mesh_file_seeds()),
                           ("pose_sequence", pose_sequence_seeds()), ("scene", scene_seeds()),
                           ("recording", recording_seeds())):
        folder = CORPUS / harness
        folder.mkdir(parents=True, exist_ok=True)
        for old in folder.iterdir():
            old.unlink()
        for name, data in seeds.items():
            (folder / name).write_bytes(data)
        print(f"{folder.relative_to(HERE.parent)}: {len(seeds)} seeds")


if __name__ == "__main__":
    main()
