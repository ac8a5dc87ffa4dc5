//! Errors of model building and the dynamics algorithms.

use softrod_kinematics::{KinematicsError, Strain};
use softrod_mechanics::MechanicsError;
use std::fmt;

/// A rod as errors name it: its index in the model (`None` before it is in
/// one, e.g. from [`crate::RodBuilder::build`]) and its name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RodId {
    /// Position in the model's rods (0-based), when known.
    pub index: Option<usize>,
    /// [`crate::Rod::name`] (may be empty).
    pub name: String,
}

impl fmt::Display for RodId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.index, self.name.is_empty()) {
            (Some(i), false) => write!(f, "rod {i} ('{}')", self.name),
            (Some(i), true) => write!(f, "rod {i}"),
            (None, false) => write!(f, "rod '{}'", self.name),
            (None, true) => f.write_str("rod"),
        }
    }
}

/// What went wrong, with the values that did.
///
/// Model-building variants name the rod ([`RodId`]) and chain the lower
/// layer's error as [`std::error::Error::source`], so a caller (a scene
/// loader) can map it back to its input by matching, not by reading text.
/// A variant with a source does not repeat it in its message: whoever
/// prints an error walks the chain (`softrod::report`) and
/// shows each cause once.
#[non_exhaustive]
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// A model with no rod.
    #[error("a model needs at least one rod")]
    NoRods,
    /// Zero Gauss points per piece.
    #[error("quadrature needs at least one Gauss point per piece")]
    NoQuadraturePoints,
    /// A gravity component is NaN or infinite.
    #[error("gravity component {component} is not finite ({value})")]
    GravityNotFinite {
        /// 0 = x, 1 = y, 2 = z (world).
        component: usize,
        /// The value.
        value: f64,
    },
    /// The kinematic description of a rod (length, pieces, strains, rest
    /// strain, base pose) is invalid.
    #[error("{rod}: invalid kinematic description")]
    RodGeometry {
        /// Which rod.
        rod: RodId,
        /// What the kinematics layer rejected.
        #[source]
        source: KinematicsError,
    },
    /// The body of a rod (length, section) is invalid, or does not match
    /// the kinematic rod's length.
    #[error("{rod}: invalid body")]
    RodProperties {
        /// Which rod.
        rod: RodId,
        /// What the mechanics layer rejected.
        #[source]
        source: MechanicsError,
    },
    /// [`crate::RodBuilder::build`] without a section.
    #[error("{rod}: no section given")]
    MissingSection {
        /// Which rod.
        rod: RodId,
    },
    /// [`crate::RodBuilder::build`] without a material.
    #[error("{rod}: no material given")]
    MissingMaterial {
        /// Which rod.
        rod: RodId,
    },
    /// Piece lengths that do not sum to the rod length (to
    /// `softrod_mechanics::RodProperties::LENGTH_RTOL`).
    #[error("{rod}: piece lengths sum to {sum} m but the rod length is {length} m")]
    PieceLengthSum {
        /// Which rod.
        rod: RodId,
        /// `Σ ℓ_n` \[m\].
        sum: f64,
        /// The length given \[m\].
        length: f64,
    },
    /// Not one stress-free strain per piece.
    #[error("{rod}: {got} stress-free strains given for {expected} pieces")]
    StressFreeCount {
        /// Which rod.
        rod: RodId,
        /// Strains given.
        got: usize,
        /// Pieces of the rod.
        expected: usize,
    },
    /// A stress-free strain component is NaN or infinite.
    #[error("{rod}: stress-free strain {component} of piece {piece} is not finite ({value})")]
    StressFreeNotFinite {
        /// Which rod.
        rod: RodId,
        /// Piece index.
        piece: usize,
        /// The component.
        component: Strain,
        /// The value.
        value: f64,
    },
    /// A cable of a rod is invalid on that rod.
    #[error("{rod}, cable {cable}: invalid cable")]
    Cable {
        /// Which rod.
        rod: RodId,
        /// Index in [`crate::Rod::cables`].
        cable: usize,
        /// What the mechanics layer rejected.
        #[source]
        source: MechanicsError,
    },
    /// A point load of a rod is invalid on that rod.
    #[error("{rod}, point load {load}: invalid point load")]
    PointLoad {
        /// Which rod.
        rod: RodId,
        /// Index in [`crate::Rod::point_loads`].
        load: usize,
        /// What the mechanics layer rejected.
        #[source]
        source: MechanicsError,
    },
    /// A distributed load of a rod is invalid.
    #[error("{rod}, distributed load {load}: invalid distributed load")]
    DistributedLoad {
        /// Which rod.
        rod: RodId,
        /// Index in [`crate::Rod::distributed_loads`].
        load: usize,
        /// What the mechanics layer rejected.
        #[source]
        source: MechanicsError,
    },
    /// The drag of a rod is invalid.
    #[error("{rod}: invalid drag")]
    Drag {
        /// Which rod.
        rod: RodId,
        /// What the mechanics layer rejected.
        #[source]
        source: MechanicsError,
    },
    /// A kinematic query of an evaluation failed.
    #[error("kinematics of rod {rod} failed")]
    Kinematics {
        /// Rod index in the model.
        rod: usize,
        /// The kinematics layer's error.
        #[source]
        source: KinematicsError,
    },
    /// A rod index past the model's rods.
    #[error("rod index {index} is out of range (the model has {count} rods)")]
    RodIndex {
        /// The index given.
        index: usize,
        /// The number of rods.
        count: usize,
    },
    /// A body index past the model's bodies.
    #[error("body index {index} is out of range (the model has {count} bodies)")]
    BodyIndex {
        /// The index given.
        index: usize,
        /// The number of bodies.
        count: usize,
    },
    /// A vector argument has the wrong length.
    #[error("{what} has {got} entries, the model has {expected} coordinates")]
    SizeMismatch {
        /// Which argument.
        what: &'static str,
        /// Its length.
        got: usize,
        /// `n_dof`.
        expected: usize,
    },
    /// The cable-tension inputs do not match the model's cables.
    #[error("{got} cable tensions given, the model has {expected} cables")]
    TensionCount {
        /// Tensions given.
        got: usize,
        /// [`crate::Model::n_cables`].
        expected: usize,
    },
    /// A cable-tension input is negative or not finite (a cable can only pull).
    #[error("cable tension u[{index}] = {value} N must be finite and non-negative")]
    InvalidTension {
        /// Index of the cable in model order.
        index: usize,
        /// The value given.
        value: f64,
    },
    /// The joint force inputs do not match the model's actuated joint
    /// coordinates (IS14).
    #[error("{got} joint forces given, the model has {expected} actuated joint coordinates")]
    JointForceCount {
        /// Forces given.
        got: usize,
        /// [`crate::Model::n_joint_inputs`].
        expected: usize,
    },
    /// A value is NaN or infinite.
    #[error("{what} is not finite ({value})")]
    NotFinite {
        /// Which quantity and where.
        what: String,
        /// The value.
        value: f64,
    },
    /// The dynamics evaluated at finite arguments gave a value that is not
    /// finite: not bad input but a breakdown at the state reached (an
    /// explicit step that diverged, a state far beyond the model's validity).
    #[error(
        "{what} is not finite ({value}) at a finite state: the dynamics broke down there \
         (a step that diverged, or a state far beyond the model's validity)"
    )]
    NonFiniteResult {
        /// Which quantity, at which time.
        what: String,
        /// The value.
        value: f64,
    },
    /// A per-piece matrix that must be positive definite is not.
    #[error("{what} of rod {rod}, piece {piece} is not positive definite")]
    Singular {
        /// Rod index.
        rod: usize,
        /// Piece index.
        piece: usize,
        /// Which matrix.
        what: &'static str,
    },
    /// A whole-model matrix (the mass matrix) that must be positive definite
    /// is not; its Cholesky factorization does not say where.
    #[error("{what} is not positive definite")]
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
    },
    /// A matrix-free analysis that needs a symmetric tangent stiffness
    /// ([`crate::lowest_modes`]) met a non-symmetric one (follower loads,
    /// cables).
    #[error(
        "{what} needs a symmetric tangent stiffness, this one's relative asymmetry is about {asymmetry:.1e} (non-conservative loads: world-frame moments, follower loads or cables): use the dense modes, which take the symmetric part"
    )]
    NotSymmetric {
        /// Which analysis.
        what: &'static str,
        /// The estimated `‖K − Kᵀ‖_F / ‖K‖_F`.
        asymmetry: f64,
    },
    /// Statics did not converge.
    #[error(
        "statics did not converge: {reason} (load fraction {load_fraction:.3}, {iterations} Newton iterations, residual {residual:.3e})"
    )]
    StaticsFailed {
        /// Why it stopped.
        reason: String,
        /// Fraction of the full load reached by continuation.
        load_fraction: f64,
        /// Newton iterations spent in total.
        iterations: usize,
        /// Residual norm (max-abs, N or N·m per coordinate) at the stop.
        residual: f64,
    },
    /// A shift coefficient of `M + a·K + b·D` is negative or not finite
    /// ([`crate::ShiftedSolver::factor`]).
    #[error("shift coefficient {what} = {value} must be finite and non-negative")]
    InvalidShift {
        /// `"a"` (stiffness) or `"b"` (damping).
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A solve was asked of a factorization that does not exist yet (or
    /// whose last `factor` failed).
    #[error("{what}: solve called before a successful factor")]
    NotFactored {
        /// Which solver.
        what: &'static str,
    },
    /// A joint is invalid (axis zero or not finite, parallel universal
    /// axes, spring/damper/rest vectors of the wrong length or sign).
    #[error("joint of '{element}': {reason}")]
    InvalidJoint {
        /// Name of the element the joint moves.
        element: String,
        /// What is wrong, with the values.
        reason: String,
    },
    /// A rigid body is invalid (mass ≤ 0, inertia not symmetric positive
    /// definite, values not finite).
    #[error("body '{body}': {reason}")]
    InvalidBody {
        /// The body's name.
        body: String,
        /// What is wrong, with the values.
        reason: String,
    },
    /// An element names a parent that is no rod or body of the model (or
    /// a name several elements share).
    #[error("'{element}': parent '{parent}' is {reason}")]
    UnknownParent {
        /// The element.
        element: String,
        /// The parent it names.
        parent: String,
        /// "not a rod or body of the model" or "ambiguous (…)".
        reason: String,
    },
    /// The parents form a cycle.
    #[error("'{element}' is its own ancestor (parent cycle)")]
    ParentCycle {
        /// An element on the cycle.
        element: String,
    },
    /// An element hangs from a rod at an arc length outside it.
    #[error("'{element}': at = {at} m is not on rod '{parent}' (0 to {length} m)")]
    AttachOutsideRod {
        /// The element.
        element: String,
        /// The parent rod.
        parent: String,
        /// The arc length asked for \[m\].
        at: f64,
        /// The parent rod's length \[m\].
        length: f64,
    },
    /// An articulated-body matrix of a node of a model with joints or
    /// bodies is not positive definite (e.g. nothing with inertia outboard
    /// of a joint).
    #[error("{what} at {node} is not positive definite")]
    SingularNode {
        /// Which node (element and part).
        node: String,
        /// Which matrix.
        what: &'static str,
    },
    /// An algorithm that does not (yet) cover models with joints, bodies or
    /// parents was called on one.
    #[error("{what} does not support models with joints, bodies or parents yet")]
    Unsupported {
        /// Which algorithm.
        what: &'static str,
    },
    /// A workspace was built for a model of another shape.
    #[error("{what} was built for a model with {built} coordinates, used with one of {got}")]
    WorkspaceMismatch {
        /// Which workspace.
        what: &'static str,
        /// `n_dof` of the model it was built for.
        built: usize,
        /// `n_dof` of the model it is used with.
        got: usize,
    },
    /// An algorithm that does not (yet) cover loop closures was called on a
    /// model with closures (docs/theory.md §11, D67).
    #[error("{what} does not support models with loop closures yet")]
    UnsupportedClosed {
        /// Which algorithm.
        what: &'static str,
    },
    /// An algorithm that does not cover contact was called on a model
    /// with contact (its forces enter the dense derivatives only).
    #[error("{what} does not support models with contact (use the dense derivatives)")]
    UnsupportedContact {
        /// Which algorithm.
        what: &'static str,
    },
    /// Products of a linearization were asked before one succeeded.
    #[error("{what}: no linearization evaluated (or the last one failed)")]
    NotLinearized {
        /// Which product.
        what: &'static str,
    },
    /// A closure frame is invalid: unknown element, `at` off the rod, a
    /// base pose that is not a rigid motion.
    #[error("closure '{closure}', frame {end} (element '{element}'): {reason}")]
    ClosureFrame {
        /// The closure's name.
        closure: String,
        /// "a" or "b".
        end: &'static str,
        /// The element named.
        element: String,
        /// What is wrong.
        reason: String,
    },
    /// A slider closure's axis is zero or not finite.
    #[error("closure '{closure}': slider axis {axis:?} is zero or not finite")]
    ClosureAxis {
        /// The closure's name.
        closure: String,
        /// The axis given.
        axis: softrod_lie::Vec3,
    },
    /// An obstacle's description is invalid.
    #[error("obstacle {index} ('{name}') is invalid")]
    Obstacle {
        /// Position in the obstacle list (0-based).
        index: usize,
        /// Its name.
        name: String,
        /// What is wrong.
        #[source]
        source: softrod_mechanics::ObstacleError,
    },
    /// An obstacle's parent is no body of the model.
    #[error(
        "obstacle {index} ('{name}'): parent '{parent}' is not a body of the model (bodies: {})",
        if bodies.is_empty() { "none; use \"world\"".to_string() } else { bodies.join(", ") }
    )]
    ObstacleParent {
        /// Position in the obstacle list.
        index: usize,
        /// Its name.
        name: String,
        /// The unknown parent.
        parent: String,
        /// The model's bodies.
        bodies: Vec<String>,
    },
    /// The rod–rod contact settings are invalid.
    #[error("contact settings are invalid")]
    ContactSettings {
        /// What is wrong.
        #[source]
        source: softrod_mechanics::ObstacleError,
    },
    /// A rod's contact radius is not positive and finite.
    #[error("{rod}: contact_radius must be positive and finite, got {value}")]
    ContactRadius {
        /// Which rod.
        rod: RodId,
        /// The value.
        value: f64,
    },
    /// A rod starts inside an obstacle or another rod, deeper than allowed
    /// (docs/theory-contact.md CT3).
    #[error(
        "{rod} starts inside {other} at s = {s:.6} m: penetration {depth:.3e} m > allowed \
         {allowed:.3e} m (move it out)"
    )]
    InitialOverlap {
        /// The rod.
        rod: RodId,
        /// Arc length on it \[m\].
        s: f64,
        /// What it overlaps: `obstacle 'name'` or `rod 'name' (its s = … m)`.
        other: String,
        /// Penetration depth \[m\].
        depth: f64,
        /// The allowed penetration \[m\].
        allowed: f64,
    },
    /// A contact penetrated deeper than the model can resolve
    /// (docs/theory-contact.md CT3).
    #[error(
        "{rod} penetrates {other} at s = {s:.6} m, t = {t} s by {depth:.3e} m > bound \
         {bound:.3e} m (contact failed: smaller steps, or a slower impact)"
    )]
    Penetration {
        /// The rod.
        rod: RodId,
        /// Arc length on it \[m\].
        s: f64,
        /// What it penetrates.
        other: String,
        /// Time \[s\].
        t: f64,
        /// Penetration depth \[m\].
        depth: f64,
        /// The bound \[m\].
        bound: f64,
    },
    /// A closure does not hold at the initial state (D66).
    #[error(
        "closure '{closure}' does not hold at the initial state: residual {residual:.3e} m \
         > tolerance {tolerance:.3e} m (start from a state where the closed loop is assembled)"
    )]
    ClosureNotHeld {
        /// The closure's name.
        closure: String,
        /// Its residual norm `max(‖d‖, ℓ‖r‖)` \[m\].
        residual: f64,
        /// The tolerance `1e-9 ℓ` \[m\].
        tolerance: f64,
    },
}

