"""Shared helpers of the Python test suite (run by scripts/test.sh)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import softrod

REPO = Path(__file__).resolve().parents[3]
EXAMPLES = REPO / "examples"


def rod(pieces=10, strains="all", length=0.5, radius=0.01, young=1e7, poisson=0.5, **kw):
    """The facade tests' soft cantilever: L = 0.5 m, r = 1 cm, E = 10 MPa, rho = 1000."""
    return softrod.Rod(
        length=length,
        pieces=pieces,
        strains=strains,
        section=softrod.Circle(radius),
        material=softrod.Material(density=1000.0, young=young, poisson=poisson,
                                  viscosity=kw.pop("viscosity", 0.0)),
        **kw,
    )


def scene_text(rod_extra="", extra="", pieces=10):
    """The same cantilever as a scene (docs/scene-format.md)."""
    return (
        f'[[rod]]\nname = "arm"\nlength = 0.5\npieces = {pieces}\n{rod_extra}\n'
        'section = { shape = "circle", radius = 0.01 }\n'
        "material = { density = 1000.0, young = 1.0e7, poisson = 0.5 }\n"
        f"{extra}"
    )


def smooth_state(n, scale=0.3, seed=0.7):
    """A deterministic, non-trivial state: O(scale) strains and rates."""
    i = np.arange(n, dtype=float)
    return scale * np.sin(seed * i + 0.1), scale * np.cos(1.3 * i + 0.2)


@pytest.fixture(scope="session")
def softrod_bin() -> Path:
    """The `softrod` command: $SOFTROD_BIN, else the workspace's debug build
    (built by `cargo test --workspace`), else built here."""
    env = os.environ.get("SOFTROD_BIN")
    if env:
        return Path(env)
    for profile in ("debug", "release"):
        p = REPO / "target" / profile / "softrod"
        if p.exists():
            return p
    cargo = shutil.which("cargo")
    if cargo is None:
        pytest.skip("no softrod binary and no cargo to build it")
    subprocess.run([cargo, "build", "-p", "softrod-cli"], cwd=REPO, check=True)
    return REPO / "target" / "debug" / "softrod"


@pytest.fixture(scope="session")
def ray_cluster():
    """One real local Ray cluster for the whole session (Ray starts in
    seconds, so it is started once), shut down at the end."""
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()
