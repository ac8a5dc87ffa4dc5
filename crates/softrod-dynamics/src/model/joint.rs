//! Joints, rigid bodies and attachments: the parts of a robot that are not
//! rods (docs/theory.md §11, D50–D55).
//!
//! A joint between an attachment frame and a child element (rod or body) is
//! a chain of massless *virtual pieces* of unit length whose strain bases
//! are the joint's motion subspace (D50): revolute `[a; 0]`, prismatic
//! `[0; a]`, spherical `[I; 0]` (the rotation vector: `exp` of the strain is
//! `(exp(r̂), 0)`), universal two revolute pieces, free a translation piece
//! `[0; I]` followed by a spherical one, so `g = (exp(r̂), p)`. The PCS maps
//! (`exp`, `T₋`, its rate) of a unit piece then give the joint's pose,
//! motion subspace `T₋(1)B` and velocity-product acceleration exactly.

use crate::error::DynamicsError;
use crate::model::prescribed::Prescribed;
use nalgebra::Matrix6xX;
use softrod_lie::{Mat3, Mat6, Pose, Vec3, Wrench, join, skew};
use softrod_mechanics::LoadFrame;

/// The kind of a joint and its axes (unit vectors in the child element's
/// frame at joint value 0; normalized by [`Joint::validate`]).
#[derive(Clone, Debug, PartialEq)]
pub enum JointKind {
    /// No relative motion (0 DoF): the element is clamped to its parent.
    Fixed,
    /// Rotation by an angle \[rad\] about `axis` (1 DoF).
    Revolute {
        /// Rotation axis.
        axis: Vec3,
    },
    /// Translation by a displacement \[m\] along `axis` (1 DoF).
    Prismatic {
        /// Translation axis.
        axis: Vec3,
    },
    /// Rotation about `axes[0]` then about `axes[1]` (2 DoF, angles \[rad\]);
    /// the second axis is in the frame turned by the first rotation (Cardan).
    Universal {
        /// The two axes, first then second.
        axes: [Vec3; 2],
    },
    /// Any rotation (3 DoF): the rotation vector `r` \[rad\], `R = exp(r̂)`.
    Spherical,
    /// Any rigid motion (6 DoF): `(r, p)`, rotation vector \[rad\] then
    /// translation \[m\] in the attachment frame, `g = (exp(r̂), p)`: a
    /// floating base.
    Free,
}

impl JointKind {
    /// Number of coordinates.
    pub fn dof(&self) -> usize {
        match self {
            JointKind::Fixed => 0,
            JointKind::Revolute { .. } | JointKind::Prismatic { .. } => 1,
            JointKind::Universal { .. } => 2,
            JointKind::Spherical => 3,
            JointKind::Free => 6,
        }
    }

    /// The scene-file name (`"fixed"`, `"revolute"`, …).
    pub fn name(&self) -> &'static str {
        match self {
            JointKind::Fixed => "fixed",
            JointKind::Revolute { .. } => "revolute",
            JointKind::Prismatic { .. } => "prismatic",
            JointKind::Universal { .. } => "universal",
            JointKind::Spherical => "spherical",
            JointKind::Free => "free",
        }
    }

    /// The virtual pieces base to tip (D50): each strain basis (6×k) and the
    /// index of its first coordinate among the joint's.
    pub(crate) fn segments(&self) -> Vec<(Matrix6xX<f64>, usize)> {
        let col = |ang: &Vec3, lin: &Vec3| Matrix6xX::from_column_slice(join(ang, lin).as_slice());
        let z = Vec3::zeros();
        let block = |angular: bool| {
            let mut m = Matrix6xX::zeros(3);
            for i in 0..3 {
                m[(if angular { i } else { i + 3 }, i)] = 1.0;
            }
            m
        };
        match self {
            JointKind::Fixed => vec![],
            JointKind::Revolute { axis } => vec![(col(axis, &z), 0)],
            JointKind::Prismatic { axis } => vec![(col(&z, axis), 0)],
            JointKind::Universal { axes } => vec![(col(&axes[0], &z), 0), (col(&axes[1], &z), 1)],
            JointKind::Spherical => vec![(block(true), 0)],
            // Translation first (coordinates 3..6), then the rotation (0..3):
            // g = (I, p)(exp r̂, 0) = (exp r̂, p).
            JointKind::Free => vec![(block(false), 3), (block(true), 0)],
        }
    }
}

