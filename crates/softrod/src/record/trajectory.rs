//! A run kept in memory: every record's numbers at the output times.

use nalgebra::DVector;
use softrod_dynamics::{Data, Energies, Model};
use softrod_lie::Pose;

use super::{Columns, Recorder, Row};
use crate::simulation::{Flow, Observer, RunSummary, Sample};

/// A run kept in memory: samples at the output times (see
/// [`Record`](super::Record) for what each quantity is).
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// Output times \[s\].
    pub t: Vec<f64>,
    /// Coordinates at each time.
    pub q: Vec<DVector<f64>>,
    /// Velocities at each time.
    pub qdot: Vec<DVector<f64>>,
    /// Tip pose of every rod (world frame) at each time: `tips[i][rod]`.
    pub tips: Vec<Vec<Pose>>,
    /// Energies at each time.
    pub energies: Vec<Energies>,
    /// Cable tensions \[N\] at each time: `tensions[i][cable]`.
    pub tensions: Vec<Vec<f64>>,
    /// The power each cable puts into the rods \[W\]: `cable_power[i][cable]`.
    pub cable_power: Vec<Vec<f64>>,
    /// Prescribed joint coordinates at each time (D59).
    pub prescribed_q: Vec<Vec<f64>>,
    /// The prescribed drives' generalized forces at each time (D60).
    pub prescribed_force: Vec<Vec<f64>>,
    /// The largest closure residual at each time \[m\] (0 without closures).
    pub closure_residual: Vec<f64>,
    /// The active contacts at each time, with their forces, as the run's
    /// committed friction state gives them (`contacts.csv`'s rows;
    /// [`Record::contacts`](super::Record::contacts)); empty lists for a
    /// model without contact.
    pub contacts: Vec<Vec<softrod_mechanics::ContactPoint>>,
    /// The largest penetration `−gap` over the samples \[m\] (0 without
    /// contact or when nothing penetrated): `summary.json`'s
    /// `max_penetration`.
    pub max_penetration: f64,
    /// The most contacts active at one sample (`summary.json`'s
    /// `max_contacts`).
    pub max_contacts: usize,
    /// The shape of the rows ([`Trajectory::row`]).
    pub columns: Columns,
    /// How the run ended.
    pub summary: RunSummary,
}

impl Trajectory {
    /// An empty trajectory of `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            t: Vec::new(),
            q: Vec::new(),
            qdot: Vec::new(),
            tips: Vec::new(),
            energies: Vec::new(),
            tensions: Vec::new(),
            cable_power: Vec::new(),
            prescribed_q: Vec::new(),
            prescribed_force: Vec::new(),
            closure_residual: Vec::new(),
            contacts: Vec::new(),
            max_penetration: 0.0,
            max_contacts: 0,
            columns: Columns::of(model),
            summary: RunSummary::default(),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Tip position of rod `rod` at sample `i` [m, world frame].
    pub fn tip_position(&self, i: usize, rod: usize) -> [f64; 3] {
        let p = self.tips[i][rod].translation;
        [p[0], p[1], p[2]]
    }

    /// Sample `i` as a row of `trajectory.csv` (push its numbers with
    /// [`Columns::push_row`]).
    pub fn row(&self, i: usize) -> Row<'_> {
        Row {
            t: self.t[i],
            tip: &self.tips[i][0],
            energies: &self.energies[i],
            q: self.q[i].as_slice(),
            qdot: self.qdot[i].as_slice(),
            tensions: &self.tensions[i],
            cable_power: &self.cable_power[i],
            prescribed_q: &self.prescribed_q[i],
            prescribed_force: &self.prescribed_force[i],
        }
    }

    /// Bytes a sample of a model with these columns and `rods` rods keeps
    /// (for the memory check of a run).
    pub(crate) fn bytes_per_sample(columns: &Columns, rods: usize) -> u64 {
        use std::mem::size_of;
        let vec = size_of::<Vec<f64>>();
        (8 + 2 * (size_of::<DVector<f64>>() + 8 * columns.n_dof)
            + vec
            + rods * size_of::<Pose>()
            + size_of::<Energies>()
            + 4 * vec
            // The contacts' list (its entries depend on the run).
            + size_of::<Vec<softrod_mechanics::ContactPoint>>()
            + 16 * (columns.n_cables + columns.n_prescribed)
            + 8) as u64
    }
}

/// Keeps every sample of a run as a [`Trajectory`], through a
/// [`Recorder`]. The observer behind
/// [`Simulation::simulate`](crate::Simulation::simulate); front ends that
/// drive the integrator themselves (a controller in the loop) record with
/// [`TrajectoryRecorder::record`].
pub struct TrajectoryRecorder {
    traj: Trajectory,
    recorder: Recorder,
}

impl TrajectoryRecorder {
    /// An empty record for runs of `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            traj: Trajectory::new(model),
            recorder: Recorder::new(model),
        }
    }

    /// Records the state `(q, q̇)` at `t`; `data` must have the prescribed
    /// joints at `t` (`Model::set_time`).
    pub fn record(
        &mut self,
        model: &Model,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qdot: &[f64],
    ) -> std::result::Result<(), String> {
        let r = self
            .recorder
            .record(model, data, t, q, qdot)
            .map_err(|e| crate::error::report(&e))?;
        let tr = &mut self.traj;
        tr.t.push(t);
        tr.q.push(DVector::from_column_slice(q));
        tr.qdot.push(DVector::from_column_slice(qdot));
        tr.tips
            .push((0..r.poses.n_rods()).map(|i| *r.poses.tip(i)).collect());
        tr.energies.push(r.energies);
        tr.tensions.push(r.tensions.clone());
        tr.cable_power.push(r.cable_power.clone());
        tr.prescribed_q.push(r.prescribed_q.clone());
        tr.prescribed_force.push(r.prescribed_force.clone());
        tr.closure_residual.push(r.closure_residual);
        tr.contacts.push(r.contacts.clone());
        tr.max_penetration = self.recorder.max_penetration();
        tr.max_contacts = self.recorder.max_contacts();
        tr.summary.samples += 1;
        Ok(())
    }

    /// The record so far (its summary is the caller's to fill).
    pub fn trajectory_mut(&mut self) -> &mut Trajectory {
        &mut self.traj
    }

    /// [`Recorder::penetration_warning`] of the samples recorded.
    pub fn penetration_warning(&self, model: &Model) -> Option<String> {
        self.recorder.penetration_warning(model)
    }

    /// The record.
    pub fn into_trajectory(self) -> Trajectory {
        self.traj
    }
}

impl Observer for TrajectoryRecorder {
    fn sample(&mut self, s: Sample<'_>) -> std::result::Result<Flow, String> {
        self.record(s.model, s.data, s.t, s.q, s.qd)?;
        Ok(Flow::Continue)
    }
}
