//! Inverse statics: cable tensions (and unknown point forces) for
//! targets (docs/theory-control.md IS1–IS13).
//!
//! The equilibrium `r(q, T) = τ_s(q) − B(q) T = 0` (IS1) defines `q(T)`
//! wherever its tangent stiffness `K_t = ∂r/∂q` is regular, with
//! `∂q/∂T = K_t⁻¹ B` (IS3, the implicit function theorem; `B = −∂ℓ/∂q` the
//! actuation matrix, D15); with loop closures the equilibrium carries the
//! closure forces `J_vᵀλ` and `∂q/∂T` comes from the bordered system
//! `[[K_t, −J_vᵀ], [J_e, 0]]` (IS8–IS10). The tensions minimize
//! `f(T) = ½ Σ_i w_i ‖e_i(q(T))‖² + ½ ε ‖T‖²` on the box `0 ≤ T ≤ T_max`
//! (IS2) by projected Gauss–Newton: each step solves the bounded QP of the
//! linearized residuals (IS4, [`super::qp`]), then re-solves the statics at
//! the trial tensions from the last equilibrium and backtracks until `f`
//! decreases enough (IS5).

use std::borrow::Cow;

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6xX, Rotation3, Vector3};
use softrod_dynamics::{
    DynamicsError, Forces, IdDerivatives, Model, StaticsOptions, actuation_matrix, body_jacobian,
    closure_statics, inverse_dynamics_derivatives_with, section_jacobian, statics_sensitivity,
};
use softrod_lie::{Mat3, Pose, Vec3};
use softrod_mechanics::{LoadFrame, PointLoad};

use crate::error::{Error, Result};

/// The default relative weight `ρ` of the effort term (IS2): the term is
/// `½ ε ‖T‖²` with `ε = ρ ‖∂e/∂T‖²_F` at the starting point, so it is
/// `ρ` of the best-controlled direction whatever the units and stiffness.
/// Small enough that a reachable target is missed by only about
/// `ρ σ_max² ‖T‖ / σ_min` (σ the singular values of `∂e/∂T`: 6e-9 m on the
/// shipped 3-cable example, whose stretch direction has σ_min = 3e-5 m/N);
/// large enough that the least-effort tensions among equally good ones
/// (redundant cables, antagonistic pairs) are found to ~1e-7 relative
/// despite the round-off of forming `JᵀJ`. Set it to 0 for a plain
/// least-squares fit when the tensions are determined.
pub const DEFAULT_EFFORT_WEIGHT: f64 = 1e-9;

/// What a rod section or a rigid body's frame should reach: a world
/// position, a world orientation, or both, with a weight.
#[derive(Clone, Debug, PartialEq)]
pub struct Target {
    /// The rod's index in [`Model::rods`] (not read when `body` is set).
    pub rod: usize,
    /// Arc length of the section \[m\], in `[0, L]` (not read when `body`
    /// is set).
    pub s: f64,
    /// A rigid body's index in [`Model::bodies`]: the target is then the
    /// body's frame (its origin and axes, the pose of
    /// [`softrod_dynamics::body_jacobian`]; IS11) instead of a rod section.
    pub body: Option<usize>,
    /// The frame's wanted world position \[m\], if any.
    pub position: Option<Vec3>,
    /// The frame's wanted orientation (maps the section's or body's frame
    /// to the world, like `Pose::rotation`), if any.
    pub rotation: Option<Mat3>,
    /// Weight `w` of the target's squared error (position in m, rotation
    /// angle in rad): `> 0`, finite.
    pub weight: f64,
}

impl Target {
    /// A position target of weight 1.
    pub fn position(rod: usize, s: f64, position: [f64; 3]) -> Self {
        Self {
            rod,
            s,
            body: None,
            position: Some(Vec3::from(position)),
            rotation: None,
            weight: 1.0,
        }
    }

    /// A position target of weight 1 for the frame origin of body `body`
    /// (index in [`Model::bodies`]).
    pub fn body_position(body: usize, position: [f64; 3]) -> Self {
        Self {
            rod: 0,
            s: 0.0,
            body: Some(body),
            position: Some(Vec3::from(position)),
            rotation: None,
            weight: 1.0,
        }
    }

    /// The same target with an orientation too.
    pub fn with_rotation(mut self, rotation: Mat3) -> Self {
        self.rotation = Some(rotation);
        self
    }

    /// The same target with weight `w`.
    pub fn with_weight(mut self, w: f64) -> Self {
        self.weight = w;
        self
    }
}

/// A point force whose value is an unknown of the inverse problem
/// (IS13): a dead force `f` \[N\] in world axes at the rod section
/// `(rod, s)`, each component within `min[k] ≤ f_k ≤ max[k]`. It acts in
/// addition to the model's own loads; its generalized force is `J_pᵀ f`
/// (`J_p` the section point's linear Jacobian), one column of the
/// actuation matrix per component.
#[derive(Clone, Debug, PartialEq)]
pub struct UnknownLoad {
    /// The rod's index in [`Model::rods`].
    pub rod: usize,
    /// Arc length of the point of application \[m\], in `[0, L]`.
    pub s: f64,
    /// Lower bounds of the world components \[N\]; `−∞` for none.
    pub min: [f64; 3],
    /// Upper bounds of the world components \[N\]; `+∞` for none.
    pub max: [f64; 3],
}

