"""Physics through Python against independent references: exact circle
arcs, the Timoshenko beam, the elastica (a shooting solution computed here),
Euler-Bernoulli modes, conservation of energy, forward vs inverse dynamics,
and every matrix against finite differences or a second formula."""

from __future__ import annotations

import math

import numpy as np
import pytest

import softrod
from conftest import rod, smooth_state

E, R, L, RHO = 1e7, 0.01, 0.5, 1000.0


@pytest.mark.parametrize("kappa", [0.0, 1e-12, 2.0, 80.0])
def test_constant_curvature_is_a_circle_arc(kappa):
    """A uniform curvature kappa about y is an arc of radius 1/kappa, exact
    whatever the pieces, from straight (0, 1e-12: the series branch) to six
    turns per piece (80 rad/m over 0.05 m pieces)."""
    # Closed-form exponentials: round-off of a few operations per piece
    # on 0.5 m, times the 10 pieces composed.
    arc_tol = 1e-13
    sim = softrod.Simulation(rods=[rod(strains=["ky"])])
    s = np.linspace(0.0, L, 23)
    p = sim.pose(0, s, np.full(10, kappa))[:, :3, 3]
    if kappa == 0.0:
        want = np.stack([s, 0 * s, 0 * s], axis=1)
    else:
        # Bending about +y turns the tangent x toward -z; 1 - cos x written
        # as 2 sin^2(x/2), which does not cancel at kappa = 1e-12.
        want = np.stack([np.sin(kappa * s) / kappa, 0 * s,
                         -2 * np.sin(kappa * s / 2) ** 2 / kappa], axis=1)
    assert np.abs(p - want).max() < arc_tol
    # The tangent turns by kappa * s about y.
    g = sim.pose(0, L, np.full(10, kappa))
    c, sn = math.cos(kappa * L), math.sin(kappa * L)
    assert np.abs(g[:3, :3] - [[c, 0, sn], [0, 1, 0], [-sn, 0, c]]).max() < arc_tol


def test_statics_of_a_small_tip_load_is_the_timoshenko_beam():
    """delta = PL^3/(3EI) + PL/(GA) (examples/tip_load_statics.toml)."""
    # 10 pieces of constant strain: tip error ~ delta/(4 N^2) = 1.3e-5 m.
    tip_tol = 2e-5
    p = 0.01
    sim = softrod.Simulation(rods=[rod(loads=[softrod.PointLoad(s=L, force=[0, 0, -p])])])
    eq = sim.statics()
    tip = sim.tip_pose(0, eq.q)[:3, 3]
    i, a, g = math.pi * R**4 / 4, math.pi * R**2, E / 3.0
    delta = p * L**3 / (3 * E * i) + p * L / (g * a)
    assert abs(tip[2] + delta) < tip_tol
    assert eq.residual < 1e-10


def elastica_shooting(alpha, steps=4000):
    """Kirchhoff elastica under a dead tip force (alpha = P L^2 / EI), by
    shooting on u = s/L: phi'' = -alpha cos(phi), phi(0) = 0, phi'(1) = 0;
    x' = cos(phi), y' = -sin(phi) (load along -y). Bisection on phi'(0),
    classical RK4. Returns the tip (x, y)/L."""

    def f(y):
        return np.array([y[1], -alpha * math.cos(y[0]), math.cos(y[0]), -math.sin(y[0])])

    def shoot(c):
        h, y = 1.0 / steps, np.array([0.0, c, 0.0, 0.0])
        for _ in range(steps):
            k1 = f(y)
            k2 = f(y + h / 2 * k1)
            k3 = f(y + h / 2 * k2)
            k4 = f(y + h * k3)
            y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return y

    lo, hi = 0.0, alpha
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if shoot(mid)[1] < 0.0:
            lo = mid
        else:
            hi = mid
    y = shoot(0.5 * (lo + hi))
    return y[2], y[3]


