//! Control: which actuation puts the model where it is wanted.
//!
//! [`solve_actuation`] (and [`Simulation::solve_actuation`](crate::Simulation::solve_actuation))
//! is *inverse statics*: given targets for rod sections or bodies (a
//! position, an orientation, or both, each with a weight), it finds the
//! cable tensions `0 ≤ T ≤ T_max` and the static equilibrium `q(T)`
//! (constrained, with loop closures) that bring them closest to the
//! targets, with the least effort among equally good tensions
//! (docs/theory-control.md, IS1–IS12); point forces marked unknown
//! ([`UnknownLoad`]) are solved for with them (IS13), and so are the
//! forces of joints with an actuator, within `|f| ≤ max_force` (IS14–IS15).
//!
//! Why a module of the facade and not a crate of its own: the solver is a
//! few hundred lines on top of `softrod-dynamics`' public statics, actuation
//! matrix, derivatives and section Jacobians, its one new dependency
//! (clarabel, the bounded QP) is needed by nothing below, and its users
//! reach it through [`Simulation`](crate::Simulation) like statics and modes;
//! a `softrod-control` crate would add a layer with one client. The
//! trajectory gradients of issue 28 may justify one later. Like every
//! library module it never prints: everything it has to say is in
//! [`Actuation`].
//!
//! Units SI: positions in m, rotation errors in rad, tensions and forces
//! in N, joint torques in N·m; poses
//! in the world frame.

mod inverse;
mod qp;
pub mod targets;

pub use inverse::{
    Actuation, ActuationOptions, Bound, DEFAULT_EFFORT_WEIGHT, Target, TargetResidual, UnknownLoad,
    solve_actuation,
};
pub use targets::Transition;