impl UnknownLoad {
    /// An unknown force at `(rod, s)` with `|f_k| ≤ max_force` for each
    /// world component (`f64::INFINITY` for no bound).
    pub fn new(rod: usize, s: f64, max_force: f64) -> Self {
        Self {
            rod,
            s,
            min: [-max_force; 3],
            max: [max_force; 3],
        }
    }
}

/// Settings of [`solve_actuation`].
#[derive(Clone, Debug)]
pub struct ActuationOptions {
    /// Upper bound of each cable's tension \[N\], model order; `+∞` for
    /// none. Empty: no upper bounds. The lower bound is 0 (a cable pulls).
    pub max_tension: Vec<f64>,
    /// Point forces solved for together with the tensions (IS13), in the
    /// order of [`Actuation::forces`]. Empty by default.
    pub unknown_loads: Vec<UnknownLoad>,
    /// Relative weight `ρ` of the effort term (IS2), `≥ 0`: `ε = ρ ‖∂e/∂T‖²_F`
    /// at the starting point; [`DEFAULT_EFFORT_WEIGHT`].
    pub effort_weight: f64,
    /// Converged when a full Gauss–Newton step changes no tension by more
    /// than `step_tolerance · (1 + max T)` \[relative\] (IS6).
    pub step_tolerance: f64,
    /// A target counts as reached when its weighted error `√w ‖e‖` is at
    /// most this \[m or rad\]; converged solutions with a larger error are
    /// the closest reachable shape, and say so.
    pub reach_tolerance: f64,
    /// Gauss–Newton iterations at most.
    pub max_iterations: usize,
    /// Warm start: tensions to start from (clipped to the bounds); default
    /// the tensions the model's cables have at `time` (clipped).
    pub initial_tensions: Option<Vec<f64>>,
    /// Warm start: the equilibrium at `initial_tensions` or near it; default
    /// the rest shape.
    pub initial_q: Option<Vec<f64>>,
    /// Warm start: the unknown loads' forces to start from \[N\, world\]
    /// (clipped to their bounds); default 0 (clipped).
    pub initial_forces: Option<Vec<[f64; 3]>>,
    /// Warm start: the actuated joints' forces to start from \[N or N·m\],
    /// one per actuated coordinate ([`Model::n_joint_inputs`], IS14;
    /// clipped to their bounds); default their actuators' forces at `time`
    /// (clipped).
    pub initial_joint_forces: Option<Vec<f64>>,
    /// Time of the prescribed joints (held at rest) \[s\].
    pub time: f64,
}

impl Default for ActuationOptions {
    fn default() -> Self {
        Self {
            max_tension: Vec::new(),
            unknown_loads: Vec::new(),
            effort_weight: DEFAULT_EFFORT_WEIGHT,
            step_tolerance: 1e-10,
            reach_tolerance: 1e-6,
            max_iterations: 100,
            initial_tensions: None,
            initial_q: None,
            initial_forces: None,
            initial_joint_forces: None,
            time: 0.0,
        }
    }
}

impl ActuationOptions {
    /// These options warm-started from a previous solution (a target that
    /// moved a little costs a few iterations).
    pub fn warm_start(mut self, previous: &Actuation) -> Self {
        self.initial_tensions = Some(previous.tensions.as_slice().to_vec());
        self.initial_q = Some(previous.q.as_slice().to_vec());
        self.initial_forces = Some(previous.forces.iter().map(|f| (*f).into()).collect());
        self.initial_joint_forces = Some(previous.joint_forces.clone());
        self
    }
}

/// Where a tension ended relative to its bounds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bound {
    /// Strictly inside.
    Free,
    /// At 0 (the cable would have to push to do better).
    Lower,
    /// At its `max_tension`.
    Upper,
}

impl Bound {
    /// `"free"`, `"lower"`, `"upper"`.
    pub fn name(self) -> &'static str {
        match self {
            Bound::Free => "free",
            Bound::Lower => "lower",
            Bound::Upper => "upper",
        }
    }
}

/// How far one target is from where the solution puts its section or body.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetResidual {
    /// The section's (body frame's) world position at the solution \[m\].
    pub position: Vec3,
    /// Its orientation (section or body frame to world).
    pub rotation: Mat3,
    /// `‖p − p*‖` \[m\] (0 without a position target).
    pub position_error: f64,
    /// Angle of `R R*ᵀ` \[rad\] (0 without an orientation target).
    pub rotation_error: f64,
}

/// The result of [`solve_actuation`].
#[derive(Clone, Debug)]
pub struct Actuation {
    /// Whether the iteration met its tolerance (IS6). When `false` the
    /// tensions and shape are the last iterate, not a solution.
    pub converged: bool,
    /// Whether every target is reached within `reach_tolerance`.
    pub reached: bool,
    /// Cable tensions \[N\], model order.
    pub tensions: DVector<f64>,
    /// The equilibrium at these tensions (n_dof).
    pub q: DVector<f64>,
    /// Gauss–Newton iterations.
    pub iterations: usize,
    /// Newton iterations of the statics solves, all together.
    pub statics_iterations: usize,
    /// One per target, in order.
    pub residuals: Vec<TargetResidual>,
    /// `f = ½ Σ w‖e‖² + ½ε‖T‖²` at the solution (IS2).
    pub cost: f64,
    /// The effort weight `ε` used \[(m or rad)²/N²\] (IS2).
    pub effort_weight: f64,
    /// `√(Σ w ‖e‖²)`: the weighted target error \[m, rad\].
    pub target_error: f64,
    /// Where each tension is relative to its bounds.
    pub bounds: Vec<Bound>,
    /// The unknown loads' forces \[N, world axes\], in the order of
    /// [`ActuationOptions::unknown_loads`] (IS13).
    pub forces: Vec<Vec3>,
    /// Where each of their components is relative to its bounds
    /// (`Lower` at `min`, `Upper` at `max`).
    pub force_bounds: Vec<[Bound; 3]>,
    /// The actuated joints' forces \[N or N·m\], one per actuated
    /// coordinate in the order of [`Model::n_joint_inputs`]
    /// ([`softrod_dynamics::ElementInfo::actuator_inputs`]; IS14).
    pub joint_forces: Vec<f64>,
    /// Where each is relative to its bounds `−max_force ≤ f ≤ max_force`
    /// (`Lower` at `−max_force`, `Upper` at `max_force`).
    pub joint_force_bounds: Vec<Bound>,
    /// One sentence: reached, closest reachable shape, or why not converged.
    pub message: String,
}

