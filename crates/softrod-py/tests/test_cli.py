"""The Python package against the `softrod` command on the same scene:
the same integration (the facade's), so the same samples, bit for bit."""

from __future__ import annotations

import json
import subprocess

import numpy as np

import softrod
from conftest import EXAMPLES, scene_text


def sim_names(scene):
    return softrod.Simulation.from_file(scene).q_names


def test_run_matches_the_cli_trajectory(tmp_path, softrod_bin):
    text = scene_text(
        'strains = ["ky", "qx", "qz"]',
        "[world]\ngravity = [0.0, 0.0, -9.81]\n"
        "[run]\nduration = 0.05\noutput_every = 0.005\n",
        pieces=4,
    )
    scene = tmp_path / "release.toml"
    scene.write_text(text)
    out = tmp_path / "out"
    subprocess.run([str(softrod_bin), "run", str(scene), "--out", str(out)], check=True,
                   capture_output=True)
    csv = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1, ndmin=2)
    traj = softrod.Simulation.from_file(scene).simulate(0.05)
    # The CLI prints f64 with Rust's shortest round-trip formatting, which
    # numpy parses back exactly; the integration is the same code on the
    # same input, so equality is exact.
    np.testing.assert_array_equal(csv[:, 0], traj.t)
    np.testing.assert_array_equal(csv[:, 1:4], traj.tip_position)
    np.testing.assert_array_equal(csv[:, 8], traj.energy)
    n = traj.q.shape[1]
    np.testing.assert_array_equal(csv[:, 9:9 + n], traj.q)
    np.testing.assert_array_equal(csv[:, 9 + n:9 + 2 * n], traj.qdot)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["q_names"] == sim_names(scene)
    assert summary["steps"] == traj.stats["steps"]


def test_statics_matches_the_cli(softrod_bin):
    scene = EXAMPLES / "tip_load_statics.toml"
    r = subprocess.run([str(softrod_bin), "statics", str(scene), "--json"], check=True,
                       capture_output=True, text=True)
    cli = json.loads(r.stdout)
    eq = softrod.Simulation.from_file(scene).statics()
    np.testing.assert_array_equal(np.array(cli["q"]), eq.q)
    assert cli["iterations"] == eq.iterations
