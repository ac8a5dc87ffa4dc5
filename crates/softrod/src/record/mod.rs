//! What a run records at each output time, computed once here for every
//! front end: the state, the energies (D28), each cable's tension and the
//! power it puts into the rods (D15), the prescribed joints' coordinates
//! and the generalized forces their drives apply (D59–D60), the largest
//! closure residual (D66), and the world poses of every rod (tips, piece
//! boundaries, strains and, on request, samples along the exact PCS arcs)
//! and body.
//!
//! - [`Recorder`] fills one [`Record`] per sample, reusing its buffers (a
//!   front end that streams, like `softrod run`, formats each record and
//!   keeps nothing); it refuses non-finite values and a closed loop that
//!   came apart ([`RecordError`]).
//! - [`TrajectoryRecorder`] keeps every record's numbers as a
//!   [`Trajectory`] (what [`Simulation::simulate`](crate::Simulation::simulate)
//!   and the Python package return).
//! - [`Columns`] names the columns of `trajectory.csv`, in order; every
//!   writer takes them from there.
//! - [`WorldPoses`] is the one definition of world poses (also behind
//!   [`Simulation::pose`](crate::Simulation::pose) and its siblings).
//!
//! A new recorded quantity goes into [`Record`] (computed in
//! [`Recorder::record`]) and, if it is a column, into [`Columns`]. The
//! contacts (`contacts.csv`, scene-format.md "Contact") are in
//! [`Record::contacts`]: one entry per active contact with its force, from
//! the sample's dynamics buffers (the run's friction state).

mod columns;
mod poses;
mod trajectory;

pub use columns::{CONTRACT_COLUMNS, ColumnGroup, Columns, Row};
pub use poses::{
    MAX_DEFAULT_POINTS_PER_PIECE, RodSampling, SMOOTH_SAMPLES_PER_ROD, WorldPoses,
    default_points_per_piece, position, quaternion,
};
pub use trajectory::{Trajectory, TrajectoryRecorder};

use nalgebra::DVectorView;
use softrod_dynamics::{
    Data, Energies, Model, actuation_matrix, energies, forward_dynamics, max_closure_residual,
};

use crate::error::Error;

/// A run stops with [`RecordError::ClosureApart`] when the largest closure
/// residual exceeds this fraction of the model's length scale (its longest
/// rod): the loop has come apart and the results mean nothing.
pub const CLOSURE_FAIL_RELATIVE: f64 = 1e-3;
/// Front ends warn when the largest closure residual of a run exceeds this
/// fraction of the length scale (the Baumgarte stabilization normally
/// holds it far below; a tighter `rtol` reduces it).
pub const CLOSURE_WARN_RELATIVE: f64 = 1e-6;

/// The length scale of a model's closure residuals: its longest rod \[m\].
pub fn closure_length_scale(model: &Model) -> f64 {
    model
        .rods()
        .iter()
        .map(|r| r.spec.geometry.length())
        .fold(0.0, f64::max)
}

/// Everything recorded at one output time. Units SI; poses in the world
/// frame.
#[derive(Clone, Debug)]
pub struct Record {
    /// Time \[s\].
    pub t: f64,
    /// Coordinates (n_dof).
    pub q: Vec<f64>,
    /// Velocities (n_dof).
    pub qdot: Vec<f64>,
    /// Kinetic, elastic and gravitational energy \[J\] (with prescribed
    /// joints the kinetic energy includes their motion).
    pub energies: Energies,
    /// Each cable's tension \[N\] (model order): the input set with
    /// `Data::set_cable_tensions`, else its schedule at `t`.
    pub tensions: Vec<f64>,
    /// The power each cable puts into the rods, `T_c (B_c · q̇)` \[W\],
    /// `B_c` the cable's column of the actuation matrix (D15).
    pub cable_power: Vec<f64>,
    /// The prescribed joint coordinates at `t` \[rad or m\] (D59).
    pub prescribed_q: Vec<f64>,
    /// The generalized force each prescribed drive applies \[N·m or N\]
    /// (D60), from the forward dynamics at this state.
    pub prescribed_force: Vec<f64>,
    /// The largest closure residual `max(‖d‖, ℓ‖r‖)` \[m\] (D66); 0
    /// without closures.
    pub closure_residual: f64,
    /// World poses of every rod and body.
    pub poses: WorldPoses,
    /// The active contacts with their forces (rod `a` at `s`, what touches
    /// it, point, normal from b to a, gap, force on `a` \[N\], stick or
    /// slip; docs/theory-contact.md), as the run's committed friction state
    /// gives them; empty for a model without contact.
    pub contacts: Vec<softrod_mechanics::ContactPoint>,
}