/// Cable tensions within `0 ≤ T ≤ max_tension` and the equilibrium they
/// hold that bring the sections and bodies of `targets` closest to them,
/// the least effort among equally close ones (IS1–IS12). Models with loop
/// closures are solved with their constrained equilibrium (IS8–IS10).
/// The point forces of `options.unknown_loads` are unknowns too, within
/// their bounds (IS13), and so are the forces of the joints that carry an
/// actuator, within `|f| ≤ max_force` (IS14). `data`'s cable and joint
/// force inputs are left as they were.
///
/// Refused (an input error naming the key): no targets, no cables, no
/// actuated joints and no unknown loads, an unknown load on a missing rod, off it or with NaN or
/// crossed bounds (`unknown_load[i].…`), a
/// target on a rod or body that does not exist or outside `[0, L]`, a
/// non-finite or non-orthonormal target, a weight not positive,
/// `max_tension` of the wrong length, negative or NaN. A statics failure
/// at the starting tensions is an error; later ones shorten the step. Not
/// converging within `max_iterations` is `converged: false` with the
/// residual, never an error.
pub fn solve_actuation(
    model: &Model,
    data: &mut softrod_dynamics::Data,
    targets: &[Target],
    options: &ActuationOptions,
) -> Result<Actuation> {
    validate(model, targets, options)?;
    let saved = data.cable_tensions().map(<[f64]>::to_vec);
    let saved_joints = data.joint_forces().map(<[f64]>::to_vec);
    let out = Solver::new(model, targets, options).run(data);
    data.set_cable_tensions(model, saved.as_deref())?;
    data.set_joint_forces(model, saved_joints.as_deref())?;
    out
}

fn bad(key: impl Into<String>, message: impl Into<String>) -> Error {
    Error::Actuation {
        key: key.into(),
        message: message.into(),
    }
}