def test_large_deflection_statics_is_the_elastica():
    """A dead tip load with alpha = PL^2/EI = 3 (tip drop ~0.6 L) on an
    inextensible, unshearable planar rod (strains ["kz"])."""
    # The shooting reference reproduces Bisshopp & Drucker (1945), Table 1:
    # alpha = 1 drops the tip by 0.30172 L (5 digits published).
    _, y1 = elastica_shooting(1.0, steps=800)
    assert abs(y1 + 0.30172) < 1e-5
    alpha, n = 3.0, 32
    xr, yr = elastica_shooting(alpha, steps=800)
    ei = E * math.pi * R**4 / 4
    load = softrod.PointLoad(s=L, force=[0, -alpha * ei / L**2, 0])
    sim = softrod.Simulation(rods=[rod(pieces=n, strains=["kz"], loads=[load])])
    tip = sim.tip_pose(0, sim.statics().q)[:3, 3] / L
    err = math.hypot(tip[0] - xr, tip[1] - yr)
    # PCS converges as 1/N^2 with the linear-beam constant 1/(4N^2) of the
    # tip deflection (docs/validation.md); the elastica must be within it.
    assert err < math.hypot(xr, yr) / (4 * n * n)
    assert err > 0.0


def test_modes_are_euler_bernoulli_frequencies():
    """omega_i = (beta_i L)^2 sqrt(EI/rho A)/L^2 above which PCS lies by the
    Rayleigh-Ritz error C_i/N^2, C = 0.19366, 1.35072 (docs/validation.md)."""
    ritz = [0.19366, 1.35072]
    # At N = 20 the next order is < 1 % of C/N^2 (docs/validation.md).
    ritz_rel_tol = 0.02
    sim = softrod.Simulation(rods=[rod(length=1.0, pieces=20, strains=["ky"], radius=1e-3)])
    m = sim.modes()
    assert m.equilibrium == "rest"
    i, a = math.pi * 1e-3**4 / 4, math.pi * 1e-3**2
    for k, bl in enumerate([1.875104, 4.694091]):
        exact = bl * bl * math.sqrt(E * i / (RHO * a))
        err = m.omega[k] / exact - 1
        assert abs(err / (ritz[k] / 400) - 1) < ritz_rel_tol
    np.testing.assert_allclose(m.frequencies_hz, m.omega / (2 * math.pi), rtol=1e-15)
    # Mode shapes are M-orthonormal.
    mm = sim.mass_matrix(0.0, np.zeros(sim.n_dof))
    v = m.shapes
    assert np.abs(v.T @ mm @ v - np.eye(v.shape[1])).max() < 1e-9


def test_lowest_modes_of_a_long_chain():
    """lowest_modes on 200 bending pieces (Lanczos, above 160 coordinates):
    Euler-Bernoulli with the Ritz error C_i/N^2 as above, N = 200, and
    M-orthonormal shapes."""
    ritz = [0.19366, 1.35072]
    ritz_rel_tol = 0.02
    n, r = 200, 1e-4  # L/r = 1e4: rotary inertia far below C/N^2
    sim = softrod.Simulation(rods=[rod(length=1.0, pieces=n, strains=["ky"], radius=r)])
    m = sim.lowest_modes(2)
    assert m.equilibrium == "rest"
    assert m.omega.shape == (2,) and m.shapes.shape == (n, 2)
    i, a = math.pi * r**4 / 4, math.pi * r**2
    for k, bl in enumerate([1.875104, 4.694091]):
        exact = bl * bl * math.sqrt(E * i / (RHO * a))
        err = m.omega[k] / exact - 1
        assert abs(err / (ritz[k] / n**2) - 1) < ritz_rel_tol
    mm = sim.mass_matrix(0.0, np.zeros(sim.n_dof))
    v = m.shapes
    assert np.abs(v.T @ mm @ v - np.eye(2)).max() < 1e-9


def test_undamped_release_conserves_energy():
    # dopri5 at rtol 1e-9 over 0.05 s: drift ~1e-9 of the ~1e-2 J exchanged.
    energy_tol = 1e-8
    sim = softrod.Simulation(rods=[rod(pieces=4, strains=["ky", "qx", "qz"])],
                             gravity=[0, 0, -9.81])
    tr = sim.simulate(0.05, integrator="dopri5", rtol=1e-9, atol=1e-12, output_every=0.005)
    assert np.abs(tr.energy - tr.energy[0]).max() < energy_tol
    assert tr.kinetic.max() > 1e-4  # it moved: energy was exchanged
    e = sim.energies(0.0, tr.q[-1], tr.qdot[-1])
    assert e.total == pytest.approx(tr.energy[-1], rel=1e-14)
    # The run's watch saw the same states: its change is the samples' (the
    # last sample is the end of the run), no work, no warnings.
    b = tr.energy_balance
    assert b["change"] == pytest.approx(tr.energy[-1] - tr.energy[0], abs=1e-15)
    assert b["initial"] == pytest.approx(tr.energy[0], rel=1e-14)
    assert b["work"] == 0.0 and not b["non_conservative"]
    assert b["error"] < energy_tol and b["relative"] == pytest.approx(b["error"] / b["scale"])
    assert tr.warnings == []


