"""Simulation.value_and_gradient (exact trajectory gradients by the discrete adjoint,
docs/theory-control.md G1-G9) against central differences of whole runs on one fixed
step sequence, its use by scipy.optimize.minimize(jac=True), and its errors."""

from __future__ import annotations

import numpy as np
import pytest

import softrod

SCENE = """
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "arm"
length = 0.3
pieces = 3
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1000.0, young = {young!r}, poisson = 0.5, viscosity = {viscosity!r} }}
[[cable]]
rod = "arm"
offset = [0.0, 0.006]
tension = {{ times = [0.0, 0.1], values = [{t0!r}, {t1!r}] }}
[run]
rtol = 1e-8
atol = 1e-10
"""
TRUTH = {"young": 1.0e6, "viscosity": 500.0, "t0": 1.0, "t1": 3.0}
TIMES = [0.04, 0.08, 0.1]
KW = {"fixed_step": 0.004, "newton_tol": 1e-3}


def sim(**over: float) -> softrod.Simulation:
    return softrod.Simulation.from_toml(SCENE.format(**{**TRUTH, **over}))


def loss(n: int) -> list[object]:
    targets = [[0.25, 0.0, 0.05], [0.28, 0.0, 0.0], [0.27, 0.0, -0.02]]
    return [
        {"type": "position", "rod": "arm", "times": TIMES, "targets": targets, "weight": 100.0},
        {"type": "quadratic", "times": [0.1], "q_weights": 0.1, "qdot_weights": np.full(n, 1e-3)},
    ]


def value(s: softrod.Simulation) -> float:
    return s.value_and_gradient(loss(s.n_dof), [], 0.1, **KW)[0]


def test_gradients_match_central_differences():
    s = sim()
    v, g = s.value_and_gradient(
        loss(s.n_dof), ["arm.young", "arm.viscosity", "cable0.tension", "qdot0"], 0.1, **KW
    )
    assert v > 0
    assert isinstance(g["arm.young"], float)
    assert g["cable0.tension"].shape == (2,) and g["qdot0"].shape == (s.n_dof,)
    for key, name, index in [
        ("young", "arm.young", None),
        ("viscosity", "arm.viscosity", None),
        ("t0", "cable0.tension", 0),
        ("t1", "cable0.tension", 1),
    ]:
        d = 1e-6 * TRUTH[key]
        fd = (value(sim(**{key: TRUTH[key] + d})) - value(sim(**{key: TRUTH[key] - d}))) / (2 * d)
        adjoint = g[name] if index is None else g[name][index]
        assert adjoint == pytest.approx(fd, rel=1e-6), key