fn validate(model: &Model, targets: &[Target], options: &ActuationOptions) -> Result<()> {
    let nc = model.n_cables();
    let nj = model.n_joint_inputs();
    if nc == 0 && nj == 0 && options.unknown_loads.is_empty() {
        return Err(bad(
            "cable",
            "the model has no cables, no actuated joints and no unknown loads to solve for",
        ));
    }
    if let Some(f) = &options.initial_joint_forces {
        if f.len() != nj {
            return Err(bad(
                "initial_joint_forces",
                format!(
                    "has {} entries, the model has {nj} actuated joint coordinates",
                    f.len()
                ),
            ));
        }
        if let Some(k) = f.iter().position(|v| !v.is_finite()) {
            return Err(bad(
                format!("initial_joint_forces[{k}]"),
                format!("must be finite, got {}", f[k]),
            ));
        }
    }
    if targets.is_empty() {
        return Err(bad("target", "no targets given"));
    }
    let rods = model.rods();
    for (i, t) in targets.iter().enumerate() {
        if let Some(b) = t.body {
            let count = model.bodies().len();
            if b >= count {
                return Err(bad(
                    format!("target[{i}].element"),
                    format!("no body {b} (the model has {count})"),
                ));
            }
        } else {
            let Some(r) = rods.get(t.rod) else {
                return Err(bad(
                    format!("target[{i}].element"),
                    format!("no rod {} (the model has {})", t.rod, rods.len()),
                ));
            };
            let len = r.spec.geometry.length();
            // The rod's length is a sum of piece lengths: its nominal length
            // may exceed it by round-off.
            if !(t.s.is_finite() && (0.0..=len * (1.0 + 1e-12)).contains(&t.s)) {
                return Err(bad(
                    format!("target[{i}].s"),
                    format!("must be in [0, {len}] (rod {:?}), got {}", r.spec.name, t.s),
                ));
            }
        }
        if t.position.is_none() && t.rotation.is_none() {
            return Err(bad(
                format!("target[{i}]"),
                "needs a position, a rotation or both",
            ));
        }
        if let Some(p) = &t.position
            && let Some(k) = p.iter().position(|v| !v.is_finite())
        {
            return Err(bad(
                format!("target[{i}].position[{k}]"),
                format!("must be finite, got {}", p[k]),
            ));
        }
        if let Some(rot) = &t.rotation {
            if rot.iter().any(|v| !v.is_finite()) {
                return Err(bad(format!("target[{i}].rotation"), "must be finite"));
            }
            let dev = (rot.transpose() * rot - Matrix3::identity()).amax();
            if dev > 1e-6 || rot.determinant() <= 0.0 {
                return Err(bad(
                    format!("target[{i}].rotation"),
                    format!(
                        "must be a rotation matrix (RᵀR = I to 1e-6, det R = 1); RᵀR − I is off by {dev:.1e}"
                    ),
                ));
            }
        }
        if !(t.weight.is_finite() && t.weight > 0.0) {
            return Err(bad(
                format!("target[{i}].weight"),
                format!("must be positive and finite, got {}", t.weight),
            ));
        }
    }
    if !options.max_tension.is_empty() && options.max_tension.len() != nc {
        return Err(bad(
            "max_tension",
            format!(
                "has {} entries, the model has {nc} cables",
                options.max_tension.len()
            ),
        ));
    }
    for (c, m) in options.max_tension.iter().enumerate() {
        if m.is_nan() || *m < 0.0 {
            return Err(bad(
                format!("cable[{c}].max_tension"),
                format!("must be ≥ 0, got {m}"),
            ));
        }
    }
    if !(options.effort_weight.is_finite() && options.effort_weight >= 0.0) {
        return Err(bad(
            "effort_weight",
            format!("must be ≥ 0 and finite, got {}", options.effort_weight),
        ));
    }
    for (key, v) in [
        ("step_tolerance", options.step_tolerance),
        ("reach_tolerance", options.reach_tolerance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(bad(key, format!("must be positive and finite, got {v}")));
        }
    }
    if let Some(t) = &options.initial_tensions {
        if t.len() != nc {
            return Err(bad(
                "initial_tensions",
                format!("has {} entries, the model has {nc} cables", t.len()),
            ));
        }
        if let Some(k) = t.iter().position(|v| !v.is_finite()) {
            return Err(bad(
                format!("initial_tensions[{k}]"),
                format!("must be finite, got {}", t[k]),
            ));
        }
    }
    for (i, u) in options.unknown_loads.iter().enumerate() {
        let Some(r) = rods.get(u.rod) else {
            return Err(bad(
                format!("unknown_load[{i}].rod"),
                format!("no rod {} (the model has {})", u.rod, rods.len()),
            ));
        };
        let len = r.spec.geometry.length();
        if !(u.s.is_finite() && (0.0..=len * (1.0 + 1e-12)).contains(&u.s)) {
            return Err(bad(
                format!("unknown_load[{i}].s"),
                format!("must be in [0, {len}] (rod {:?}), got {}", r.spec.name, u.s),
            ));
        }
        for k in 0..3 {
            let (lo, hi) = (u.min[k], u.max[k]);
            if lo.is_nan() || lo == f64::INFINITY {
                return Err(bad(
                    format!("unknown_load[{i}].min[{k}]"),
                    format!("must be a number below +∞, got {lo}"),
                ));
            }
            if hi.is_nan() || hi == f64::NEG_INFINITY {
                return Err(bad(
                    format!("unknown_load[{i}].max[{k}]"),
                    format!("must be a number above −∞, got {hi}"),
                ));
            }
            if lo > hi {
                return Err(bad(
                    format!("unknown_load[{i}].max[{k}]"),
                    format!("must be ≥ min ({lo}), got {hi}"),
                ));
            }
        }
    }
    if let Some(f) = &options.initial_forces {
        if f.len() != options.unknown_loads.len() {
            return Err(bad(
                "initial_forces",
                format!(
                    "has {} entries, there are {} unknown loads",
                    f.len(),
                    options.unknown_loads.len()
                ),
            ));
        }
        for (i, v) in f.iter().enumerate() {
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(bad(
                    format!("initial_forces[{i}][{k}]"),
                    format!("must be finite, got {}", v[k]),
                ));
            }
        }
    }
    if let Some(q) = &options.initial_q {
        if q.len() != model.n_dof() {
            return Err(bad(
                "initial_q",
                format!(
                    "has {} entries, the model has {} DoF",
                    q.len(),
                    model.n_dof()
                ),
            ));
        }
        if let Some(k) = q.iter().position(|v| !v.is_finite()) {
            return Err(bad(
                format!("initial_q[{k}]"),
                format!("must be finite, got {}", q[k]),
            ));
        }
    }
    Ok(())
}

/// An equilibrium and what the step needs of it.
struct Point {
    /// The unknowns `x = (T, f_1, …, u)`: tensions, then the unknown
    /// loads' world force components (IS13), then the actuated joints'
    /// forces (IS14).
    t: DVector<f64>,
    q: DVector<f64>,
    /// The closure multipliers at `q` (empty on an open model; IS8).
    lambda: DVector<f64>,
    /// Weighted residuals `√w e` (IS2), stacked.
    e: DVector<f64>,
    cost: f64,
}

/// `(∂e/∂x, ∂q/∂x)` at an equilibrium (IS3, IS13).
type Sensitivity = (DMatrix<f64>, DMatrix<f64>);

struct Solver<'a> {
    /// The caller's model, without the unknown loads.
    base: &'a Model,
    /// What the statics see: `base` with the unknown loads appended at
    /// the forces of the last [`Solver::set_loads`] (IS13); `base` itself
    /// without unknown loads.
    model: Cow<'a, Model>,
    targets: &'a [Target],
    options: &'a ActuationOptions,
    /// Number of cables: the first `nc` unknowns are tensions.
    nc: usize,
    /// Where the joint forces start among the unknowns (`nc + 3 n_u`).
    nj0: usize,
    lo: Vec<f64>,
    hi: Vec<f64>,
    work: IdDerivatives,
    zero: Vec<f64>,
    statics_iterations: usize,
    /// `ε` of IS2, fixed at the first step.
    eps: f64,
}

