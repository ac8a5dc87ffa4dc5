"""Run a scene with softrod from Python and plot it with matplotlib.

    .venv/bin/pip install matplotlib          # only this example needs it
    .venv/bin/python examples/python/cantilever.py [SCENE] [--out DIR]

SCENE defaults to examples/cantilever_gravity.toml (a soft cantilever
released from straight under gravity). The script simulates the scene's
[run] duration, prints the tip's lowest point, the energy balance and the
integrator's work, and writes DIR/cantilever.png (default out/python/):
the rod's shape every tenth of the run (x-z plane), the tip height, and the
energies, whose sum is conserved when the scene has no damping.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import softrod

try:
    import matplotlib
except ImportError:  # an extra: say so in one line instead of a traceback
    sys.exit("cantilever.py draws with matplotlib, which is not installed: "
             "pip install matplotlib (into the softrod environment, e.g. .venv/bin/pip)")
matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", type=Path,
                        default=REPO / "examples" / "cantilever_gravity.toml")
    parser.add_argument("--out", type=Path, default=REPO / "out" / "python")
    args = parser.parse_args()

    sim = softrod.Simulation.from_file(args.scene)
    for warning in sim.warnings:
        print("warning:", warning)
    duration = sim.duration  # the scene's [run] duration
    start = time.perf_counter()
    traj = sim.simulate()
    wall = time.perf_counter() - start
    print(f"{args.scene.name}: {sim.n_dof} coordinates, {len(traj)} samples over {duration} s "
          f"in {wall:.3f} s ({traj.stats['steps']} steps, {sim.settings.integrator})")
    low = int(np.argmin(traj.tip_position[:, 2]))
    print(f"lowest tip: z = {traj.tip_position[low, 2]:.5f} m at t = {traj.t[low]:.3f} s")
    drift = np.abs(traj.energy - traj.energy[0]).max()
    print(f"energy: {traj.energy[0]:.6e} J at t = 0, largest change {drift:.2e} J")

    fig, (ax_shape, ax_tip, ax_energy) = plt.subplots(1, 3, figsize=(15, 4.5))
    for k in np.linspace(0, len(traj) - 1, 11).astype(int):
        p = traj.shape(int(k), s=np.linspace(0.0, sim.rod_lengths[0], 50))
        ax_shape.plot(p[:, 0], p[:, 2], color=plt.cm.viridis(traj.t[k] / duration))
    ax_shape.set(xlabel="x [m]", ylabel="z [m]", title="shape every tenth of the run",
                 aspect="equal")
    ax_tip.plot(traj.t, traj.tip_position[:, 2])
    ax_tip.set(xlabel="t [s]", ylabel="tip z [m]", title="tip height")
    for name in ("kinetic", "elastic", "gravitational", "energy"):
        ax_energy.plot(traj.t, getattr(traj, name), label="total" if name == "energy" else name)
    ax_energy.set(xlabel="t [s]", ylabel="energy [J]", title="energies")
    ax_energy.legend()
    fig.tight_layout()
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "cantilever.png"
    fig.savefig(path, dpi=110)
    print("wrote", path)


if __name__ == "__main__":
    main()
