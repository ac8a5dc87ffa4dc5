"""Cable friction along the channel (docs/theory.md D15f) from Python: a
planar arm without gravity, one cable at offset d anchored at the tip. The
tension decays as T e^(-mu phi), so the turning angle follows
phi(s) = ln(1 + mu k0 s)/mu, k0 = T d / EI (the closed form of the Rust
test tests/cable_friction.rs), and a Python-built arm equals the same
scene read from TOML."""

from __future__ import annotations

import math

import numpy as np
import pytest

import softrod

E, R, L, D, MU = 1.0e6, 0.01, 0.3, 0.008, 0.3
EI = E * math.pi * R**4 / 4.0
T = 2.0 / L * EI / D  # k0 L = 2 rad


def arm(pieces: int, friction: float) -> softrod.Simulation:
    return softrod.Simulation(
        rods=[softrod.Rod(length=L, pieces=pieces, strains=["ky"],
                          section=softrod.Circle(R),
                          material=softrod.Material(density=1000.0, young=E, poisson=0.5),
                          cables=[softrod.Cable(offset=(0.0, D), tension=T,
                                                friction=friction)])],
        gravity=[0.0, 0.0, 0.0])


def test_turning_angle_follows_the_capstan_closed_form():
    k0 = T * D / EI
    n = 20
    q = np.asarray(arm(n, MU).statics().q)
    phi = np.cumsum(np.abs(q)) * (L / n)
    s = np.arange(1, n + 1) * (L / n)
    exact = np.log1p(MU * k0 * s) / MU
    # Second order in the piece length: 3.7e-5 of phi(L) at 20 pieces.
    assert np.abs(phi - exact).max() < 1e-4 * exact[-1]
    # Without friction the arc is uniform.
    q0 = np.asarray(arm(n, 0.0).statics().q)
    np.testing.assert_allclose(np.abs(q0), k0, rtol=1e-9)


def test_python_and_toml_arms_agree():
    toml = (
        f"[world]\ngravity = [0.0, 0.0, 0.0]\n[[rod]]\nname = \"rod0\"\nlength = {L}\n"
        f"pieces = 8\nstrains = [\"ky\"]\nsection = {{ shape = \"circle\", radius = {R} }}\n"
        f"material = {{ density = 1000.0, young = {E}, poisson = 0.5 }}\n"
        f"[[cable]]\nrod = \"rod0\"\noffset = [0.0, {D}]\ntension = {T}\nfriction = {MU}\n"
    )
    from_toml = softrod.Simulation.from_toml(toml)
    np.testing.assert_allclose(np.asarray(from_toml.statics().q),
                               np.asarray(arm(8, MU).statics().q), rtol=1e-12, atol=1e-12)


def test_negative_friction_is_refused():
    with pytest.raises(softrod.InputError, match="friction"):
        softrod.Cable(offset=(0.0, D), tension=1.0, friction=-0.1)
