"""`softrod run --npz`: trajectory.npz read with numpy.load (a reader
independent of the writer) holds exactly trajectory.csv's rows, and the
names of summary.json."""

from __future__ import annotations

import csv as csvmod
import json
import re
import subprocess

import numpy as np
import pytest

import softrod
from conftest import EXAMPLES


def with_run(example: str, run_table: str, path):
    text = (EXAMPLES / example).read_text()
    cut = text.find("[run]")
    path.write_text((text if cut < 0 else text[:cut]) + run_table + "\n")
    return path


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csvmod.reader(f))
    header = rows[0]
    # float() parses Rust's shortest round-trip text back to the same double.
    data = np.array([[float(v) for v in r] for r in rows[1:]], dtype=float)
    return header, data.reshape(len(rows) - 1, len(header))


def cols(header, data, names):
    return data[:, [header.index(n) for n in names]]


def numbered(header, prefix):
    """The columns PREFIX0, PREFIX1, … in order."""
    pat = re.compile(re.escape(prefix) + r"(\d+)$")
    found = sorted((int(m.group(1)), h) for h in header if (m := pat.match(h)))
    return [h for _, h in found]


@pytest.mark.parametrize(
    "example, run_table",
    [
        ("cable_planar_arm.toml",
         '[run]\nduration = 0.1\nintegrator = "dopri5"\nrtol = 1e-5\natol = 1e-8\noutput_every = 0.01'),
        ("oscillating_base.toml", "[run]\nduration = 0.1\noutput_every = 0.01"),
    ],
)
def test_npz_loads_with_numpy_and_equals_the_csv(tmp_path, softrod_bin, example, run_table):
    scene = with_run(example, run_table, tmp_path / example)
    out = tmp_path / "out"
    subprocess.run([str(softrod_bin), "run", str(scene), "--out", str(out), "--quiet", "--npz"],
                   check=True, capture_output=True)
    header, data = read_csv(out / "trajectory.csv")
    summary = json.loads((out / "summary.json").read_text())
    with np.load(out / "trajectory.npz") as z:
        a = {k: z[k] for k in z.files}
    m = data.shape[0]
    assert m == 11
    np.testing.assert_array_equal(a["t"], data[:, header.index("t")])
    assert a["t"].shape == (m,)
    q = numbered(header, "q")
    np.testing.assert_array_equal(a["q"], cols(header, data, q))
    np.testing.assert_array_equal(a["qdot"], cols(header, data, numbered(header, "qdot")))
    np.testing.assert_array_equal(
        a["tip"], cols(header, data, ["tip_x", "tip_y", "tip_z", "tip_qw", "tip_qx", "tip_qy", "tip_qz"]))
    np.testing.assert_array_equal(
        a["energy"], cols(header, data, ["energy", "kinetic", "elastic", "gravitational"]))
    assert a["q_names"].dtype.kind == "U"
    assert list(a["q_names"]) == summary["q_names"]
    assert len(q) == len(summary["q_names"])
    expected = {"t", "q", "qdot", "tip", "energy", "q_names"}
    tension = numbered(header, "tension")
    if tension:
        np.testing.assert_array_equal(a["tension"], cols(header, data, tension))
        np.testing.assert_array_equal(a["power"], cols(header, data, numbered(header, "power")))
        assert np.any(a["tension"] != 0)
        expected |= {"tension", "power"}
    pres = numbered(header, "prescribed")
    if pres:
        np.testing.assert_array_equal(a["prescribed"], cols(header, data, pres))
        np.testing.assert_array_equal(
            a["prescribed_force"], cols(header, data, numbered(header, "prescribed_force")))
        assert list(a["prescribed_names"]) == summary["prescribed_names"]
        expected |= {"prescribed", "prescribed_force", "prescribed_names"}
    assert set(a) == expected
    assert tension or pres, "each scene exercises an optional pair"


@pytest.mark.parametrize(
    "example, run_table",
    [
        ("cable_planar_arm.toml",
         '[run]\nduration = 0.1\nintegrator = "dopri5"\nrtol = 1e-5\natol = 1e-8\noutput_every = 0.01'),
        ("oscillating_base.toml", "[run]\nduration = 0.1\noutput_every = 0.01"),
        ("parallel_robot.toml", "[run]\nduration = 0.02\noutput_every = 0.005"),
    ],
)
def test_python_trajectory_table_is_the_csv(tmp_path, softrod_bin, example, run_table):
    """The Python trajectory's `table` and `columns` are trajectory.csv's
    numbers and header (one definition of the columns, one recorder): the
    same run, bit for bit, also the cable powers and drive forces."""
    scene = with_run(example, run_table, tmp_path / example)
    out = tmp_path / "out"
    subprocess.run([str(softrod_bin), "run", str(scene), "--out", str(out), "--quiet"],
                   check=True, capture_output=True)
    header, data = read_csv(out / "trajectory.csv")
    traj = softrod.Simulation.from_file(scene).simulate()
    assert traj.columns == header
    np.testing.assert_array_equal(traj.table, data)
    tension = numbered(header, "tension")
    if tension:
        np.testing.assert_array_equal(traj.tension, cols(header, data, tension))
        np.testing.assert_array_equal(traj.power, cols(header, data, numbered(header, "power")))
    pres = numbered(header, "prescribed")
    if pres:
        np.testing.assert_array_equal(traj.prescribed, cols(header, data, pres))
        np.testing.assert_array_equal(
            traj.prescribed_force, cols(header, data, numbered(header, "prescribed_force")))