def test_callable_loss_and_scipy():
    scipy_optimize = pytest.importorskip("scipy.optimize")
    # Recover the final tension value from the state it produces at the end.
    qref = _final_q(sim())

    def fun(x: np.ndarray) -> tuple[float, np.ndarray]:
        s = sim(t1=float(x[0]))

        def ell(t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
            e = q - qref
            return 0.5e4 * float(e @ e), 1e4 * e, np.zeros_like(qd)

        v, g = s.value_and_gradient(ell, ["cable0.tension"], 0.1, times=[0.1], **KW)
        return v, np.array([g["cable0.tension"][1]])

    r = scipy_optimize.minimize(fun, [1.0], jac=True, method="L-BFGS-B", bounds=[(0.0, 10.0)])
    assert r.x[0] == pytest.approx(TRUTH["t1"], rel=1e-4), r


def _final_q(s: softrod.Simulation) -> np.ndarray:
    captured: list[np.ndarray] = []

    def grab(t: float, q: np.ndarray, qd: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
        captured.append(q.copy())
        return 0.0, np.zeros_like(q), np.zeros_like(qd)

    s.value_and_gradient(grab, [], 0.1, times=[0.1], **KW)
    return captured[-1]


@pytest.mark.parametrize(
    ("params", "loss_term", "says"),
    [
        (["nope.young"], None, "no rod named 'nope'"),
        (["payload.mass"], None, "no body named 'payload'"),
        (["arm.stiffness"], None, "unknown parameter"),
        (["q0"], {"type": "position", "rod": "hand", "times": [0.1], "targets": [[0, 0, 0]]}, "hand"),
        (["q0"], {"type": "position", "times": [0.1], "targets": [[np.nan, 0, 0]]}, "NaN"),
        (["q0"], {"type": "wiggle", "times": [0.1]}, "unknown loss"),
    ],
)
def test_bad_input_names_it(params, loss_term, says):
    s = sim()
    with pytest.raises(softrod.InputError, match=says):
        s.value_and_gradient(loss_term or loss(s.n_dof), params, 0.1, **KW)


def test_a_failing_loss_function_is_reported():
    s = sim()

    def boom(t, q, qd):
        raise ValueError("no loss here")

    with pytest.raises(softrod.InputError, match="no loss here"):
        s.value_and_gradient(boom, ["q0"], 0.1, times=[0.1], **KW)
    with pytest.raises(softrod.InputError, match="non-finite"):
        s.value_and_gradient(
            lambda t, q, qd: (np.nan, q, qd), ["q0"], 0.1, times=[0.1], **KW
        )


def test_forward_sensitivities_equal_the_adjoint():
    # G21: a second algorithm over the same recorded steps; equal to round-off.
    s = sim()
    params = ["arm.young", "arm.viscosity", "cable0.tension", "q0", "qdot0"]
    va, ga = s.value_and_gradient(loss(s.n_dof), params, 0.1, **KW)
    vf, gf = s.value_and_gradient(loss(s.n_dof), params, 0.1, method="forward", **KW)
    assert va == vf
    scale = max(float(np.max(np.abs(ga[p]))) for p in params)
    for p in params:
        np.testing.assert_allclose(gf[p], ga[p], rtol=1e-8, atol=1e-12 * scale)


def test_radau5_scene_gradients_match_differences_and_forward_sensitivities():
    # G25, G26: a radau5 scene gets its own discrete adjoint (it was refused before). Its
    # Newton test is relative to its internal tolerance 0.1*rtol^(2/3), 46x this scene's
    # rtol: newton_tol scaled by rtol / (0.1*rtol^(2/3)) solves the stages of the
    # differenced runs to the same absolute accuracy as the esdirk runs above.
    radau = SCENE.replace("[run]", '[run]\nintegrator = "radau5"')
    kw = {"fixed_step": 0.004, "newton_tol": 1e-3 * 1e-8 / (0.1 * 1e-8 ** (2 / 3))}

    def make(**over: float) -> softrod.Simulation:
        return softrod.Simulation.from_toml(radau.format(**{**TRUTH, **over}))

    def val(s: softrod.Simulation) -> float:
        return s.value_and_gradient(loss(s.n_dof), [], 0.1, **kw)[0]

    s = make()
    params = ["arm.young", "arm.viscosity", "cable0.tension", "q0", "qdot0"]
    va, ga = s.value_and_gradient(loss(s.n_dof), params, 0.1, **kw)
    for key, name, index in [("young", "arm.young", None), ("t1", "cable0.tension", 1)]:
        d = 1e-6 * TRUTH[key]
        fd = (val(make(**{key: TRUTH[key] + d})) - val(make(**{key: TRUTH[key] - d}))) / (2 * d)
        adjoint = ga[name] if index is None else ga[name][index]
        assert adjoint == pytest.approx(fd, rel=1e-6), key
    # Both passes recompute the stages by one code and solve with one LU (transposed or
    # not): equal to round-off.
    vf, gf = s.value_and_gradient(loss(s.n_dof), params, 0.1, method="forward", **kw)
    assert va == vf
    scale = max(float(np.max(np.abs(ga[p]))) for p in params)
    for p in params:
        np.testing.assert_allclose(gf[p], ga[p], rtol=1e-10, atol=1e-12 * scale)


def test_an_unknown_gradient_method_names_it():
    s = sim()
    with pytest.raises(softrod.InputError, match="method: 'backward' is not a gradient method"):
        s.value_and_gradient(loss(s.n_dof), ["arm.young"], 0.1, method="backward", **KW)


CLOSED = """
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "a"
joint = {{ type = "revolute", axis = [0, 1, 0] }}
length = 0.3
pieces = 2
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1000.0, young = {young!r}, poisson = 0.5, viscosity = 300.0 }}
[[rod]]
name = "b"
base = {{ position = [0.3, 0.0, -0.15], rotation = [[0, 0, -1], [0, 1, 0], [1, 0, 0]] }}
joint = {{ type = "revolute", axis = [0, 1, 0] }}
length = 0.15
pieces = 2
strains = ["ky", "qx"]
section = {{ shape = "circle", radius = 0.008 }}
material = {{ density = 1100.0, young = 2.0e6, poisson = 0.5, viscosity = 1.0e3 }}
[[body]]
name = "hand"
parent = "b"
mass = {mass!r}
inertia = [1e-6, 1e-6, 1e-6]
[[closure]]
type = "ball"
a = {{ element = "a" }}
b = {{ element = "hand" }}
[run]
rtol = 1e-8
atol = 1e-10
"""


def test_closed_chain_gradient_matches_central_differences():
    """A four-bar closed by a ball joint (docs/theory-control.md G22-G24): the adjoint
    through the constrained dynamics against central differences of whole runs."""
    truth = {"young": 1.0e6, "mass": 0.01}

    def closed(**over: float) -> softrod.Simulation:
        return softrod.Simulation.from_toml(CLOSED.format(**{**truth, **over}))

    def closed_loss(n: int) -> list[object]:
        return [
            {
                "type": "position",
                "rod": "a",
                "s": 0.15,
                "times": TIMES,
                "targets": [[0.15, 0.0, 0.02]] * 3,
                "weight": 100.0,
            },
            {"type": "quadratic", "times": [0.1], "q_weights": 0.1, "qdot_weights": 1e-3},
        ]

    s = closed()
    _, g = s.value_and_gradient(closed_loss(s.n_dof), ["a.young", "hand.mass"], 0.1, **KW)
    for key, name in [("young", "a.young"), ("mass", "hand.mass")]:
        h = 1e-6 * truth[key]

        def at(x: float) -> float:
            c = closed(**{key: x})
            return c.value_and_gradient(closed_loss(c.n_dof), [], 0.1, **KW)[0]

        fd = (at(truth[key] + h) - at(truth[key] - h)) / (2 * h)
        assert g[name] == pytest.approx(fd, rel=1e-6), name


WRIST = """
[world]
gravity = [0.0, 0.0, -9.81]
[[rod]]
name = "upper"
length = 0.25
pieces = 2
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.01 }}
material = {{ density = 1100.0, young = 2.0e6, poisson = 0.5, viscosity = 2.0e3 }}
[[rod]]
name = "lower"
parent = "upper"
joint = {{ type = "{kind}", {axes}, prescribed = {{ times = [0.0, 0.05, 0.1], values = {values} }} }}
length = 0.2
pieces = 2
strains = ["ky", "kz", "qx"]
section = {{ shape = "circle", radius = 0.008 }}
material = {{ density = 1000.0, young = 2.0e6, poisson = 0.5, viscosity = 2.0e3 }}
[run]
rtol = 1e-8
atol = 1e-10
"""


def _wrist(values: np.ndarray) -> softrod.Simulation:
    if values.ndim == 1:
        kind, axes = "revolute", "axis = [0, 1, 0]"
    else:
        kind, axes = "universal", "axes = [[0, 1, 0], [0, 0, 1]]"
    text = WRIST.format(kind=kind, axes=axes, values=repr(values.tolist()))
    return softrod.Simulation.from_toml(text)


def _wrist_loss(n: int) -> list[object]:
    targets = [[0.4, 0.0, -0.05], [0.42, 0.02, -0.1], [0.38, -0.01, -0.12]]
    return [
        {"type": "position", "rod": "lower", "times": TIMES, "targets": targets, "weight": 100.0},
        {"type": "quadratic", "times": [0.1], "q_weights": 0.1, "qdot_weights": 1e-3},
    ]


@pytest.mark.parametrize(
    "values", [np.array([0.0, 0.4, 0.1]), np.array([[0.0, 0.0], [0.4, -0.2], [0.1, 0.3]])]
)
def test_prescribed_samples_match_central_differences(values):
    """ELEMENT.prescribed (docs/theory-control.md G17-G20): the gradient by a prescribed
    joint's samples, shaped as its values, against central differences of whole runs;
    the forward sensitivities give the same numbers."""
    s = _wrist(values)
    _, g = s.value_and_gradient(_wrist_loss(s.n_dof), ["lower.prescribed"], 0.1, **KW)
    gp = g["lower.prescribed"]
    assert gp.shape == values.shape
    for index in np.ndindex(values.shape):
        h = 1e-6

        def at(x: float) -> float:
            v = values.copy()
            v[index] = x
            w = _wrist(v)
            return w.value_and_gradient(_wrist_loss(w.n_dof), [], 0.1, **KW)[0]

        fd = (at(values[index] + h) - at(values[index] - h)) / (2 * h)
        assert gp[index] == pytest.approx(fd, rel=1e-6), index
    _, gf = s.value_and_gradient(
        _wrist_loss(s.n_dof), ["lower.prescribed"], 0.1, method="forward", **KW
    )
    scale = float(np.max(np.abs(gp)))
    np.testing.assert_allclose(gf["lower.prescribed"], gp, rtol=1e-8, atol=1e-12 * scale)


@pytest.mark.parametrize(
    ("param", "says"),
    [("elbow.prescribed", "no rod or body named 'elbow'"), ("upper.prescribed", "not prescribed")],
)
def test_bad_prescribed_parameters_name_it(param, says):
    s = _wrist(np.array([0.0, 0.4, 0.1]))
    with pytest.raises(softrod.InputError, match=says):
        s.value_and_gradient(_wrist_loss(s.n_dof), [param], 0.1, **KW)


ACTUATED_WRIST = WRIST.replace(
    "prescribed = {{ times = [0.0, 0.05, 0.1], values = {values} }}",
    "stiffness = 0.2, actuator = {{ force = {{ times = [0.0, 0.05, 0.1], values = {values} }} }}",
)


def test_actuator_force_table_matches_central_differences():
    """ELEMENT.actuator (docs/theory-control.md G29): the gradient by a joint actuator's
    torque table, shaped as its values, against central differences of whole runs."""
    assert "actuator" in ACTUATED_WRIST
    values = np.array([[0.0, 0.01], [0.02, -0.01], [-0.01, 0.015]])

    def sim(v: np.ndarray) -> softrod.Simulation:
        text = ACTUATED_WRIST.format(
            kind="universal", axes="axes = [[0, 1, 0], [0, 0, 1]]", values=repr(v.tolist())
        )
        return softrod.Simulation.from_toml(text)

    s = sim(values)
    _, g = s.value_and_gradient(_wrist_loss(s.n_dof), ["lower.actuator"], 0.1, **KW)
    ga = g["lower.actuator"]
    assert ga.shape == values.shape
    for index in np.ndindex(values.shape):
        h = 1e-6

        def at(x: float) -> float:
            v = values.copy()
            v[index] = x
            w = sim(v)
            return w.value_and_gradient(_wrist_loss(w.n_dof), [], 0.1, **KW)[0]

        fd = (at(values[index] + h) - at(values[index] - h)) / (2 * h)
        assert ga[index] == pytest.approx(fd, rel=1e-6), index
    with pytest.raises(softrod.InputError, match="no actuator"):
        s.value_and_gradient(_wrist_loss(s.n_dof), ["upper.actuator"], 0.1, **KW)
