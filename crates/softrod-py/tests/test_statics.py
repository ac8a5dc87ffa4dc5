"""`Simulation.statics()` reports what `softrod statics --json` does, and
takes tensions and loads for a study without editing the scene: each is
checked against the same setting written in a scene, the CLI's JSON and the
kinematic queries."""

from __future__ import annotations

import ast
import json
import re
import subprocess

import numpy as np
import pytest

import softrod
from conftest import EXAMPLES


def example(name: str) -> str:
    return (EXAMPLES / name).read_text()


def test_statics_reports_the_cli_json(softrod_bin):
    scene = EXAMPLES / "parallel_robot.toml"
    r = subprocess.run([str(softrod_bin), "statics", str(scene), "--json"], check=True,
                       capture_output=True, text=True)
    cli = json.loads(r.stdout)
    sim = softrod.Simulation.from_file(scene)
    st = sim.statics()
    assert st.converged is True and cli["converged"] is True
    np.testing.assert_allclose(st.q, cli["q"], rtol=0, atol=1e-14)
    # The poses are those of the kinematic queries at the equilibrium.
    np.testing.assert_array_equal(st.tip, sim.tip_pose(0, st.q))
    for i, name in enumerate(sim.rod_names):
        np.testing.assert_array_equal(st.tips[name], sim.tip_pose(name, st.q))
        rod = next(r for r in cli["rods"] if r["name"] == name)
        np.testing.assert_allclose(st.tips[name][:3, 3], rod["tip"]["position"], atol=1e-14)
    body_poses = sim.body_poses(st.q)
    assert list(st.bodies) == [b["name"] for b in cli["bodies"]] == ["platform"]
    np.testing.assert_array_equal(st.bodies["platform"], body_poses[0])
    assert st.closures == sim.closure_residuals(st.q)
    assert set(st.closures) == {c["name"] for c in cli["closures"]}
    assert max(st.closures.values()) < 1e-9
    assert st.stable == cli["stable"]
    assert st.warnings == []


def test_tensions_equal_the_same_tensions_in_the_scene():
    text = example("cable_planar_arm.toml")
    u = [1.3, 0.4]
    tables = re.findall(r"^tension = \{.*\}$", text, re.M)
    assert len(tables) == 2
    edited = text
    for table, v in zip(tables, u):
        edited = edited.replace(table, f"tension = {v}")
    sim = softrod.Simulation.from_toml(text)
    by_scene = softrod.Simulation.from_toml(edited).statics()
    by_input = sim.statics(tensions=u)
    np.testing.assert_allclose(by_input.q, by_scene.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(by_input.tip, by_scene.tip, rtol=0, atol=1e-12)
    # The inputs hold for that solve only: the schedules are back.
    np.testing.assert_array_equal(sim.statics().q, softrod.Simulation.from_toml(text).statics().q)
    assert np.abs(by_input.q - sim.statics().q).max() > 1e-3


def test_loads_equal_the_same_load_in_the_scene():
    text = example("tip_load_statics.toml")
    unloaded = re.sub(r"\[\[load\]\].*?\n\n", "", text, flags=re.S)
    assert "[[load]]" not in unloaded
    scene = softrod.Simulation.from_toml(text).statics()
    load = softrod.PointLoad(s=0.5, force=[0.0, 0.0, -0.01], frame="world")
    sim = softrod.Simulation.from_toml(unloaded)
    studied = sim.statics(loads=[("beam", load)])
    np.testing.assert_allclose(studied.q, scene.q, rtol=0, atol=1e-12)
    # The scene's reference: the linear Timoshenko tip (5e-5 m).
    np.testing.assert_allclose(studied.tip[:3, 3], [0.49996623, 0.0, -5.3099394e-3], atol=5e-5)
    # The simulation keeps its own model: unloaded, the beam stays straight.
    assert np.abs(sim.statics().q).max() == 0.0
    # Two loads add up (by index and by name): about twice the deflection.
    double = sim.statics(loads=[(0, load), ("beam", load)])
    assert double.tip[2, 3] < 1.9 * studied.tip[2, 3]


def test_bad_study_inputs_raise_input_errors():
    sim = softrod.Simulation.from_file(EXAMPLES / "cable_planar_arm.toml")
    with pytest.raises(softrod.InputError, match=r"tensions must have shape \(2,\)"):
        sim.statics(tensions=[1.0])
    with pytest.raises(softrod.InputError, match=r"tensions\[1\] = -1"):
        sim.statics(tensions=[1.0, -1.0])
    load = softrod.PointLoad(s=0.1, force=[0.0, 0.0, 1.0])
    with pytest.raises(softrod.InputError, match=r"loads\[0\] must be a \(rod, softrod.PointLoad\)"):
        sim.statics(loads=[load])
    with pytest.raises(softrod.InputError, match="no rod"):
        sim.statics(loads=[("leg", load)])
    far = softrod.PointLoad(s=2.0, force=[0.0, 0.0, 1.0])
    with pytest.raises(softrod.InputError, match=r"loads\[0\]"):
        sim.statics(loads=[("arm", far)])


def test_reprs_are_readable():
    sim = softrod.Simulation.from_file(EXAMPLES / "cantilever_gravity.toml")
    st = sim.statics()
    r = repr(st)
    assert r.startswith("Statics(converged=True, iterations=") and "tip=[" in r, r
    m = repr(sim.modes())
    assert re.match(r"Modes\(\d+ about statics: [\d.]+, [\d.]+, [\d.]+, [\d.]+, … Hz\)", m), m
    tr = sim.simulate(0.01)
    t = repr(tr)
    assert t.startswith(f"Trajectory({len(tr)} samples, t = 0") and "tip at the end [" in t, t


STUB = softrod.__file__.replace("__init__.py", "_softrod.pyi")


@pytest.mark.parametrize("cls", ["Statics", "Modes", "Trajectory"])
def test_the_stub_names_every_public_attribute(cls):
    tree = ast.parse(open(STUB, encoding="utf-8").read())
    node = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == cls)
    stubbed = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
    public = {a for a in dir(getattr(softrod, cls)) if not a.startswith("_")}
    assert public <= stubbed, public - stubbed