/// A joint with optional per-coordinate stiffness \[N/m or N·m/rad\],
/// damping \[N·s/m or N·m·s/rad\] and rest value (where the spring force is
/// zero): generalized force `−k_i (q_i − rest_i) − d_i q̇_i` (D53). Empty
/// vectors mean zero.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Kind and axes.
    pub kind: JointKind,
    /// Stiffness per coordinate (empty or `dof` values, ≥ 0).
    pub stiffness: Vec<f64>,
    /// Damping per coordinate (empty or `dof` values, ≥ 0).
    pub damping: Vec<f64>,
    /// Rest value per coordinate (empty or `dof` values).
    pub rest: Vec<f64>,
    /// The joint's coordinates as given functions of time (D59): then they
    /// are not generalized coordinates, the joint has no spring, damper or
    /// rest value, and the force it needs is an output.
    pub prescribed: Option<Prescribed>,
    /// A force source at the joint's coordinates (docs/theory-control.md
    /// IS14): a generalized force per coordinate, an input of the model.
    pub actuator: Option<JointActuator>,
}

/// The generalized force of a joint actuator per coordinate as a function
/// of time \[N for a translation, N·m for a rotation coordinate\]
/// (docs/theory-control.md IS14).
#[derive(Clone, Debug, PartialEq)]
pub enum JointForce {
    /// One constant value per coordinate.
    Constant(Vec<f64>),
    /// Piecewise linear in time through `(times[i], values[i])` [s; one
    /// value per coordinate], times strictly increasing; held at the first
    /// and last rows outside.
    Table {
        /// Times \[s\], strictly increasing.
        times: Vec<f64>,
        /// One row per time, one value per coordinate.
        values: Vec<Vec<f64>>,
    },
}

impl JointForce {
    /// The force of coordinate `i` at time `t`: the constant, or linear
    /// interpolation in the table (held outside it). No allocation.
    #[inline]
    pub fn at(&self, i: usize, t: f64) -> f64 {
        match self {
            JointForce::Constant(v) => v[i],
            JointForce::Table { times, values } => {
                let last = times.len() - 1;
                if t <= times[0] {
                    return values[0][i];
                }
                if t >= times[last] {
                    return values[last][i];
                }
                // First time above t: the segment [k − 1, k] holds it.
                let k = times.partition_point(|&x| x <= t);
                let (t0, t1) = (times[k - 1], times[k]);
                let w = (t - t0) / (t1 - t0);
                values[k - 1][i] + w * (values[k][i] - values[k - 1][i])
            }
        }
    }

    /// The times where the force has a kink (a table's times) \[s\].
    pub fn breakpoints(&self) -> &[f64] {
        match self {
            JointForce::Constant(_) => &[],
            JointForce::Table { times, .. } => times,
        }
    }
}

/// A joint actuator (docs/theory-control.md IS14): the generalized force
/// `f(t)` it applies at each coordinate of its joint (adding `+f` to the
/// joint's generalized forces, like a spring's `−k(q − rest)`), and the
/// bound `|f_i| ≤ max_force[i]` an inverse statics solve keeps it within.
#[derive(Clone, Debug, PartialEq)]
pub struct JointActuator {
    /// The force over time (one value per coordinate).
    pub force: JointForce,
    /// Bound of each coordinate's force \[N or N·m\], `≥ 0` (`+∞`: none);
    /// empty: no bound.
    pub max_force: Vec<f64>,
}

impl JointActuator {
    /// A constant force per coordinate, no bound.
    pub fn constant(force: &[f64]) -> Self {
        Self {
            force: JointForce::Constant(force.to_vec()),
            max_force: Vec::new(),
        }
    }

    /// The same actuator with the bound `|f_i| ≤ max_force[i]`.
    pub fn with_max_force(mut self, max_force: &[f64]) -> Self {
        self.max_force = max_force.to_vec();
        self
    }

    /// The bound of coordinate `i` (`+∞` when none is given).
    pub fn bound(&self, i: usize) -> f64 {
        self.max_force.get(i).copied().unwrap_or(f64::INFINITY)
    }