impl<'a> Solver<'a> {
    fn new(model: &'a Model, targets: &'a [Target], options: &'a ActuationOptions) -> Self {
        let nc = model.n_cables();
        let mut hi = if options.max_tension.is_empty() {
            vec![f64::INFINITY; nc]
        } else {
            options.max_tension.clone()
        };
        let mut lo = vec![0.0; nc];
        for u in &options.unknown_loads {
            lo.extend_from_slice(&u.min);
            hi.extend_from_slice(&u.max);
        }
        let nj0 = lo.len();
        for e in model.elements() {
            if let Some(a) = &e.attachment.joint.actuator {
                for i in 0..e.actuator_inputs.len() {
                    lo.push(-a.bound(i));
                    hi.push(a.bound(i));
                }
            }
        }
        Self {
            base: model,
            model: Cow::Borrowed(model),
            targets,
            options,
            nc,
            nj0,
            lo,
            hi,
            work: IdDerivatives::new(model),
            zero: vec![0.0; model.n_dof()],
            statics_iterations: 0,
            eps: 0.0,
        }
    }

    /// The unknown loads at the forces of `x` (IS13): the caller's model
    /// with one dead point load per unknown load appended to its rod.
    /// Rebuilding the rods (their load placement) is cheap next to a
    /// statics solve; `Data` does not depend on the loads.
    fn set_loads(&mut self, x: &DVector<f64>) -> std::result::Result<(), DynamicsError> {
        let loads = &self.options.unknown_loads;
        if loads.is_empty() {
            return Ok(());
        }
        let mut m = self.base.clone();
        let mut rods: Vec<usize> = loads.iter().map(|u| u.rod).collect();
        rods.sort_unstable();
        rods.dedup();
        for rod in rods {
            let on_rod = loads
                .iter()
                .enumerate()
                .filter(|(_, u)| u.rod == rod)
                .map(|(i, u)| PointLoad {
                    s: u.s.min(self.base.rods()[rod].spec.geometry.length()),
                    force: Vec3::new(
                        x[self.nc + 3 * i],
                        x[self.nc + 3 * i + 1],
                        x[self.nc + 3 * i + 2],
                    ),
                    moment: Vec3::zeros(),
                    frame: LoadFrame::World,
                })
                .collect();
            m = m.with_point_loads(rod, on_rod)?;
        }
        self.model = Cow::Owned(m);
        Ok(())
    }

    /// Sets `data`'s cable tensions and joint forces to those of `x`.
    fn set_tensions(
        &self,
        data: &mut softrod_dynamics::Data,
        x: &DVector<f64>,
    ) -> std::result::Result<(), DynamicsError> {
        if self.nj0 < x.len() {
            data.set_joint_forces(&self.model, Some(&x.as_slice()[self.nj0..]))?;
        }
        data.set_cable_tensions(&self.model, Some(&x.as_slice()[..self.nc]))
    }

    /// The actuation matrix of all unknowns at `q` (n_dof × (n_c + 3 n_u +
    /// n_j)): `B` (D15), then per unknown load the generalized forces
    /// `J_pᵀ e_k` of unit world forces at its point, `J_p = J_v − [p]× J_ω`
    /// the point's linear velocity rows (IS13), then per actuated joint
    /// coordinate the unit column of that coordinate (IS14).
    fn actuation(
        &self,
        data: &mut softrod_dynamics::Data,
        q: &[f64],
    ) -> std::result::Result<DMatrix<f64>, DynamicsError> {
        let b = actuation_matrix(&self.model, q)?;
        let loads = &self.options.unknown_loads;
        let nx = self.lo.len();
        if nx == self.nc {
            return Ok(b);
        }
        let n = self.model.n_dof();
        let mut g = DMatrix::zeros(n, nx);
        for e in self.model.elements() {
            for (i, o) in e
                .joint_dofs
                .clone()
                .enumerate()
                .take(e.actuator_inputs.len())
            {
                g[(o, self.nj0 + e.actuator_inputs.start + i)] = 1.0;
            }
        }
        g.columns_mut(0, self.nc).copy_from(&b);
        self.model.set_time(data, self.options.time);
        for (i, u) in loads.iter().enumerate() {
            let s = u.s.min(self.model.rods()[u.rod].spec.geometry.length());
            let (pose, js) = section_jacobian(&self.model, data, q, u.rod, s)?;
            let jp = js.fixed_rows::<3>(3) - skew(&pose.translation) * js.fixed_rows::<3>(0);
            g.columns_mut(self.nc + 3 * i, 3).copy_from(&jp.transpose());
        }
        Ok(g)
    }

    fn clamp(&self, t: &mut DVector<f64>) {
        for (i, v) in t.iter_mut().enumerate() {
            *v = v.clamp(self.lo[i], self.hi[i]);
        }
    }

    /// The equilibrium at tensions `t` from `q0` (IS1) and its residuals.
    fn point(
        &mut self,
        data: &mut softrod_dynamics::Data,
        t: DVector<f64>,
        q0: &[f64],
    ) -> std::result::Result<Point, DynamicsError> {
        self.set_loads(&t)?;
        self.set_tensions(data, &t)?;
        let opts = StaticsOptions {
            time: self.options.time,
            ..StaticsOptions::default()
        };
        // `statics` itself on an open model; the constrained Newton of
        // D69, with its multipliers, on a closed one (IS8).
        let (r, lambda) = closure_statics(&self.model, data, q0, &opts)?;
        self.statics_iterations += r.iterations;
        let e = self.residuals(data, r.q.as_slice(), None)?;
        let cost = 0.5 * e.norm_squared() + 0.5 * self.eps * t.norm_squared();
        Ok(Point {
            t,
            q: r.q,
            lambda,
            e,
            cost,
        })
    }