def test_forward_and_inverse_dynamics_are_inverse():
    """q'' = FD(q, q', tau) then ID(q, q', q'') = tau: the articulated O(N)
    recursion against the RNEA, and both against M q'' + b = tau with M
    and b from their own routines."""
    # Round-off of O(N) recursions on O(1e2) forces at 60 coordinates.
    rel_tol = 1e-9
    sim = softrod.Simulation(rods=[rod(viscosity=5.0)], gravity=[0, 0, -9.81])
    n = sim.n_dof
    q, qd = smooth_state(n)
    tau = np.cos(np.arange(n))
    qdd = sim.forward_dynamics(0.0, q, qd, tau)
    back = sim.inverse_dynamics(0.0, q, qd, qdd)
    scale = np.abs(sim.bias_force(0.0, q, qd)).max()
    assert np.abs(back - tau).max() < rel_tol * scale
    lhs = sim.mass_matrix(0.0, q) @ qdd + sim.bias_force(0.0, q, qd)
    assert np.abs(lhs - tau).max() < rel_tol * scale


def test_jacobian_is_the_derivative_of_the_pose():
    """Body-frame J columns equal vee(g^-1 dg/dq_c) by central differences."""
    # h = 1e-6 on O(1) strains: O(h^2) truncation plus 1e-16/h round-off.
    fd_tol = 1e-8
    sim = softrod.Simulation(rods=[rod()])
    q, _ = smooth_state(sim.n_dof)
    at, h = 0.37, 1e-6
    j = sim.jacobian(0, at, q)
    jw = sim.jacobian(0, at, q, frame="world")
    g = sim.pose(0, at, q)
    r = g[:3, :3]
    for c in [0, 5, 17, 33, 59]:
        dq = np.zeros_like(q)
        dq[c] = h
        dg = (sim.pose(0, at, q + dq) - sim.pose(0, at, q - dq)) / (2 * h)
        w = r.T @ dg[:3, :3]
        fd = np.array([w[2, 1], w[0, 2], w[1, 0], *(r.T @ dg[:3, 3])])
        assert np.abs(j[:, c] - fd).max() < fd_tol
        # World (spatial) twist: Ad_g of the body twist.
        p = g[:3, 3]
        phat = np.array([[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]])
        ad = np.block([[r, np.zeros((3, 3))], [phat @ r, r]])
        assert np.abs(jw[:, c] - ad @ j[:, c]).max() < 1e-12


def test_matrices_against_energies_and_bias():
    """K q = dV_e/dq and G = dV_g/dq by central differences of the energies;
    C q' = b(q, q') - b(q, 0) (no damping); M - 2C skew via dM/dt."""
    sim = softrod.Simulation(rods=[rod(pieces=4)], gravity=[0, 0, -9.81])
    n = sim.n_dof
    q, qd = smooth_state(n, scale=0.2)
    z = np.zeros(n)
    h = 1e-6
    grad_e, grad_g = np.zeros(n), np.zeros(n)
    for c in range(n):
        dq = np.zeros(n)
        dq[c] = h
        ep, em = sim.energies(0.0, q + dq, z), sim.energies(0.0, q - dq, z)
        grad_e[c] = (ep.elastic - em.elastic) / (2 * h)
        grad_g[c] = (ep.gravitational - em.gravitational) / (2 * h)
    k = sim.stiffness_matrix()
    # Central differences (h = 1e-6) of energies ~1e-2 J: ~1e-10 absolute
    # round-off per derivative, O(h^2) truncation smaller.
    fd_tol = 1e-6
    assert np.abs(k @ q - grad_e).max() < fd_tol * np.abs(k @ q).max()
    assert np.abs(sim.gravity_force(0.0, q) - grad_g).max() < fd_tol * np.abs(grad_g).max()
    b0, b1 = sim.bias_force(0.0, q, z), sim.bias_force(0.0, q, qd)
    cq = sim.coriolis_force(q, qd)
    assert np.abs(cq - (b1 - b0)).max() < 1e-9 * np.abs(cq).max()
    mdot = (sim.mass_matrix(0.0, q + h * qd) - sim.mass_matrix(0.0, q - h * qd)) / (2 * h)
    s = mdot - 2 * sim.coriolis_matrix(q, qd)
    assert np.abs(s + s.T).max() < 1e-6 * np.abs(mdot).max()
    assert np.abs(sim.damping_matrix()).max() == 0.0


