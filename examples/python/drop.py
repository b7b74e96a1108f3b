"""Bodies dropped into a scene, their kinetic energy plotted step by step.

Loads a scene file (default: the stack scene of the data folder), steps it
on Bullet with rtcd's narrow phase and plots the kinetic energy of every
step to a PNG: it rises while the bodies fall and drops as contacts stop them.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python/drop.py --steps 240
"""
from __future__ import annotations

import argparse
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # no display needed: the plot goes to a file
import matplotlib.pyplot as plt  # noqa: E402

import rtcd  # noqa: E402


def default_scene() -> Path:
    """$RTCD_DATA/scenes/stack.json, else the checkout's data folder."""
    data = Path(os.environ["RTCD_DATA"]) if "RTCD_DATA" in os.environ else Path(__file__).resolve().parents[2] / "data"
    return data / "scenes" / "stack.json"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", nargs="?", type=Path, default=default_scene(), help="scene file (JSON)")
    parser.add_argument("--steps", type=int, default=240, help="steps to simulate (default 240)")
    parser.add_argument("--backend", default="", help="narrow-phase backend (default: the scene's)")
    parser.add_argument("--out", type=Path, default=Path("drop_energy.png"), help="the plot (PNG)")
    args = parser.parse_args()
    if args.steps < 1:
        parser.error("--steps must be at least 1")

    sim = rtcd.Simulation(args.scene, backend=args.backend)
    energy = []
    for _ in range(args.steps):
        sim.step()
        energy.append(sim.record["kinetic_energy"])
    steps = range(1, len(energy) + 1)

    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(steps, energy)
    ax.set_xlabel("step")
    ax.set_ylabel("kinetic energy (J)")
    ax.set_title(f"{args.scene.name}: {len(sim.labels)} bodies, backend {sim.backend}")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)

    peak = max(range(len(energy)), key=energy.__getitem__)
    print(f"{args.scene}: {sim.steps_done} steps on {sim.backend}")
    print(f"  kinetic energy: peak {energy[peak]:.3f} J at step {peak + 1}, last {energy[-1]:.3f} J")
    if sim.warnings:
        print("  warnings: " + "; ".join(sim.warnings))
    print(f"  plot: {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