    /// The stacked weighted residuals at `q` (IS2) and, with `jac`, their
    /// Jacobian with respect to `q` (rows as the residuals, n_dof columns).
    fn residuals(
        &self,
        data: &mut softrod_dynamics::Data,
        q: &[f64],
        mut jac: Option<&mut DMatrix<f64>>,
    ) -> std::result::Result<DVector<f64>, DynamicsError> {
        let rows = self.rows();
        let mut e = DVector::zeros(rows);
        if let Some(j) = jac.as_deref_mut() {
            *j = DMatrix::zeros(rows, self.model.n_dof());
        }
        self.model.set_time(data, self.options.time);
        let mut row = 0;
        for tg in self.targets {
            let (g, js) = self.frame(data, q, tg)?;
            let sw = tg.weight.sqrt();
            if let Some(p) = &tg.position {
                let d = g.translation - p;
                e.fixed_rows_mut::<3>(row).copy_from(&(d * sw));
                if let Some(j) = jac.as_deref_mut() {
                    // The world point's velocity: v_o + ω × p = J_v − [p]× J_ω
                    // (spatial twist, D11).
                    let px = skew(&g.translation);
                    let jw = js.fixed_rows::<3>(0);
                    let jv = js.fixed_rows::<3>(3);
                    let jp = (jv - px * jw) * sw;
                    j.rows_mut(row, 3).copy_from(&jp);
                }
                row += 3;
            }
            if let Some(rs) = &tg.rotation {
                let err = rotation_vector(&(g.rotation * rs.transpose()));
                e.fixed_rows_mut::<3>(row).copy_from(&(err * sw));
                if let Some(j) = jac.as_deref_mut() {
                    // d log(R R*ᵀ) ≈ ω (world), exact at zero error (IS2).
                    j.rows_mut(row, 3).copy_from(&(js.fixed_rows::<3>(0) * sw));
                }
                row += 3;
            }
        }
        Ok(e)
    }

    /// The world pose and spatial Jacobian (D11) of the target's section
    /// or body frame (IS11).
    fn frame(
        &self,
        data: &mut softrod_dynamics::Data,
        q: &[f64],
        tg: &Target,
    ) -> std::result::Result<(Pose, Matrix6xX<f64>), DynamicsError> {
        match tg.body {
            Some(b) => body_jacobian(&self.model, data, q, b),
            None => section_jacobian(&self.model, data, q, tg.rod, self.abscissa(tg)),
        }
    }

    /// The target's `s` inside the rod (a nominal tip `s = L` may exceed
    /// the summed piece lengths by round-off).
    fn abscissa(&self, tg: &Target) -> f64 {
        tg.s.min(self.model.rods()[tg.rod].spec.geometry.length())
    }

    fn rows(&self) -> usize {
        self.targets
            .iter()
            .map(|t| 3 * usize::from(t.position.is_some()) + 3 * usize::from(t.rotation.is_some()))
            .sum()
    }

    /// `∂e/∂T = (∂e/∂q) K_t⁻¹ B` at the equilibrium `p` (IS3), with the
    /// unknown loads' columns (IS13); with closures `∂q/∂T` from the
    /// bordered system (IS9).
    fn sensitivity(
        &mut self,
        data: &mut softrod_dynamics::Data,
        p: &Point,
    ) -> std::result::Result<Option<Sensitivity>, DynamicsError> {
        // The last statics may have been a rejected trial point: the
        // tangent is the one at `p`'s loads.
        self.set_loads(&p.t)?;
        if self.model.has_closures() {
            let b = self.actuation(data, p.q.as_slice())?;
            self.set_tensions(data, &p.t)?;
            let Some(sens) = statics_sensitivity(
                &self.model,
                data,
                self.options.time,
                p.q.as_slice(),
                p.lambda.as_slice(),
                &b,
            )?
            else {
                return Ok(None);
            };
            let mut jq = DMatrix::zeros(0, 0);
            self.residuals(data, p.q.as_slice(), Some(&mut jq))?;
            let j = jq * &sens.dq;
            return Ok(j.iter().all(|v| v.is_finite()).then_some((j, sens.dq)));
        }
        let b = self.actuation(data, p.q.as_slice())?;
        let w = &mut self.work;
        w.tensions = Some(p.t.rows(0, self.nc).into_owned());
        w.joint_inputs =
            (self.nj0 < p.t.len()).then(|| p.t.rows(self.nj0, p.t.len() - self.nj0).into_owned());
        inverse_dynamics_derivatives_with(
            &self.model,
            w,
            Forces::at_rest(1.0),
            self.options.time,
            p.q.as_slice(),
            &self.zero,
            &self.zero,
        )?;
        let Some(dq_dt) = w.dtau_dq.clone().lu().solve(&b) else {
            return Ok(None);
        };
        let mut jq = DMatrix::zeros(0, 0);
        self.residuals(data, p.q.as_slice(), Some(&mut jq))?;
        let j = jq * &dq_dt;
        Ok(j.iter().all(|v| v.is_finite()).then_some((j, dq_dt)))
    }