impl Record {
    /// The record's row of `trajectory.csv` (see [`Columns`]).
    pub fn row(&self) -> Row<'_> {
        Row {
            t: self.t,
            tip: self.poses.tip(0),
            energies: &self.energies,
            q: &self.q,
            qdot: &self.qdot,
            tensions: &self.tensions,
            cable_power: &self.cable_power,
            prescribed_q: &self.prescribed_q,
            prescribed_force: &self.prescribed_force,
        }
    }
}

/// Why a sample could not be recorded. Each ends the run (its `Display`
/// is what the run reports).
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// A recorded number is NaN or infinite (`what` names its column:
    /// `q3`, `qdot0`, `energy`, `tip pose`, `prescribed_force1`).
    #[error("non-finite {what} at t = {t:e}; output stopped")]
    NonFinite {
        /// What is not finite.
        what: String,
        /// Time \[s\].
        t: f64,
    },
    /// A sampled pose of a rod is NaN or infinite.
    #[error("non-finite pose of rod '{rod}' at s = {s} m, t = {t:e}; output stopped")]
    NonFinitePose {
        /// The rod's name.
        rod: String,
        /// Abscissa \[m\].
        s: f64,
        /// Time \[s\].
        t: f64,
    },
    /// An evaluation failed (`what`: `energy`, `closure residual`, `poses`,
    /// `cables`, `prescribed joint forces`).
    #[error("{what} at t = {t:e}")]
    Evaluation {
        /// What was being evaluated.
        what: &'static str,
        /// Time \[s\].
        t: f64,
        /// Why it failed.
        #[source]
        source: Box<Error>,
    },
    /// The largest closure residual exceeds [`CLOSURE_FAIL_RELATIVE`] of the
    /// longest rod.
    #[error(
        "closure residual {residual:.3e} m at t = {t:e} exceeds {limit:.3e} m ({CLOSURE_FAIL_RELATIVE:e} \
         of the longest rod): the closed loop has come apart; output stopped"
    )]
    ClosureApart {
        /// The residual \[m\].
        residual: f64,
        /// Time \[s\].
        t: f64,
        /// The limit \[m\].
        limit: f64,
    },
}

impl RecordError {
    fn evaluation(what: &'static str, t: f64) -> impl FnOnce(Error) -> Self {
        move |e| Self::Evaluation {
            what,
            t,
            source: Box::new(e),
        }
    }

    /// The time of the sample \[s\].
    pub fn t(&self) -> f64 {
        match self {
            Self::NonFinite { t, .. }
            | Self::NonFinitePose { t, .. }
            | Self::Evaluation { t, .. }
            | Self::ClosureApart { t, .. } => *t,
        }
    }
}

/// Fills a [`Record`] per sample (see the [module docs](self)), its buffers
/// allocated once.
#[derive(Clone, Debug)]
pub struct Recorder {
    record: Record,
    /// The residual that stops the run \[m\].
    closure_limit: f64,
    closure_residual_max: f64,
    max_penetration: f64,
    deepest_relative: Option<Penetration>,
    max_contacts: usize,
}

/// Depth over a contact's radius beyond which a run warns: the stated bound
/// of a 1 m/s impact (docs/theory-contact.md CT3).
pub const PENETRATION_WARN: f64 = 0.1;

/// A penetration measured against its contact's radius: where a run went
/// deepest ([`Recorder::deepest_relative_penetration`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Penetration {
    /// Depth over the contact's radius.
    pub relative: f64,
    /// Depth \[m\].
    pub depth: f64,
    /// Time \[s\].
    pub t: f64,
    /// The rod (model index) and its arc length there \[m\].
    pub rod: usize,
    /// See [`Penetration::rod`].
    pub s: f64,
}

