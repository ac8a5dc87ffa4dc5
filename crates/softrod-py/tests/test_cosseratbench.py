"""softrod as a cosseratbench solver: its cantilever against Euler-Bernoulli,
and the experiments outside softrod's model reported unsupported."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

cb = pytest.importorskip("cosseratbench")
from cosseratbench import experiment, registry  # noqa: E402


def test_the_solver_is_registered():
    solver = registry.load_solver("softrod")
    assert solver.name == "softrod"
    assert registry.load_solver("softrod", time_step_scale=2.0).rtol == pytest.approx(8e-5)


def test_cantilever_against_euler_bernoulli():
    result = experiment.run(registry.load_experiment("cantilever"), registry.load_solver("softrod"))
    assert result.outcome == "completed", result.failure or result.missing
    # The benchmark's own budget: geometric nonlinearity and shear each
    # change the deflection by < 0.1 % (experiments/cantilever.py); 20 PCS
    # pieces under-bend by 1/(4 N^2) = 0.06 % (docs/validation.md).
    assert result.metrics["tip_deflection_error"] < 2.6e-3
    # Quasi-static: settled (node speeds in rod lengths per second).
    assert result.metrics["settling_residual"] < 1e-4
    assert result.trajectory.positions[0].shape == (101, 21, 3)
    assert result.trajectory.directors[0].shape == (101, 20, 3)


@pytest.mark.parametrize("name, reason", [
    ("pendulum", "clamped at the start and free at the end"),
    ("catenary", "clamped at the start and free at the end"),
    ("twist", "self-contact"),
    ("pile", "rod_contact"),
    ("capstan", "cylinder_contact"),
])
def test_experiments_outside_the_model_are_unsupported(name, reason):
    result = experiment.run(registry.load_experiment(name), registry.load_solver("softrod"))
    assert result.outcome == "unsupported"
    assert any(reason in m for m in result.missing), result.missing


def test_the_command_line_runs_the_cantilever(tmp_path):
    exe = Path(sys.executable).parent / "cosseratbench"
    subprocess.run([str(exe), "run", "cantilever", "-s", "softrod", "-o", str(tmp_path)],
                   check=True, capture_output=True)
    results = list(tmp_path.rglob("result.json"))
    assert len(results) == 1
    assert json.loads(results[0].read_text())["outcome"] == "completed"