    /// Checks the shapes and values for a joint of `k` coordinates; the
    /// message names the key under `actuator` (`force`, `force.times`,
    /// `max_force[1]`, …).
    pub fn check(&self, k: usize) -> Result<(), String> {
        let row = |what: &str, v: &[f64]| -> Result<(), String> {
            if v.len() != k {
                return Err(format!(
                    "{what} has {} values, the joint has {k} coordinates",
                    v.len()
                ));
            }
            if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(format!("{what}[{i}] = {x} must be finite"));
            }
            Ok(())
        };
        match &self.force {
            JointForce::Constant(v) => row("force", v)?,
            JointForce::Table { times, values } => {
                if times.is_empty() {
                    return Err("force.times is empty".into());
                }
                if values.len() != times.len() {
                    return Err(format!(
                        "force.values has {} rows for {} times",
                        values.len(),
                        times.len()
                    ));
                }
                for (i, t) in times.iter().enumerate() {
                    if !t.is_finite() {
                        return Err(format!("force.times[{i}] = {t} must be finite"));
                    }
                    if i > 0 && *t <= times[i - 1] {
                        return Err(format!(
                            "force.times[{i}] = {t} must be greater than the time before it ({})",
                            times[i - 1]
                        ));
                    }
                }
                for (i, v) in values.iter().enumerate() {
                    row(&format!("force.values[{i}]"), v)?;
                }
            }
        }
        if !self.max_force.is_empty() && self.max_force.len() != k {
            return Err(format!(
                "max_force has {} values, the joint has {k} coordinates",
                self.max_force.len()
            ));
        }
        if let Some((i, x)) = self
            .max_force
            .iter()
            .enumerate()
            .find(|(_, x)| x.is_nan() || **x < 0.0)
        {
            return Err(format!("max_force[{i}] = {x} must be ≥ 0"));
        }
        Ok(())
    }
}

impl Default for Joint {
    fn default() -> Self {
        Self::fixed()
    }
}

impl Joint {
    /// A joint of this kind, without spring or damper.
    pub fn new(kind: JointKind) -> Self {
        Self {
            kind,
            stiffness: Vec::new(),
            damping: Vec::new(),
            rest: Vec::new(),
            prescribed: None,
            actuator: None,
        }
    }

    /// [`JointKind::Fixed`].
    pub fn fixed() -> Self {
        Self::new(JointKind::Fixed)
    }

    /// [`JointKind::Revolute`] about `axis`.
    pub fn revolute(axis: impl Into<Vec3>) -> Self {
        Self::new(JointKind::Revolute { axis: axis.into() })
    }

    /// [`JointKind::Prismatic`] along `axis`.
    pub fn prismatic(axis: impl Into<Vec3>) -> Self {
        Self::new(JointKind::Prismatic { axis: axis.into() })
    }

    /// [`JointKind::Universal`] about `a` then `b`.
    pub fn universal(a: impl Into<Vec3>, b: impl Into<Vec3>) -> Self {
        Self::new(JointKind::Universal {
            axes: [a.into(), b.into()],
        })
    }

    /// [`JointKind::Spherical`].
    pub fn spherical() -> Self {
        Self::new(JointKind::Spherical)
    }

    /// [`JointKind::Free`].
    pub fn free() -> Self {
        Self::new(JointKind::Free)
    }

    /// With a spring per coordinate.
    pub fn with_stiffness(mut self, k: &[f64]) -> Self {
        self.stiffness = k.to_vec();
        self
    }

    /// With a damper per coordinate.
    pub fn with_damping(mut self, d: &[f64]) -> Self {
        self.damping = d.to_vec();
        self
    }

    /// With a rest value per coordinate.
    pub fn with_rest(mut self, rest: &[f64]) -> Self {
        self.rest = rest.to_vec();
        self
    }

    /// With prescribed motion (one curve per coordinate, D59).
    pub fn with_prescribed(mut self, motion: Prescribed) -> Self {
        self.prescribed = Some(motion);
        self
    }

    /// With an actuator (IS14).
    pub fn with_actuator(mut self, actuator: JointActuator) -> Self {
        self.actuator = Some(actuator);
        self
    }

    /// Number of actuated coordinates: the joint's coordinates when it has
    /// an actuator, else 0.
    pub fn actuated_dof(&self) -> usize {
        if self.actuator.is_some() {
            self.dof()
        } else {
            0
        }
    }

    /// Number of generalized coordinates: the kind's, or zero when the
    /// motion is prescribed.
    pub fn dof(&self) -> usize {
        if self.prescribed.is_some() {
            0
        } else {
            self.kind.dof()
        }
    }

    /// Number of prescribed coordinates (the kind's when prescribed, else 0).
    pub fn prescribed_dof(&self) -> usize {
        if self.prescribed.is_some() {
            self.kind.dof()
        } else {
            0
        }
    }

