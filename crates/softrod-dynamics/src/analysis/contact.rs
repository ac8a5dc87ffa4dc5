//! What contact outputs and checks ask of a state (docs/theory-contact.md):
//! the contacts with their forces, the deepest penetration, the check of an
//! initial state, and the commit of the friction anchors after an accepted
//! step (CT5).

use crate::algorithms::contact::{law, parent_pose};
use crate::algorithms::{check_vec, contact_force};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::contact::Active;
use crate::model::data::Data;
use softrod_mechanics::contact::{ContactPoint, Contactee};

/// A contact penetrating deeper than this fraction of the rod's radius
/// stops a run ([`commit_contact`]): the penalty no longer resolves it.
pub const FAILURE_PENETRATION: f64 = 0.5;

impl Model {
    /// The active contacts at `(t, q, q̇)` and their forces, for outputs
    /// (allocates a fresh [`Data`]: no committed friction state, so friction
    /// forces are zero; [`Model::contacts_with`] uses a run's state). Empty
    /// for a model without contact.
    pub fn contacts(
        &self,
        t: f64,
        q: &[f64],
        qdot: &[f64],
    ) -> Result<Vec<ContactPoint>, DynamicsError> {
        let mut data = Data::new(self);
        self.contacts_with(&mut data, t, q, qdot)
    }

    /// [`Model::contacts`] with the friction state committed in `data`
    /// ([`commit_contact`]): with friction, each force is the one the
    /// dynamics at that state uses.
    pub fn contacts_with(
        &self,
        data: &mut Data,
        t: f64,
        q: &[f64],
        qdot: &[f64],
    ) -> Result<Vec<ContactPoint>, DynamicsError> {
        check_vec(self, "q", q)?;
        check_vec(self, "qdot", qdot)?;
        if !contact_force(self, data, Forces::ALL, t, q, Some(qdot)) {
            return Ok(Vec::new());
        }
        let work = data.contact.as_ref().expect("contact work");
        Ok(work.active.iter().map(|a| self.point_of(a)).collect())
    }

    fn point_of(&self, a: &Active) -> ContactPoint {
        let smp = &self.contact.samples[a.rod][a.sample];
        ContactPoint {
            a: a.rod,
            s: smp.s,
            b: Contactee::Obstacle(a.obstacle),
            point: a.point - a.normal * smp.radius,
            normal: a.normal,
            gap: a.gap,
            force: a.force,
            sticking: a.sticking,
        }
    }

    /// The largest penetration `−gap` \[m\] at `(t, q)`, 0 if none.
    pub fn max_penetration(&self, t: f64, q: &[f64]) -> Result<f64, DynamicsError> {
        let zero = vec![0.0; self.n_dof()];
        Ok(self
            .contacts(t, q, &zero)?
            .iter()
            .fold(0.0, |m, c| f64::max(m, -c.gap)))
    }

    /// Refuses an initial state where a rod starts deeper inside an
    /// obstacle than [`Model::allowed_penetration`] (1 % of its radius):
    /// [`DynamicsError::InitialOverlap`] naming the rod, the obstacle, `s`
    /// and the depth.
    pub fn check_initial_contact(&self, q: &[f64]) -> Result<(), DynamicsError> {
        if !self.has_contact() {
            return Ok(());
        }
        let zero = vec![0.0; self.n_dof()];
        for c in self.contacts(0.0, q, &zero)? {
            let allowed = self.allowed_penetration(c.a, c.s);
            if -c.gap > allowed {
                return Err(DynamicsError::InitialOverlap {
                    rod: self.rod_id(c.a),
                    s: c.s,
                    other: self.contactee_name(&c.b),
                    depth: -c.gap,
                    allowed,
                });
            }
        }
        Ok(())
    }

    /// `obstacle 'name'` or `rod 'name' at s = …`, for messages.
    pub fn contactee_name(&self, b: &Contactee) -> String {
        match *b {
            Contactee::Obstacle(o) => format!("obstacle '{}'", self.contact.obstacles[o].name),
            Contactee::Rod { rod, s } => {
                format!("rod '{}' at s = {s:.6} m", self.rods[rod].spec.name)
            }
        }
    }
}

/// After an accepted step to `(t, q, q̇)`: commits the friction anchors
/// (CT5: a sticking contact keeps its anchor, a sliding one drags it to
/// where the spring carries `μ f_n`, a new contact anchors where it
/// touches, a contact that opened forgets it) and checks the penetration:
/// [`DynamicsError::Penetration`] if a contact is deeper than
/// [`FAILURE_PENETRATION`] of the rod's radius. Nothing for a model
/// without contact. A rejected step must not be committed: the anchors are
/// read, never written, by the evaluations of a step.
pub fn commit_contact(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<(), DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    if !contact_force(model, data, Forces::ALL, t, q, Some(qd)) {
        return Ok(());
    }
    let mut work = data.contact.take().expect("contact work");
    let n_obs = model.contact.obstacles.len();
    let mut result = Ok(());
    let mut next: Vec<(usize, usize, softrod_lie::Vec3)> = Vec::with_capacity(work.active.len());
    for a in &work.active {
        let smp = &model.contact.samples[a.rod][a.sample];
        if result.is_ok() && -a.gap > FAILURE_PENETRATION * smp.radius {
            result = Err(DynamicsError::Penetration {
                rod: model.rod_id(a.rod),
                s: smp.s,
                other: model.contactee_name(&Contactee::Obstacle(a.obstacle)),
                t,
                depth: -a.gap,
                bound: FAILURE_PENETRATION * smp.radius,
            });
        }
        let l = law(model, a.rod, a.sample, a.obstacle, true);
        if l.mu <= 0.0 {
            continue;
        }
        let frame = parent_pose(model, data, a.obstacle);
        let idx = a.sample * n_obs + a.obstacle;
        let anchor_world = match work.anchors[a.rod][idx] {
            Some(_) if a.sticking => None,
            Some(_) => {
                // Slip: the stretch that carries the tangential force.
                let ft = a.force - a.normal * a.normal.dot(&a.force);
                Some(a.point + ft / l.k)
            }
            None => Some(a.point),
        };
        let keep = work.anchors[a.rod][idx];
        let world = anchor_world.or_else(|| keep.map(|k| frame.transform_point(&k)));
        if let Some(w) = world {
            next.push((a.rod, idx, frame.inverse().transform_point(&w)));
        }
    }
    for anchors in &mut work.anchors {
        anchors.fill(None);
    }
    for (rod, idx, a) in next {
        work.anchors[rod][idx] = Some(a);
    }
    data.contact = Some(work);
    result
}