impl Recorder {
    /// A recorder for runs of `model`: tips, boundaries, strains and
    /// bodies, no samples along the rods.
    pub fn new(model: &Model) -> Self {
        Self::with_poses(model, WorldPoses::new(model))
    }

    /// A recorder that also samples every rod at `sampling` (one per rod,
    /// model order; see [`RodSampling::of_model`]).
    pub fn with_sampling(model: &Model, sampling: Vec<RodSampling>) -> Self {
        Self::with_poses(model, WorldPoses::with_sampling(model, sampling))
    }

    fn with_poses(model: &Model, poses: WorldPoses) -> Self {
        let n = model.n_dof();
        let np = model.n_prescribed();
        let nc = model.n_cables();
        Self {
            record: Record {
                t: 0.0,
                q: vec![0.0; n],
                qdot: vec![0.0; n],
                energies: Energies::default(),
                tensions: Vec::with_capacity(nc),
                cable_power: Vec::with_capacity(nc),
                prescribed_q: vec![0.0; np],
                prescribed_force: vec![0.0; np],
                closure_residual: 0.0,
                poses,
                contacts: Vec::new(),
            },
            closure_limit: CLOSURE_FAIL_RELATIVE * closure_length_scale(model),
            closure_residual_max: 0.0,
            max_penetration: 0.0,
            deepest_relative: None,
            max_contacts: 0,
        }
    }

    /// Records the state `(q, q̇)` at `t`. `data` must hold the prescribed
    /// joints at `t` (`Model::set_time`, as the run's samples do); it is
    /// used as scratch.
    pub fn record(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qdot: &[f64],
    ) -> Result<&Record, RecordError> {
        let non_finite = |v: &[f64]| v.iter().position(|x| !x.is_finite());
        if let Some(i) = non_finite(q) {
            return Err(RecordError::NonFinite {
                what: format!("q{i}"),
                t,
            });
        }
        if let Some(i) = non_finite(qdot) {
            return Err(RecordError::NonFinite {
                what: format!("qdot{i}"),
                t,
            });
        }
        let r = &mut self.record;
        r.t = t;
        r.q.copy_from_slice(q);
        r.qdot.copy_from_slice(qdot);
        r.energies = energies(model, data, q, qdot)
            .map_err(|e| RecordError::evaluation("energy", t)(e.into()))?;
        if model.has_closures() {
            let res = max_closure_residual(model, data, q)
                .map_err(|e| RecordError::evaluation("closure residual", t)(e.into()))?;
            r.closure_residual = res;
            self.closure_residual_max = self.closure_residual_max.max(res);
            if res.is_nan() || res > self.closure_limit {
                return Err(RecordError::ClosureApart {
                    residual: res,
                    t,
                    limit: self.closure_limit,
                });
            }
        }
        if !r.energies.total().is_finite() {
            return Err(RecordError::NonFinite {
                what: "energy".into(),
                t,
            });
        }
        r.poses
            .update(model, t, q)
            .map_err(RecordError::evaluation("poses", t))?;
        let tip = r.poses.tip(0);
        let finite = |p: &softrod_lie::Pose| {
            poses::position(p)
                .iter()
                .chain(poses::quaternion(p).iter())
                .all(|v| v.is_finite())
        };
        if !finite(tip) {
            return Err(RecordError::NonFinite {
                what: "tip pose".into(),
                t,
            });
        }
        for (i, rm) in model.rods().iter().enumerate() {
            if let Some(k) = r.poses.samples(i).iter().position(|g| !finite(g)) {
                return Err(RecordError::NonFinitePose {
                    rod: rm.spec.name.clone(),
                    s: r.poses.sampling(i).s[k],
                    t,
                });
            }
        }
        r.tensions.clear();
        r.cable_power.clear();
        if model.n_cables() > 0 {
            let b = actuation_matrix(model, q)
                .map_err(|e| RecordError::evaluation("cables", t)(e.into()))?;
            let qdv = DVectorView::from_slice(qdot, qdot.len());
            let inputs = data.cable_tensions();
            for rm in model.rods() {
                for (c, cable) in rm.spec.cables.iter().enumerate() {
                    let col = rm.cable_offset + c;
                    let tension = inputs.map_or_else(|| cable.tension_at(t), |u| u[col]);
                    r.tensions.push(tension);
                    r.cable_power.push(tension * b.column(col).dot(&qdv));
                }
            }
        }
        if model.n_prescribed() > 0 {
            // The drive's force comes with the accelerations at this state.
            forward_dynamics(model, data, t, q, qdot, None)
                .map_err(|e| RecordError::evaluation("prescribed joint forces", t)(e.into()))?;
            if let Some(i) = non_finite(data.prescribed_force.as_slice()) {
                return Err(RecordError::NonFinite {
                    what: format!("prescribed_force{i}"),
                    t,
                });
            }
            r.prescribed_q.copy_from_slice(data.prescribed_q.as_slice());
            r.prescribed_force
                .copy_from_slice(data.prescribed_force.as_slice());
        }
        r.contacts.clear();
        if model.has_contact() {
            r.contacts = model
                .contacts_with(data, t, q, qdot)
                .map_err(|e| RecordError::evaluation("contacts", t)(e.into()))?;
            let bad = r.contacts.iter().position(|c| {
                !(c.gap.is_finite()
                    && c.s.is_finite()
                    && c.point
                        .iter()
                        .chain(&c.normal)
                        .chain(&c.force)
                        .all(|v| v.is_finite()))
            });
            if let Some(k) = bad {
                return Err(RecordError::NonFinite {
                    what: format!("contact {k}"),
                    t,
                });
            }
            let deepest = r.contacts.iter().fold(0.0, |m, c| f64::max(m, -c.gap));
            self.max_penetration = self.max_penetration.max(deepest);
            for c in &r.contacts {
                let relative = -c.gap / model.contact_scale(c);
                if relative > self.deepest_relative.map_or(0.0, |d| d.relative) {
                    self.deepest_relative = Some(Penetration {
                        relative,
                        depth: -c.gap,
                        t,
                        rod: c.a,
                        s: c.s,
                    });
                }
            }
            self.max_contacts = self.max_contacts.max(r.contacts.len());
        }
        Ok(&self.record)
    }