    /// Checks the axes (finite, non-zero; universal: not parallel) and
    /// normalizes them; checks the spring, damper and rest vectors (empty or
    /// one finite value per coordinate, stiffness and damping ≥ 0).
    pub fn validate(&mut self, element: &str) -> Result<(), DynamicsError> {
        let bad = |reason: String| DynamicsError::InvalidJoint {
            element: element.to_string(),
            reason,
        };
        let unit = |a: &Vec3, what: &str| -> Result<Vec3, DynamicsError> {
            let n = a.norm();
            if !n.is_finite() || n < 1e-12 {
                return Err(bad(format!(
                    "{what} [{}, {}, {}] must be finite and non-zero",
                    a[0], a[1], a[2]
                )));
            }
            Ok(a / n)
        };
        match &mut self.kind {
            JointKind::Revolute { axis } | JointKind::Prismatic { axis } => {
                *axis = unit(axis, "axis")?;
            }
            JointKind::Universal { axes } => {
                axes[0] = unit(&axes[0], "axes[0]")?;
                axes[1] = unit(&axes[1], "axes[1]")?;
                if axes[0].cross(&axes[1]).norm() < 1e-9 {
                    return Err(bad("the two axes are parallel".into()));
                }
            }
            _ => {}
        }
        let k = self.kind.dof();
        if let Some(p) = &self.prescribed {
            p.validate(k, element)?;
            if let Some(what) = [
                ("stiffness", &self.stiffness),
                ("damping", &self.damping),
                ("rest", &self.rest),
            ]
            .iter()
            .find(|(_, v)| !v.is_empty())
            .map(|(w, _)| *w)
            {
                return Err(bad(format!(
                    "{what} on a prescribed joint: its motion is given, a spring or damper would do nothing"
                )));
            }
        }
        if let Some(a) = &self.actuator {
            if k == 0 {
                return Err(bad(
                    "an actuator on a fixed joint: it has no coordinates to drive".into(),
                ));
            }
            if self.prescribed.is_some() {
                return Err(bad(
                    "an actuator on a prescribed joint: its motion is given, a force would do nothing"
                        .into(),
                ));
            }
            a.check(k).map_err(|e| bad(format!("actuator: {e}")))?;
        }
        for (what, v, non_neg) in [
            ("stiffness", &self.stiffness, true),
            ("damping", &self.damping, true),
            ("rest", &self.rest, false),
        ] {
            if !v.is_empty() && v.len() != k {
                return Err(bad(format!(
                    "{what} has {} values, the joint has {k} coordinates",
                    v.len()
                )));
            }
            if let Some((i, x)) = v
                .iter()
                .enumerate()
                .find(|(_, x)| !x.is_finite() || (non_neg && **x < 0.0))
            {
                return Err(bad(format!(
                    "{what}[{i}] = {x} must be finite{}",
                    if non_neg { " and non-negative" } else { "" }
                )));
            }
        }
        Ok(())
    }

    /// Stiffness, damping and rest of coordinate `i` (zero when not given).
    pub(crate) fn coefficients(&self, i: usize) -> (f64, f64, f64) {
        let get = |v: &Vec<f64>| v.get(i).copied().unwrap_or(0.0);
        (get(&self.stiffness), get(&self.damping), get(&self.rest))
    }
}

/// Where an element hangs (D51): its parent (`None`: the world), the arc
/// length `at` on a parent rod (default its tip; anywhere on it, D62,
/// see [`crate::Model::with_elements`]), and the joint. The element's own
/// base pose (relative to the attachment frame, at joint value 0) is the
/// rod's [`softrod_kinematics::RodGeometry::base`] or the body's [`BodySpec::base`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Attachment {
    /// Name of the parent rod or body; `None` = the world.
    pub parent: Option<String>,
    /// Arc length on a parent rod \[m\]; `None` = its tip.
    pub at: Option<f64>,
    /// The joint.
    pub joint: Joint,
}

impl Attachment {
    /// Clamped to the world.
    pub fn world() -> Self {
        Self::default()
    }

    /// To the world through `joint`.
    pub fn world_joint(joint: Joint) -> Self {
        Self {
            joint,
            ..Self::default()
        }
    }

    /// To the element named `parent` (at a parent rod's tip) through `joint`.
    pub fn to(parent: impl Into<String>, joint: Joint) -> Self {
        Self {
            parent: Some(parent.into()),
            at: None,
            joint,
        }
    }