/// The rod field of the model-building variants, by reference of either
/// mutability (match ergonomics give `&RodId` or `&mut RodId`).
macro_rules! rod_of {
    ($e:expr) => {
        match $e {
            DynamicsError::RodGeometry { rod, .. }
            | DynamicsError::RodProperties { rod, .. }
            | DynamicsError::MissingSection { rod }
            | DynamicsError::MissingMaterial { rod }
            | DynamicsError::PieceLengthSum { rod, .. }
            | DynamicsError::StressFreeCount { rod, .. }
            | DynamicsError::StressFreeNotFinite { rod, .. }
            | DynamicsError::Cable { rod, .. }
            | DynamicsError::PointLoad { rod, .. }
            | DynamicsError::DistributedLoad { rod, .. }
            | DynamicsError::Drag { rod, .. }
            | DynamicsError::ContactRadius { rod, .. } => Some(rod),
            _ => None,
        }
    };
}

impl DynamicsError {
    /// The rod a model-building error is about, if any.
    pub fn rod(&self) -> Option<&RodId> {
        rod_of!(self)
    }

    /// The same error with the rod's index in the model set.
    pub(crate) fn at_rod_index(mut self, index: usize) -> Self {
        if let Some(rod) = rod_of!(&mut self) {
            rod.index = Some(index);
        }
        self
    }
}