def test_actuation_matrix_of_a_straight_rod_is_the_lever_arm():
    """At the straight rest shape an offset cable at z0 shortens by z0 per
    unit of curvature ky and by 1 per unit of stretch: d l/d ky_n = z0 L_n,
    d l/d qx_n = L_n, so A = -dl/dq has -z0 L_n and -L_n there (D15)."""
    z0, n = 0.006, 5
    sim = softrod.Simulation(rods=[rod(pieces=n, strains=["ky", "qx"],
                                       cables=[softrod.Cable(offset=(0.0, z0), tension=2.0)])])
    a = sim.actuation_matrix(np.zeros(2 * n))
    ln = L / n
    np.testing.assert_allclose(a[0::2, 0], -z0 * ln, rtol=1e-14)
    np.testing.assert_allclose(a[1::2, 0], -ln, rtol=1e-14)


def test_tension_inputs_equal_scheduled_tensions():
    """u replaces the scheduled tensions: a rod whose cables are scheduled
    at T and the same rod with inputs u = T give the same accelerations,
    the dynamics layer's cable term against A(q) u built here."""
    cables = lambda t1, t2: [softrod.Cable(offset=(0.0, 0.008), tension=t1),  # noqa: E731
                             softrod.Cable(path=[[0.0, 0.004, 0.0], [0.5, 0.0, -0.006]],
                                           tension=t2, from_=0.1)]
    scheduled = softrod.Simulation(rods=[rod(pieces=6, cables=cables(1.5, 0.7))],
                                   gravity=[0, 0, -9.81])
    free = softrod.Simulation(rods=[rod(pieces=6, cables=cables(9.0, 9.0))],
                              gravity=[0, 0, -9.81])
    q, qd = smooth_state(scheduled.n_dof)
    want = scheduled.forward_dynamics(0.0, q, qd)
    got = free.forward_dynamics(0.0, q, qd, u=[1.5, 0.7])
    # Two summation orders of the same quadrature.
    assert np.abs(got - want).max() < 1e-9 * np.abs(want).max()
    # The inverse with inputs returns what is needed besides A u: zero here.
    back = free.inverse_dynamics(0.0, q, qd, got, u=[1.5, 0.7])
    assert np.abs(back).max() < 1e-9 * np.abs(free.bias_force(0.0, q, qd)).max()
    with pytest.raises(softrod.InputError, match="cannot push"):
        free.forward_dynamics(0.0, q, qd, u=[1.0, -0.1])


def test_linearize_is_the_derivative_of_the_dynamics():
    """A and B from the analytic derivatives against central differences of
    forward_dynamics, on a curved moving state of a rod with two cables
    (one routed along a path whose offsets change with s)."""
    cables = [softrod.Cable(offset=(0.0, 0.008), tension=1.5),
              softrod.Cable(path=[[0.0, 0.004, 0.0], [0.5, 0.0, -0.006]], tension=0.7)]
    sim = softrod.Simulation(rods=[rod(pieces=3, cables=cables, viscosity=0.02)],
                             gravity=[0, 0, -9.81])
    n = sim.n_dof
    q, qd = smooth_state(n)
    u = np.array([1.1, 0.4])
    a, b = sim.linearize(0.0, q, qd, u=u)
    assert a.shape == (2 * n, 2 * n) and b.shape == (2 * n, 2)
    assert sim.q_names[:3] == ["rod0.p0.kx", "rod0.p0.ky", "rod0.p0.kz"]
    np.testing.assert_array_equal(a[:n, :n], np.zeros((n, n)))
    np.testing.assert_array_equal(a[:n, n:], np.eye(n))

    def f(qq, vv, uu):
        return sim.forward_dynamics(0.0, qq, vv, u=uu)

    # |qdd| is ~1e8 here (O(0.3) shear strains of a stiff section): steps
    # are chosen against round-off. qdd is quadratic in qdot at fixed q
    # (Coriolis, centrifugal, damping), so central differences in qdot are
    # exact for any step, and a unit step keeps the round-off of qdd
    # (~4e-15 of it) below 1e-6 of the derivative (0.1 left it at 1.4e-6).
    h, hv = 1e-4, 1.0
    fd_q = np.column_stack([(f(q + h * e, qd, u) - f(q - h * e, qd, u)) / (2 * h)
                            for e in np.eye(n)])
    fd_v = np.column_stack([(f(q, qd + hv * e, u) - f(q, qd - hv * e, u)) / (2 * hv)
                            for e in np.eye(n)])
    # qdd is affine in u (the cables act as A(q) u): any step is exact, and a
    # large one keeps the round-off of the O(1e5) accelerations out.
    hu = 0.3
    fd_u = np.column_stack([(f(q, qd, u + hu * e) - f(q, qd, u - hu * e)) / (2 * hu)
                            for e in np.eye(2)])
    for got, want in [(a[n:, :n], fd_q), (a[n:, n:], fd_v), (b[n:], fd_u)]:
        scale = np.abs(want).max()
        assert np.abs(got - want).max() < 1e-6 * scale
    # The inputs given for the call do not stay: the schedules apply again.
    a0, _ = sim.linearize(0.0, q, qd)
    a1, _ = sim.linearize(0.0, q, qd, u=[1.5, 0.7])
    np.testing.assert_allclose(a0, a1, rtol=1e-12, atol=1e-12 * np.abs(a0).max())