    /// At arc length `s` \[m\] of the parent rod.
    pub fn at(mut self, s: f64) -> Self {
        self.at = Some(s);
        self
    }

    /// Whether this is the plain clamp to the world of a rod of the section
    /// "A scene" (no parent, fixed joint).
    pub fn is_world_clamp(&self) -> bool {
        self.parent.is_none() && self.joint.kind == JointKind::Fixed
    }
}

/// A concentrated load on a rigid body at its frame's origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyLoad {
    /// Force \[N\].
    pub force: Vec3,
    /// Moment [N·m].
    pub moment: Vec3,
    /// Frame of the components: world (dead load) or body (follower).
    pub frame: LoadFrame,
}

impl BodyLoad {
    /// The body-frame wrench `(M, N)` at a body of world pose `pose`.
    #[inline]
    pub fn wrench(&self, pose: &Pose) -> Wrench {
        join(
            &self.frame.to_body(pose, &self.moment),
            &self.frame.to_body(pose, &self.force),
        )
    }
}

/// A rigid body (D52): mass \[kg\] > 0, inertia about the centre of mass
/// in body axes \[kg·m²\] (symmetric positive definite), centre of mass in
/// the body frame \[m\], base pose relative to its attachment frame at joint
/// value 0, and point loads at the body frame's origin.
#[derive(Clone, Debug, PartialEq)]
pub struct BodySpec {
    /// Name for messages, outputs and as a parent.
    pub name: String,
    /// Mass \[kg\].
    pub mass: f64,
    /// Inertia about the centre of mass, body axes \[kg·m²\].
    pub inertia: Mat3,
    /// Centre of mass in the body frame \[m\].
    pub center_of_mass: Vec3,
    /// Pose of the body frame relative to the attachment frame (joint at 0).
    pub base: Pose,
    /// Loads at the body frame's origin.
    pub loads: Vec<BodyLoad>,
}

impl BodySpec {
    /// A body with its centre of mass at the body frame's origin and the
    /// identity base pose.
    pub fn new(name: impl Into<String>, mass: f64, inertia: Mat3) -> Self {
        Self {
            name: name.into(),
            mass,
            inertia,
            center_of_mass: Vec3::zeros(),
            base: Pose::identity(),
            loads: Vec::new(),
        }
    }

    /// Principal moments `[Ixx, Iyy, Izz]` about the centre of mass.
    pub fn principal(name: impl Into<String>, mass: f64, moments: [f64; 3]) -> Self {
        Self::new(name, mass, Mat3::from_diagonal(&Vec3::from(moments)))
    }

    /// Checks mass > 0, a finite symmetric positive-definite inertia, a
    /// finite centre of mass and finite loads.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        let bad = |reason: String| DynamicsError::InvalidBody {
            body: self.name.clone(),
            reason,
        };
        if !(self.mass.is_finite() && self.mass > 0.0) {
            return Err(bad(format!("mass = {} kg must be > 0", self.mass)));
        }
        let i = &self.inertia;
        if i.iter().any(|v| !v.is_finite()) {
            return Err(bad("inertia is not finite".into()));
        }
        let scale = i.amax().max(f64::MIN_POSITIVE);
        if (i - i.transpose()).amax() > 1e-12 * scale {
            return Err(bad("inertia is not symmetric".into()));
        }
        if i.cholesky().is_none() {
            return Err(bad("inertia is not positive definite".into()));
        }
        if self.center_of_mass.iter().any(|v| !v.is_finite()) {
            return Err(bad("center_of_mass is not finite".into()));
        }
        if self.loads.iter().any(|l| {
            l.force
                .iter()
                .chain(l.moment.iter())
                .any(|v| !v.is_finite())
        }) {
            return Err(bad("a load is not finite".into()));
        }
        Ok(())
    }

    /// Screw inertia at the body frame's origin (D52): with `c` the centre
    /// of mass, `𝓜 = [[I_c − m c̃², m c̃], [−m c̃, m I]]` so that `𝓜η` is the
    /// (angular about the origin, linear) momentum for `η = (ω, v)`.
    pub fn spatial_inertia(&self) -> Mat6 {
        let c = skew(&self.center_of_mass);
        let m = self.mass;
        let mut out = Mat6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(self.inertia - c * c * m));
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(c * m));
        out.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-c * m));
        out.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(Mat3::identity() * m));
        out
    }
}