    fn run(mut self, data: &mut softrod_dynamics::Data) -> Result<Actuation> {
        let tensions = match &self.options.initial_tensions {
            Some(t) => DVector::from_column_slice(t),
            None => DVector::from_iterator(
                self.nc,
                self.model.rods().iter().flat_map(|r| {
                    r.spec
                        .cables
                        .iter()
                        .map(|c| c.tension_at(self.options.time))
                }),
            ),
        };
        let nu = self.options.unknown_loads.len();
        let forces = self
            .options
            .initial_forces
            .clone()
            .unwrap_or_else(|| vec![[0.0; 3]; nu]);
        let nx = self.lo.len();
        let joints: Vec<f64> = match &self.options.initial_joint_forces {
            Some(f) => f.clone(),
            None => self
                .model
                .elements()
                .iter()
                .filter_map(|e| e.attachment.joint.actuator.as_ref().map(|a| (e, a)))
                .flat_map(|(e, a)| {
                    (0..e.actuator_inputs.len()).map(|i| a.force.at(i, self.options.time))
                })
                .collect(),
        };
        let mut t0 = DVector::from_iterator(
            nx,
            tensions
                .iter()
                .copied()
                .chain(forces.iter().flatten().copied())
                .chain(joints),
        );
        self.clamp(&mut t0);
        let q0 = self
            .options
            .initial_q
            .clone()
            .unwrap_or_else(|| vec![0.0; self.model.n_dof()]);
        let mut p = self.point(data, t0, &q0)?;
        let mut iterations = 0;
        let mut converged = false;
        let mut why = String::new();
        while iterations < self.options.max_iterations {
            iterations += 1;
            let Some((j, dq_dt)) = self.sensitivity(data, &p)? else {
                why = "the tangent stiffness is singular at the equilibrium (a buckling or limit point)".into();
                break;
            };
            if iterations == 1 {
                self.eps = self.options.effort_weight * j.norm_squared();
                p.cost = 0.5 * p.e.norm_squared() + 0.5 * self.eps * p.t.norm_squared();
            }
            let eps = self.eps;
            // The QP of the linearized problem in the step d (IS4):
            // ½‖e + J d‖² + ½ε‖T + d‖² on lo − T ≤ d ≤ hi − T.
            let mut h = j.transpose() * &j;
            for i in 0..nx {
                h[(i, i)] += eps;
            }
            let g = j.transpose() * &p.e + &p.t * eps;
            let lo: Vec<f64> = (0..nx).map(|i| self.lo[i] - p.t[i]).collect();
            let hi: Vec<f64> = (0..nx).map(|i| self.hi[i] - p.t[i]).collect();
            // A singular H (a cable that moves no target, ε = 0) has many
            // minimizers; a whisker of the effort term picks the smallest
            // step among them without moving a determined one measurably.
            let tiny = 1e-14 * h.diagonal().amax().max(f64::MIN_POSITIVE);
            for i in 0..nx {
                h[(i, i)] += tiny;
            }
            let d = match super::qp::bounded_qp(&h, &g, &lo, &hi) {
                Ok(d) => d,
                Err(e) => {
                    why = e;
                    break;
                }
            };
            let tmax = p.t.amax();
            if d.amax() <= self.options.step_tolerance * (1.0 + tmax) {
                converged = true;
                break;
            }
            // Backtracking on f with the statics re-solved (IS5).
            let slope = g.dot(&d);
            let mut alpha = 1.0;
            let mut accepted = None;
            while alpha >= 1e-6 {
                let mut t = &p.t + &d * alpha;
                self.clamp(&mut t);
                // The tangent predictor q + (∂q/∂T) ΔT (IS3) leaves the
                // statics a second-order error to remove.
                let guess = &p.q + &dq_dt * (&t - &p.t);
                let start = if guess.iter().all(|v| v.is_finite()) {
                    guess
                } else {
                    p.q.clone()
                };
                match self.point(data, t, start.as_slice()) {
                    Ok(trial) if trial.cost <= p.cost + 1e-4 * alpha * slope => {
                        accepted = Some(trial);
                        break;
                    }
                    Ok(_) | Err(DynamicsError::StaticsFailed { .. }) => alpha *= 0.5,
                    Err(e) => return Err(e.into()),
                }
            }
            let Some(next) = accepted else {
                // No decrease along a descent direction: f is flat to
                // round-off there, which is the optimum when the predicted
                // decrease is itself at round-off.
                if -slope <= 1e-12 * p.cost.max(f64::MIN_POSITIVE) + f64::MIN_POSITIVE {
                    converged = true;
                } else {
                    why = format!(
                        "the line search found no decrease (predicted {:.3e})",
                        -slope
                    );
                }
                break;
            };
            let small = (&next.t - &p.t).amax() <= self.options.step_tolerance * (1.0 + tmax);
            p = next;
            if small {
                converged = true;
                break;
            }
        }
        if !converged && why.is_empty() {
            why = format!(
                "{} iterations without meeting the step tolerance",
                iterations
            );
        }
        self.finish(data, p, iterations, converged, why)
    }