def test_linearize_a_robot_is_the_derivative_of_the_dynamics():
    """The same on examples/arm_with_payload.toml: two rods, a revolute
    joint with spring and damper, two bodies, a cable on the upper rod (the
    analytic derivatives on the tree, docs/theory-derivatives.md §7)."""
    from conftest import EXAMPLES

    sim = softrod.Simulation.from_file(EXAMPLES / "arm_with_payload.toml")
    n = sim.n_dof
    assert "lower.joint.theta" in sim.q_names
    q, qd = smooth_state(n)
    u = np.array([3.0])
    a, b = sim.linearize(0.1, q, qd, u=u)

    def f(qq, vv, uu):
        return sim.forward_dynamics(0.1, qq, vv, u=uu)

    h, hv, hu = 1e-5, 1.0, 0.5
    fd_q = np.column_stack([(f(q + h * e, qd, u) - f(q - h * e, qd, u)) / (2 * h)
                            for e in np.eye(n)])
    fd_v = np.column_stack([(f(q, qd + hv * e, u) - f(q, qd - hv * e, u)) / (2 * hv)
                            for e in np.eye(n)])
    fd_u = (f(q, qd, u + hu) - f(q, qd, u - hu)) / (2 * hu)
    for got, want in [(a[n:, :n], fd_q), (a[n:, n:], fd_v), (b[n:, 0], fd_u)]:
        scale = np.abs(want).max()
        assert np.abs(got - want).max() < 1e-6 * scale


def test_pose_and_jacobian_of_a_robot_go_through_the_joints():
    """On examples/arm_with_payload.toml the lower rod hangs from a body on
    the upper rod through a revolute joint: pose(s) is the world pose (its
    tip equals tip_pose) and jacobian(s, frame="world") is the derivative of
    that pose (omega from dR R^T, v = dp - omega x p), with the upper rod's
    and the joint's columns."""
    from conftest import EXAMPLES

    sim = softrod.Simulation.from_file(EXAMPLES / "arm_with_payload.toml")
    n = sim.n_dof
    q, _ = smooth_state(n)
    np.testing.assert_allclose(sim.pose("lower", 0.2, q), sim.tip_pose("lower", q),
                               rtol=0, atol=1e-14)
    s = np.array([0.0, 0.07, 0.2])
    js = sim.jacobian("lower", s, q, frame="world")
    assert js.shape == (3, 6, n)
    h = 1e-6
    for k, x in enumerate(s):
        g = sim.pose("lower", x, q)
        for c in range(n):
            e = np.eye(n)[c]
            gp, gm = sim.pose("lower", x, q + h * e), sim.pose("lower", x, q - h * e)
            w = (gp[:3, :3] - gm[:3, :3]) / (2 * h) @ g[:3, :3].T
            omega = np.array([w[2, 1], w[0, 2], w[1, 0]])
            v = (gp[:3, 3] - gm[:3, 3]) / (2 * h) - np.cross(omega, g[:3, 3])
            np.testing.assert_allclose(js[k, :, c], np.concatenate([omega, v]),
                                       rtol=0, atol=1e-8)
    joint = sim.q_names.index("lower.joint.theta")
    assert np.abs(js[:, :, joint]).max() > 0.1
    assert np.abs(js[:, :, :12]).max() > 0.01  # the upper rod moves it too


