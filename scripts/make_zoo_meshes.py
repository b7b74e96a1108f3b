"""Writes the zoo scene's generated meshes (data/meshes/zoo/*.obj) from
rtcd.gen, each about 0.45 m across: shapes real meshes have (a thin knot
tube, a gear, a branching cactus, coarse polyhedra, a torus).

    PYTHONPATH=build/release/python /usr/bin/python3 scripts/make_zoo_meshes.py
"""
from __future__ import annotations

from pathlib import Path

import rtcd

MESHES = {
    "knot": lambda: rtcd.gen.torus_knot(2, 3, 0.14, 0.02, 200, 16),
    "gear": lambda: rtcd.gen.gear(12, 0.17, 0.225, 0.04),
    "cactus": lambda: rtcd.gen.cactus(0.45),
    "tetrahedron": lambda: rtcd.gen.tetrahedron(0.26),
    "octahedron": lambda: rtcd.gen.octahedron(0.225),
    "coarse_box": lambda: rtcd.gen.box([0.16, 0.12, 0.08]),
    "ring": lambda: rtcd.gen.torus(0.16, 0.05, 32, 12),
}


def main() -> None:
    folder = Path(__file__).resolve().parents[1] / "data" / "meshes" / "zoo"
    folder.mkdir(parents=True, exist_ok=True)
    for name, make in MESHES.items():
        make().save_obj(folder / f"{name}.obj")
        print(folder / f"{name}.obj")


if __name__ == "__main__":
    main()