    /// The largest penetration `−gap` over the samples recorded \[m\] (0
    /// without contact or when nothing penetrated).
    pub fn max_penetration(&self) -> f64 {
        self.max_penetration
    }

    /// The run's warning when it penetrated deeper than [`PENETRATION_WARN`]
    /// of a contact's radius (what `summary.json` and Python's
    /// `Trajectory.warnings` say), naming the rod, `s`, the time and depth.
    pub fn penetration_warning(&self, model: &Model) -> Option<String> {
        let p = self
            .deepest_relative
            .filter(|p| p.relative > PENETRATION_WARN)?;
        Some(format!(
            "contact: rod {:?} at s = {:.4} m sank {:.3e} m ({:.1} % of its radius) at t = {}, \
             beyond the stated {:.0} % (docs/theory-contact.md CT3: the stiffness is set by \
             each point's own weight and inertia; a concentrated load or a faster impact sinks \
             deeper)",
            model.rods()[p.rod].spec.name,
            p.s,
            p.depth,
            100.0 * p.relative,
            p.t,
            100.0 * PENETRATION_WARN
        ))
    }

    /// The deepest penetration relative to its contact's radius
    /// ([`Model::contact_scale`]) over the samples recorded, and where; `None`
    /// when nothing penetrated. The stated bounds (docs/theory-contact.md
    /// CT3) are 0.01 at rest and 0.1 in a 1 m/s impact.
    pub fn deepest_relative_penetration(&self) -> Option<Penetration> {
        self.deepest_relative
    }

    /// The most contacts active at one sample.
    pub fn max_contacts(&self) -> usize {
        self.max_contacts
    }

    /// The last record (the state at `t = 0` of an empty one before the
    /// first [`Recorder::record`]).
    pub fn last(&self) -> &Record {
        &self.record
    }

    /// The largest closure residual over the samples recorded \[m\] (0
    /// without closures).
    pub fn closure_residual_max(&self) -> f64 {
        self.closure_residual_max
    }
}