    fn finish(
        &self,
        data: &mut softrod_dynamics::Data,
        p: Point,
        iterations: usize,
        converged: bool,
        why: String,
    ) -> Result<Actuation> {
        self.model.set_time(data, self.options.time);
        let mut residuals = Vec::with_capacity(self.targets.len());
        let mut reached = true;
        for tg in self.targets {
            let (g, _) = self.frame(data, p.q.as_slice(), tg)?;
            let position_error = tg.position.map_or(0.0, |x| (g.translation - x).norm());
            let rotation_error = tg.rotation.map_or(0.0, |r| {
                rotation_vector(&(g.rotation * r.transpose())).norm()
            });
            let sw = tg.weight.sqrt();
            if sw * position_error.max(rotation_error) > self.options.reach_tolerance {
                reached = false;
            }
            residuals.push(TargetResidual {
                position: g.translation,
                rotation: g.rotation,
                position_error,
                rotation_error,
            });
        }
        // A tension within 1e-9 of its range of a bound is at it (the
        // polished QP step puts it there exactly).
        let mut bounds = (0..p.t.len())
            .map(|i| {
                let range = [self.lo[i], self.hi[i], p.t[i]]
                    .iter()
                    .filter(|v| v.is_finite())
                    .fold(0.0f64, |m, v| m.max(v.abs()));
                let tol = 1e-9 * (1.0 + range);
                if p.t[i] - self.lo[i] <= tol {
                    Bound::Lower
                } else if self.hi[i] - p.t[i] <= tol {
                    Bound::Upper
                } else {
                    Bound::Free
                }
            })
            .collect::<Vec<_>>();
        let joint_force_bounds = bounds.split_off(self.nj0);
        let joint_forces = p.t.as_slice()[self.nj0..].to_vec();
        let force_bounds: Vec<[Bound; 3]> = bounds[self.nc..]
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        bounds.truncate(self.nc);
        let forces: Vec<Vec3> = p.t.as_slice()[self.nc..self.nj0]
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        let target_error = p.e.norm();
        let message = if !converged {
            format!(
                "not converged: {why}; weighted target error {target_error:.3e} at the last iterate"
            )
        } else if reached {
            format!(
                "every target reached (weighted error {target_error:.3e} ≤ reach_tolerance {:e})",
                self.options.reach_tolerance
            )
        } else {
            let mut held: Vec<String> = bounds
                .iter()
                .enumerate()
                .filter(|(_, b)| **b != Bound::Free)
                .map(|(i, b)| format!("cable {i} at its {} bound", b.name()))
                .collect();
            for (i, fb) in force_bounds.iter().enumerate() {
                for (k, b) in fb.iter().enumerate() {
                    if *b != Bound::Free {
                        held.push(format!(
                            "unknown load {i} component {k} at its {} bound",
                            b.name()
                        ));
                    }
                }
            }
            for e in self.model.elements() {
                for (i, c) in e.actuator_inputs.clone().enumerate() {
                    let b = joint_force_bounds[c];
                    if b != Bound::Free {
                        held.push(format!(
                            "the joint of {:?} coordinate {i} at its {} bound",
                            e.name,
                            b.name()
                        ));
                    }
                }
            }
            format!(
                "target not reachable: the closest reachable shape has weighted error {target_error:.3e}{}",
                if held.is_empty() {
                    String::new()
                } else {
                    format!(" ({})", held.join(", "))
                }
            )
        };
        let tensions = p.t.rows(0, self.nc).into_owned();
        Ok(Actuation {
            converged,
            reached: converged && reached,
            tensions,
            q: p.q,
            iterations,
            statics_iterations: self.statics_iterations,
            residuals,
            cost: p.cost,
            effort_weight: self.eps,
            target_error,
            bounds,
            forces,
            force_bounds,
            joint_forces,
            joint_force_bounds,
            message,
        })
    }
}

fn skew(p: &Vec3) -> Mat3 {
    Mat3::new(0.0, -p.z, p.y, p.z, 0.0, -p.x, -p.y, p.x, 0.0)
}

/// The rotation vector `θ a` of the rotation matrix `r` (its so(3)
/// logarithm, rad, in the axes `r` is written in): `sin θ · a` is
/// `vee(r − rᵀ)/2` and `θ = atan2(sin θ, (tr r − 1)/2)`, which resolves
/// small angles to round-off — `acos((tr r − 1)/2)` cannot: `cos θ`
/// rounds to 1 below θ ≈ 1e-8 rad, so an error of 1e-8 rad read 0. Past
/// a quarter turn, where `sin θ` no longer carries the axis well,
/// nalgebra's own logarithm.
fn rotation_vector(r: &Matrix3<f64>) -> Vector3<f64> {
    let v = 0.5
        * Vector3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let c = 0.5 * (r.trace() - 1.0);
    if c <= 0.0 {
        return Rotation3::from_matrix_unchecked(*r).scaled_axis();
    }
    let sin = v.norm();
    if sin == 0.0 {
        return Vector3::zeros();
    }
    v * (sin.atan2(c) / sin)
}

#[cfg(test)]
mod rotation_vector_tests {
    use super::rotation_vector;
    use nalgebra::{Rotation3, Unit, Vector3};

    /// Built from a known axis and angle, the rotation gives them back:
    /// to round-off relative at small angles (where `acos` of the trace
    /// reads 0 or ~1.5e-8), and across the whole range.
    #[test]
    fn gives_back_the_axis_and_angle_it_was_built_from() {
        let axis = Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8));
        for angle in [1e-14, 1e-10, 1e-8, 3e-8, 1e-4, 0.3, 1.5, 1.6, 2.5, 3.1] {
            let r = Rotation3::from_axis_angle(&axis, angle);
            let v = rotation_vector(r.matrix());
            let want = axis.into_inner() * angle;
            let err = (v - want).norm() / angle;
            assert!(err < 1e-12, "angle {angle:e}: {v:?} vs {want:?} ({err:e})");
        }
        assert_eq!(
            rotation_vector(&nalgebra::Matrix3::identity()),
            Vector3::zeros()
        );
    }
}