def test_robot_trajectories_are_in_the_world_frame():
    """A run of examples/arm_with_payload.toml, scheduled and with a
    controller: the recorded tips and Trajectory.shape are world positions
    (through the joint and the bodies), equal to tip_pose of the same q."""
    from conftest import EXAMPLES

    sim = softrod.Simulation.from_file(EXAMPLES / "arm_with_payload.toml")
    for traj in [sim.simulate(0.05, output_every=0.025),
                 sim.simulate(0.05, output_every=0.025,
                              controller=lambda t, q, qd: [2.0])]:
        for i in range(len(traj.t)):
            q = traj.q[i]
            want = sim.tip_pose("lower", q)[:3, 3]
            np.testing.assert_allclose(traj.tip_positions[i, 1], want, rtol=0, atol=1e-13)
            np.testing.assert_allclose(traj.shape(i, rod="lower")[-1], want,
                                       rtol=0, atol=1e-13)
            np.testing.assert_allclose(traj.shape(i, rod="lower", s=[0.2])[0], want,
                                       rtol=0, atol=1e-13)


def test_prescribed_force_drives_the_free_joint_along_the_curve(tmp_path):
    """A tentacle on a sideways-shaken base (examples/oscillating_base.toml):
    the drive is not a coordinate; the force it reports, applied to the same
    joint left free (a second scene), gives the joint the prescribed
    acceleration -A (2 pi f)^2 sin(2 pi f t) and the rod the same strain
    accelerations."""
    from conftest import EXAMPLES

    path = EXAMPLES / "oscillating_base.toml"
    sim = softrod.Simulation.from_file(path)
    assert sim.prescribed_names == ["tentacle.joint.d"]
    assert "tentacle.joint.d" not in sim.q_names
    text = path.read_text()
    drive = ", prescribed = { sine = { amplitude = 0.01, frequency = 2.0 } }"
    assert drive in text
    free_path = tmp_path / "free.toml"
    free_path.write_text(text.replace(drive, ""))
    free = softrod.Simulation.from_file(free_path)
    assert free.q_names[0] == "tentacle.joint.d"
    n = sim.n_dof
    assert free.n_dof == n + 1
    w = 2.0 * math.pi * 2.0
    q, qd = smooth_state(n)
    for t in [0.0, 0.07, 0.31]:
        f = sim.prescribed_forces(t, q, qd)
        assert f.shape == (1,)
        qdd = sim.forward_dynamics(t, q, qd)
        x, v = 0.01 * math.sin(w * t), 0.01 * w * math.cos(w * t)
        tau = np.zeros(n + 1)
        tau[0] = f[0]
        qdd_free = free.forward_dynamics(
            t, np.concatenate([[x], q]), np.concatenate([[v], qd]), tau=tau
        )
        scale = np.abs(qdd_free).max()
        assert abs(qdd_free[0] + 0.01 * w * w * math.sin(w * t)) < 1e-10 * scale
        assert np.abs(qdd_free[1:] - qdd).max() < 1e-10 * scale


def test_closure_residual_is_the_distance_between_the_held_points():
    """examples/parallel_robot.toml: at the assembled start every closure
    holds; at a perturbed q the ball closure's residual is the distance
    between leg 3's tip and the platform's corner, computed here from the
    rod's tip pose and the platform's pose; a short run keeps it small."""
    from conftest import EXAMPLES

    sim = softrod.Simulation.from_file(EXAMPLES / "parallel_robot.toml")
    n = sim.n_dof
    res = sim.closure_residuals(np.zeros(n))
    assert set(res) == {"leg2 weld", "leg3 ball"}
    assert max(res.values()) < 1e-9 * 0.3
    q = 0.2 * np.sin(1.3 * np.arange(1, n + 1))
    tip = sim.tip_pose("leg3", q)[:3, 3]
    platform = sim.body_poses(q)[0]
    corner = platform[:3, :3] @ np.array([-0.025, -0.04330127018922193, 0.0]) + platform[:3, 3]
    d = np.linalg.norm(tip - corner)
    assert d > 1e-3
    assert abs(sim.closure_residuals(q)["leg3 ball"] - d) < 1e-12
    traj = sim.simulate(0.05, output_every=0.01)
    assert max(sim.closure_residuals(traj.q[-1]).values()) < 1e-6 * 0.3
