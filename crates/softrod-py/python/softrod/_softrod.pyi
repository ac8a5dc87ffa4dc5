"""Type stubs of the compiled module softrod._softrod (re-exported by softrod).

Arrays are float64 numpy arrays; ``ArrayLike`` inputs are converted with
``numpy.ascontiguousarray(x, dtype=float64)`` (a float64 C-contiguous array
is read in place). Shapes are checked: a wrong one raises
``softrod.InputError`` naming the argument and both shapes.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal, final, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

_F64 = NDArray[np.float64]
_RodRef = str | int
_Frame = Literal["body", "world"]
# The integrator names, in the order of softrod.INTEGRATORS (Rust's
# Integrator::ALL); tests/test_integrators.py checks that they agree.
_IntegratorName = Literal["rk4", "dopri5", "rosenbrock", "generalized-alpha", "esdirk", "esdirk5", "radau5"]
_Controller = Callable[[float, _F64, _F64], ArrayLike]

__version__: str
#: The integrator names ``Settings(integrator=...)`` and ``simulate`` accept.
INTEGRATORS: tuple[_IntegratorName, ...]

class Section:
    """A cross-section; construct a Circle, Tube, Rectangle or TaperedCircle."""
    @property
    def shape(self) -> Literal["circle", "tube", "rectangle", "tapered_circle"]: ...
    @property
    def area(self) -> float:
        """Area A [m^2] at the base."""
    @property
    def second_moments(self) -> tuple[float, float, float]:
        """(Jx, Jy, Jz) [m^4] at the base; Jx = Jy + Jz."""

@final
class Circle(Section):
    """Solid circle of radius `radius` [m]."""
    def __new__(cls, radius: float) -> Circle: ...

@final
class Tube(Section):
    """Hollow circle: outer `radius`, `inner_radius` in [0, radius) [m]."""
    def __new__(cls, radius: float, inner_radius: float) -> Tube: ...

@final
class Rectangle(Section):
    """Solid rectangle: `width` along local y, `height` along local z [m]."""
    def __new__(cls, width: float, height: float) -> Rectangle: ...

@final
class TaperedCircle(Section):
    """Solid circle, radius linear from `radius_base` (s = 0) to `radius_tip` (s = L) [m]."""
    def __new__(cls, radius_base: float, radius_tip: float) -> TaperedCircle: ...

@final
class Material:
    """Linear elastic, Kelvin-Voigt viscous material: density [kg/m^3], Young's
    modulus [Pa], exactly one of `poisson` or `shear_modulus` [Pa], and the
    shear viscosity [Pa s] (bending damping 3 mu J against stiffness E J)."""
    def __new__(
        cls,
        density: float,
        young: float,
        poisson: float | None = None,
        shear_modulus: float | None = None,
        viscosity: float = 0.0,
    ) -> Material: ...
    @property
    def density(self) -> float: ...
    @property
    def young(self) -> float: ...
    @property
    def shear_modulus(self) -> float: ...
    @property
    def poisson(self) -> float: ...
    @property
    def viscosity(self) -> float: ...

@final
class Cable:
    """A cable through the section: `offset=(y, z)` [m] or `path=[(s, y, z), ...]`,
    `tension` [N] constant or `(times, values)`, span `from_`..`to` [m],
    `friction` along the channel (a pulled cable's tension decays as
    `T e^(-friction * turning angle)`)."""
    def __new__(
        cls,
        offset: ArrayLike | None = None,
        *,
        path: ArrayLike | None = None,
        tension: float | tuple[ArrayLike, ArrayLike] | None = None,
        from_: float = 0.0,
        to: float | None = None,
        friction: float = 0.0,
    ) -> Cable: ...

@final
class PointLoad:
    """A point load at `s` [m]: `force` [N], `moment` [N m] in `frame`
    ("world": dead load, "body": follower load)."""
    def __new__(
        cls,
        s: float,
        force: ArrayLike,
        moment: ArrayLike | None = None,
        frame: Literal["world", "body"] = "world",
    ) -> PointLoad: ...

@final
class Rod:
    """One rod: `pieces` (count or lengths [m]), `strains` ("all" or names of
    kx, ky, kz, qx, qy, qz; coordinates in that canonical order), `section`,
    `material`, optional `name`, `base` (4x4 transform or {"position",
    "rotation"}), `rest_strain` (6,), `drag` (translational, rotational),
    `cables`, `loads`, `contact_radius` [m]; on a robot `parent`, `at` [m]
    and `joint` (softrod.Joint(...) or a dict of the scene's joint keys)."""
    def __new__(
        cls,
        length: float,
        pieces: int | Sequence[float] | ArrayLike,
        strains: Literal["all"] | Sequence[str] | None = None,
        *,
        section: Section,
        material: Material,
        name: str | None = None,
        base: ArrayLike | dict[str, ArrayLike] | None = None,
        rest_strain: ArrayLike | None = None,
        drag: tuple[float, float] | None = None,
        cables: list[Cable] | None = None,
        loads: list[PointLoad] | None = None,
        contact_radius: float | None = None,
        parent: str | None = None,
        at: float | None = None,
        joint: Mapping[str, Any] | None = None,
    ) -> Rod: ...
    @property
    def name(self) -> str: ...
    @property
    def length(self) -> float: ...
    @property
    def n_pieces(self) -> int: ...
    @property
    def n_dof(self) -> int: ...
    @property
    def n_cables(self) -> int: ...

@final
class Settings:
    """Run settings; Settings() is the recommended setting (docs/defaults.md)."""
    def __new__(
        cls,
        integrator: _IntegratorName | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        dt: float | None = None,
        output_every: float | None = None,
        error_control: bool | None = None,
        linearly_implicit: bool | None = None,
        steps_to_outputs: bool | None = None,
        project_closures: bool | None = None,
    ) -> Settings: ...
    def replace(
        self,
        *,
        integrator: _IntegratorName | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        dt: float | None = None,
        output_every: float | None = None,
        error_control: bool | None = None,
        linearly_implicit: bool | None = None,
        steps_to_outputs: bool | None = None,
        project_closures: bool | None = None,
    ) -> Settings:
        """A copy with the named keywords changed; the rest (and the scene's duration and
        energy tolerance) kept."""
    @property
    def integrator(self) -> _IntegratorName: ...
    @property
    def rtol(self) -> float: ...
    @property
    def atol(self) -> float: ...
    @property
    def dt(self) -> float: ...
    @property
    def output_every(self) -> float | None: ...
    @property
    def error_control(self) -> bool: ...
    @property
    def linearly_implicit(self) -> bool: ...
    @property
    def steps_to_outputs(self) -> bool: ...
    @property
    def project_closures(self) -> bool: ...

@final
class Energies:
    """Energies at one state [J]."""
    @property
    def kinetic(self) -> float: ...
    @property
    def elastic(self) -> float: ...
    @property
    def gravitational(self) -> float: ...
    @property
    def total(self) -> float: ...

@final
class Statics:
    """A static equilibrium with what `softrod statics --json` reports."""
    @property
    def q(self) -> _F64:
        """(n_dof,)"""
    @property
    def converged(self) -> bool:
        """Always True: a solve that does not converge raises SimulationError."""
    @property
    def iterations(self) -> int: ...
    @property
    def residual(self) -> float:
        """max-abs generalized force left [N or N m]"""
    @property
    def load_steps(self) -> int: ...
    @property
    def stable(self) -> bool | None:
        """No linearized mode is unstable (rigid modes are neutral); None for models over 600 DoF."""
    @property
    def tip(self) -> _F64:
        """The first rod's tip pose (4, 4), world frame [m]."""
    @property
    def tips(self) -> dict[str, _F64]:
        """Every rod's tip pose (4, 4) by rod name."""
    @property
    def bodies(self) -> dict[str, _F64]:
        """Every rigid body's pose (4, 4) by body name."""
    @property
    def closures(self) -> dict[str, float]:
        """Loop-closure residuals [m] by closure name."""
    @property
    def contacts(self) -> list[Contact]:
        """The contacts at the equilibrium (statics --json's)."""
    @property
    def max_penetration(self) -> float:
        """Their largest -gap [m], 0 if none."""
    @property
    def warnings(self) -> list[str]:
        """The validity rules the equilibrium breaks and, when it is unstable, that; empty otherwise."""

@final
class Modes:
    """Undamped natural modes, lowest first."""
    @property
    def omega(self) -> _F64:
        """(n_modes,) [rad/s]"""
    @property
    def frequencies_hz(self) -> _F64:
        """(n_modes,) [Hz]"""
    @property
    def shapes(self) -> _F64:
        """(n_dof, n_modes), M-orthonormal columns"""
    @property
    def q_equilibrium(self) -> _F64:
        """(n_dof,)"""
    @property
    def equilibrium(self) -> Literal["rest", "statics", "given"]: ...
    @property
    def asymmetry(self) -> float: ...
    @property
    def rigid_tolerance(self) -> float:
        """|ω²| [rad²/s²] at or below which a mode is rigid (ω = 0)"""
    @property
    def n_rigid(self) -> int: ...
    @property
    def n_unstable(self) -> int: ...
    @property
    def warnings(self) -> list[str]: ...

@final
class State:
    """State of the step API (t [s], q and qdot (n_dof,), read-only copies)."""
    def __new__(cls, t: float, q: ArrayLike, qdot: ArrayLike) -> State: ...
    @property
    def t(self) -> float: ...
    @property
    def q(self) -> _F64: ...
    @property
    def qdot(self) -> _F64: ...

@final
class Trajectory:
    """A run: read-only arrays at the output times (index 0 is t = 0)."""
    @property
    def t(self) -> _F64:
        """(n_samples,) [s]"""
    @property
    def q(self) -> _F64:
        """(n_samples, n_dof)"""
    @property
    def qdot(self) -> _F64:
        """(n_samples, n_dof)"""
    @property
    def tip_position(self) -> _F64:
        """(n_samples, 3) [m], first rod"""
    @property
    def tip_rotation(self) -> _F64:
        """(n_samples, 3, 3), first rod"""
    @property
    def tip_positions(self) -> _F64:
        """(n_samples, n_rods, 3) [m]"""
    @property
    def tip_rotations(self) -> _F64:
        """(n_samples, n_rods, 3, 3)"""
    @property
    def kinetic(self) -> _F64: ...
    @property
    def elastic(self) -> _F64: ...
    @property
    def gravitational(self) -> _F64: ...
    @property
    def energy(self) -> _F64:
        """(n_samples,) [J], kinetic + elastic + gravitational"""
    @property
    def tension(self) -> _F64:
        """(n_samples, n_cables) [N]"""
    @property
    def power(self) -> _F64:
        """(n_samples, n_cables) [W]"""
    @property
    def prescribed(self) -> _F64:
        """(n_samples, n_prescribed) [rad or m]"""
    @property
    def prescribed_force(self) -> _F64:
        """(n_samples, n_prescribed) [N m or N]"""
    @property
    def columns(self) -> list[str]:
        """trajectory.csv's header"""
    @property
    def table(self) -> _F64:
        """(n_samples, len(columns)): trajectory.csv's numbers"""
    @property
    def status(self) -> Literal["completed", "stopped"]: ...
    @property
    def t_final(self) -> float: ...
    @property
    def stats(self) -> dict[str, int]: ...
    @property
    def energy_balance(self) -> dict[str, float | bool] | None:
        """initial, change, work, error, relative, scale, t_worst, quadrature [J or s], non_conservative"""
    @property
    def warnings(self) -> list[str]: ...
    def shape(self, i: int = -1, rod: _RodRef | None = None, s: ArrayLike | None = None) -> _F64:
        """Positions (N + 1, 3) at the piece boundaries, or (len(s), 3), at sample i."""
    @property
    def contacts(self) -> list[list[Contact]]:
        """The active contacts at each sample (contacts.csv's rows)."""
    @property
    def max_penetration(self) -> float:
        """The largest -gap over the samples [m] (summary.json's)."""
    @property
    def max_contacts(self) -> int:
        """The most contacts at one sample (summary.json's)."""
    def __len__(self) -> int: ...

@final
class Contact:
    """One contact at a state (world frame, SI): rod `rod` at `s` touches
    `other` (an obstacle, or a rod at `other_s`); `normal` from other to the
    rod, `gap` (negative: penetration), `force` on the rod."""
    @property
    def rod(self) -> str: ...
    @property
    def rod_index(self) -> int: ...
    @property
    def s(self) -> float: ...
    @property
    def other(self) -> str: ...
    @property
    def other_kind(self) -> Literal["obstacle", "rod"]: ...
    @property
    def other_index(self) -> int: ...
    @property
    def other_s(self) -> float | None: ...
    @property
    def point(self) -> _F64:
        """(3,) [m]: on the rod's surface"""
    @property
    def normal(self) -> _F64:
        """(3,): unit, from other to the rod"""
    @property
    def gap(self) -> float: ...
    @property
    def force(self) -> _F64:
        """(3,) [N]: on the rod"""
    @property
    def sticking(self) -> bool: ...
    @property
    def state(self) -> Literal["stick", "slip"]: ...

@final
class Simulation:
    """A model with its initial state and run settings (see help(softrod.Simulation))."""
    def __new__(
        cls,
        rods: list[Rod | Mapping[str, Any]],
        gravity: ArrayLike | None = None,
        *,
        quadrature: int = 4,
        bodies: Sequence[Mapping[str, Any]] | None = None,
        closures: Sequence[Mapping[str, Any]] | None = None,
        obstacles: Sequence[Mapping[str, Any]] | None = None,
        contact: Mapping[str, Any] | None = None,
    ) -> Simulation:
        """Rods (softrod.Rod or [[rod]] dicts) and, with the scene's keys,
        [[body]], [[closure]], [[obstacle]] tables and the [contact] table."""
    @classmethod
    def from_dict(cls, scene: Mapping[str, Any], *, name: str = "<dict>") -> Simulation:
        """A scene as nested dicts and lists with the TOML file's keys."""
    @classmethod
    def from_toml(cls, text: str, *, name: str = "<string>") -> Simulation:
        """The scene text `text` (TOML); for a file call from_file."""
    @classmethod
    def from_file(cls, path: str | os.PathLike[str]) -> Simulation: ...
    @property
    def n_dof(self) -> int: ...
    @property
    def n_cables(self) -> int: ...
    @property
    def n_joint_inputs(self) -> int:
        """Actuated joint coordinates (the length of a joint_forces input)."""
    @property
    def joint_max_forces(self) -> list[float]:
        """Each actuated coordinate's max_force [N or N m]; inf where the scene gives none."""
    @property
    def joint_input_names(self) -> list[str]:
        """The actuated joint coordinates' names, in joint_forces order."""
    @property
    def n_prescribed(self) -> int:
        """Prescribed joint coordinates (the length of a prescribed_targets input)."""
    @property
    def prescribed_bounds(self) -> list[tuple[float, float] | None]:
        """Each prescribed coordinate's target range (the scene's joint.prescribed.bounds)."""
    @property
    def prescribed_targets(self) -> _F64 | None:
        """The targets in force (None: the scene's curves)."""
    def prescribed_state(self, t: float) -> tuple[_F64, _F64]:
        """The prescribed coordinates' values and rates at t under the motion in force."""
    def command_prescribed(self, t: float, dt: float, targets: ArrayLike) -> None:
        """Command targets over [t, t + dt] without stepping (the cubic to rest, docs/envs.md)."""
    def hold_prescribed(self, values: ArrayLike) -> None:
        """Hold the prescribed joints at values, at rest, until the next command or reset."""
    def reset_prescribed(self) -> None:
        """Put the scene's prescribed curves back in force."""
    @property
    def duration(self) -> float | None:
        """The scene's [run] duration [s]; None when built in Python."""
    @property
    def rod_lengths(self) -> list[float]: ...
    @property
    def rod_names(self) -> list[str]: ...
    @property
    def q_names(self) -> list[str]: ...
    @property
    def prescribed_names(self) -> list[str]: ...
    @property
    def body_names(self) -> list[str]: ...
    @property
    def obstacle_names(self) -> list[str]: ...
    def contacts(
        self, q: ArrayLike, qdot: ArrayLike | None = None, *, t: float = 0.0
    ) -> list[Contact]:
        """The active contacts at (t, q, qdot) under the contact state this simulation holds:
        the stiffness its last statics (without loads), simulate or step left, and their
        friction anchors; before any, the base stiffness and zero friction."""
    def reset_contact(self) -> None:
        """Forget the committed contact state (friction anchors, raised stiffnesses): the
        next step starts fresh, as on a new simulation."""
    def max_penetration(self, q: ArrayLike, *, t: float = 0.0) -> float:
        """The largest -gap [m] at q, 0 if none (geometry: independent of the contact state)."""
    def prescribed_forces(self, t: float, q: ArrayLike, qdot: ArrayLike) -> _F64: ...
    def closure_residuals(self, q: ArrayLike, *, t: float = 0.0) -> dict[str, float]: ...
    @property
    def rod_dofs(self) -> list[tuple[str, int, int]]: ...
    @property
    def terms(self) -> list[str]: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def gravity(self) -> _F64: ...
    @property
    def has_static_loads(self) -> bool: ...
    @property
    def settings(self) -> Settings: ...
    @settings.setter
    def settings(self, settings: Settings) -> None: ...
    def initial_state(self) -> tuple[_F64, _F64]: ...
    def set_initial_state(self, q: ArrayLike, qdot: ArrayLike) -> None: ...
    def initial(self) -> State: ...
    def pose(self, rod: _RodRef, s: float | ArrayLike, q: ArrayLike, *, t: float = 0.0) -> _F64:
        """(4, 4), or (len(s), 4, 4)"""
    def tip_pose(self, rod: _RodRef, q: ArrayLike, *, t: float = 0.0) -> _F64:
        """(4, 4)"""
    def body_poses(self, q: ArrayLike, *, t: float = 0.0) -> _F64:
        """(n_bodies, 4, 4)"""
    def jacobian(
        self, rod: _RodRef, s: float | ArrayLike, q: ArrayLike, frame: _Frame = "body", *,
        t: float = 0.0,
    ) -> _F64:
        """(6, n_dof), or (len(s), 6, n_dof)"""
    def forward_dynamics(
        self, t: float, q: ArrayLike, qdot: ArrayLike, tau: ArrayLike | None = None, *,
        u: ArrayLike | None = None,
    ) -> _F64:
        """(n_dof,)"""
    def inverse_dynamics(
        self, t: float, q: ArrayLike, qdot: ArrayLike, qddot: ArrayLike, *,
        u: ArrayLike | None = None,
    ) -> _F64:
        """(n_dof,)"""
    def mass_matrix(self, t: float, q: ArrayLike) -> _F64:
        """(n_dof, n_dof)"""
    def bias_force(self, t: float, q: ArrayLike, qdot: ArrayLike) -> _F64: ...
    def coriolis_matrix(self, q: ArrayLike, qdot: ArrayLike) -> _F64: ...
    def coriolis_force(self, q: ArrayLike, qdot: ArrayLike) -> _F64: ...
    def gravity_force(self, t: float, q: ArrayLike) -> _F64: ...
    def stiffness_matrix(self) -> _F64: ...
    def damping_matrix(self) -> _F64: ...
    def actuation_matrix(self, q: ArrayLike) -> _F64:
        """(n_dof, n_cables)"""
    def linearize(self, t: float, q: ArrayLike, qdot: ArrayLike, *,
                  u: ArrayLike | None = None) -> tuple[_F64, _F64]:
        """(A (2 n_dof, 2 n_dof), B (2 n_dof, n_cables)) of x' = f(x, u), x = (q, qdot)."""
    def energies(self, t: float, q: ArrayLike, qdot: ArrayLike) -> Energies: ...
    def statics(
        self, *, tensions: ArrayLike | None = None,
        loads: Sequence[tuple[_RodRef, PointLoad]] | None = None,
        joint_forces: ArrayLike | None = None,
    ) -> Statics:
        """tensions (n_cables,) [N] and joint_forces (n_joint_inputs,) replace the
        schedules, loads are added, for this solve."""
    def solve_actuation(
        self,
        targets: Sequence[dict[str, object]],
        *,
        max_tension: float | ArrayLike | None = None,
        effort_weight: float = 1e-9,
        reach_tolerance: float = 1e-6,
        max_iterations: int = 100,
        warm_start: dict[str, object] | None = None,
        t: float = 0.0,
        unknown_loads: Sequence[dict[str, object]] | None = None,
    ) -> dict[str, object]:
        """Inverse statics: tensions 0 <= T <= max_tension [N], actuated joints' forces
        |f| <= max_force [N or N m], unknown point loads ({"rod", "s", "max_force"}; default the
        scene's [[load]] unknown = true) and the equilibrium that bring
        rod sections or body frames closest to targets ({"rod", "s", "position", "rotation",
        "weight"}, or {"body", "position", "rotation", "weight"}); closed models included;
        returns converged, reached, message, tensions, q, bounds, forces, force_bounds,
        joint_forces, joint_force_bounds, residual, targets, ...
        Raises InputError on bad input, SimulationError if it does not converge."""
    def value_and_gradient(
        self,
        loss: dict[str, object]
        | Callable[[float, _F64, _F64], tuple[float, ArrayLike, ArrayLike]]
        | Sequence[object],
        params: Sequence[str],
        duration: float | None = None,
        *,
        times: ArrayLike | None = None,
        fixed_step: float | None = None,
        newton_tol: float | None = None,
        method: Literal["adjoint", "forward"] | None = None,
    ) -> tuple[float, dict[str, float | _F64]]:
        """Loss of a run and its exact gradient (discrete adjoint of esdirk, esdirk5 or radau5) w.r.t. params
        ("q0", "qdot0", "ROD.young", "ROD.shear_modulus", "ROD.density", "ROD.viscosity",
        "BODY.mass", "cableN.tension", "ELEMENT.prescribed": a prescribed joint's samples, shaped as
        its values; "ELEMENT.actuator": a joint actuator's force values, a table shaped as its
        values). loss: {"type": "position", "rod", "s", "times",
        "targets", "weight"}, {"type": "quadratic", "times", "q_weights", "qdot_weights",
        "q_ref"}, a callable l(t, q, qdot) -> (value, dl_dq, dl_dqdot) at `times`, or a list.
        method: "adjoint" (default) or "forward" (forward sensitivities; few parameters).
        Raises InputError naming a bad parameter or loss key."""
    def modes(self) -> Modes: ...
    def lowest_modes(self, count: int = 10) -> Modes:
        """The `count` lowest modes, lowest first; matrix-free (Lanczos) on large open models."""
    def modes_about(self, q: ArrayLike) -> Modes: ...
    def simulate(
        self,
        duration: float | None = None,
        *,
        output_every: float | None = None,
        integrator: _IntegratorName | None = None,
        rtol: float | None = None,
        atol: float | None = None,
        dt: float | None = None,
        error_control: bool | None = None,
        linearly_implicit: bool | None = None,
        steps_to_outputs: bool | None = None,
        project_closures: bool | None = None,
        q0: ArrayLike | None = None,
        qdot0: ArrayLike | None = None,
        controller: _Controller | None = None,
        control_every: float | None = None,
    ) -> Trajectory: ...
    def step(
        self, state: State, dt: float, u: ArrayLike | None = None, *, substeps: int | None = None,
        joint_forces: ArrayLike | None = None, prescribed_targets: ArrayLike | None = None,
    ) -> State: ...
    def copy(self) -> Simulation: ...
    def __copy__(self) -> Simulation: ...
    def __deepcopy__(self, memo: object) -> Simulation: ...

@overload
def simulate_many(
    sims: list[Simulation], duration: float | None = None, *, threads: int | None = None,
    q0: None = None, qdot0: None = None, output_every: float | None = None,
    integrator: _IntegratorName | None = None, rtol: float | None = None,
    atol: float | None = None, dt: float | None = None,
) -> list[Trajectory]: ...
@overload
def simulate_many(
    sims: Simulation, duration: float | None = None, *, threads: int | None = None,
    q0: ArrayLike | None = None, qdot0: ArrayLike | None = None,
    output_every: float | None = None, integrator: _IntegratorName | None = None,
    rtol: float | None = None, atol: float | None = None, dt: float | None = None,
) -> list[Trajectory]: ...

@final
class BatchStepper:
    """Copies of cable-driven simulations stepped together on Rust threads
    (GIL released); row i of a step equals ``sims[i].step(...)`` bit for bit."""
    def __new__(cls, sims: list[Simulation], *, threads: int | None = None) -> BatchStepper: ...
    def __len__(self) -> int: ...
    @property
    def n_dof(self) -> int: ...
    @property
    def n_cables(self) -> int: ...
    @property
    def n_joint_inputs(self) -> int: ...
    @property
    def threads(self) -> int: ...
    def reset_contact(self, i: int | None = None) -> None:
        """Forget copy i's (None: every copy's) committed contact state."""
    @property
    def n_prescribed(self) -> int: ...
    @property
    def prescribed_targets(self) -> _F64:
        """(n, n_prescribed) targets in force, NaN rows on the scene's curves."""
    def reset_prescribed(self, i: int | None = None) -> None:
        """Put copy i's (None: every copy's) scene prescribed curves back."""
    def step(
        self, t: float | ArrayLike, q: ArrayLike, qdot: ArrayLike, u: ArrayLike, dt: float,
        active: Sequence[bool] | None = None, *, substeps: int | None = None,
        joint_forces: ArrayLike | None = None, prescribed_targets: ArrayLike | None = None,
    ) -> tuple[_F64, _F64, list[str | None]]:
        """(q (n, n_dof), qdot (n, n_dof), errors: None or the failure's message per copy)"""
