//! What contact outputs and checks ask of a state (docs/theory-contact.md):
//! the contacts with their forces, the deepest penetration, the check of an
//! initial state, and the commit of the friction anchors after an accepted
//! step (CT5).

use crate::algorithms::contact::{law, parent_pose};
use crate::algorithms::pairs::pair_poses;
use crate::algorithms::{check_vec, contact_force};
use crate::error::DynamicsError;
use crate::forces::Forces;
use crate::model::Model;
use crate::model::contact::{Active, ContactWork};
use crate::model::data::Data;
use crate::model::pairs::{PairAnchor, radius_at};
use softrod_lie::Vec3;
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
        let mut out: Vec<ContactPoint> = work.active.iter().map(|a| self.point_of(a)).collect();
        if let Some(pairs) = &work.pairs {
            out.extend(pairs.active.iter().map(|c| ContactPoint {
                a: c.a,
                s: c.sa,
                b: Contactee::Rod { rod: c.b, s: c.sb },
                point: c.point - c.normal * c.radius_a,
                normal: c.normal,
                gap: c.gap,
                force: c.force,
                sticking: c.sticking,
            }));
        }
        Ok(out)
    }

    /// The penetration a contact may start with (CT3): 1 % of the smaller
    /// radius of the two surfaces.
    fn allowed_at(&self, c: &ContactPoint) -> f64 {
        let own = self.allowed_penetration(c.a, c.s);
        match c.b {
            Contactee::Obstacle(_) => own,
            Contactee::Rod { rod, s } => own.min(self.allowed_penetration(rod, s)),
        }
    }

    /// The surface radius a contact's penetration is measured against \[m\]
    /// (CT3): the rod's at `s`, the smaller of the two for rods touching.
    /// The stated bounds are fractions of it (1 % at rest, 10 % in a 1 m/s
    /// impact of the rod's own inertia).
    pub fn contact_scale(&self, c: &ContactPoint) -> f64 {
        self.allowed_at(c) / crate::model::contact::REST_PENETRATION
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
    /// obstacle or another rod (or itself) than
    /// [`Model::allowed_penetration`] (1 % of its radius, of the smaller
    /// radius for two rods): [`DynamicsError::InitialOverlap`] naming the
    /// rod and `s`, the obstacle or the other rod and its `s`, and the
    /// depth.
    pub fn check_initial_contact(&self, q: &[f64]) -> Result<(), DynamicsError> {
        if !self.has_contact() {
            return Ok(());
        }
        let zero = vec![0.0; self.n_dof()];
        for c in self.contacts(0.0, q, &zero)? {
            let allowed = self.allowed_at(&c);
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

    /// `obstacle 'name'` or `rod 'name' (its s = … m)`, for messages.
    pub fn contactee_name(&self, b: &Contactee) -> String {
        match *b {
            Contactee::Obstacle(o) => format!("obstacle '{}'", self.contact.obstacles[o].name),
            Contactee::Rod { rod, s } => {
                format!("rod '{}' (its s = {s:.6} m)", self.rods[rod].spec.name)
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
    if work.pairs.is_some() {
        let pair_result = commit_pairs(model, data, &mut work, t, q);
        if result.is_ok() {
            result = pair_result;
        }
    }
    data.contact = Some(work);
    result
}

/// The commit of rod–rod contact (CT10): the penetration check against
/// half the smaller radius, and the pairs' friction anchors — kept while
/// sticking, moved to carry `μ f_n` while sliding, set where a new pair
/// touches, dropped when it opens.
fn commit_pairs(
    model: &Model,
    data: &Data,
    work: &mut ContactWork,
    t: f64,
    q: &[f64],
) -> Result<(), DynamicsError> {
    let mut pw = work.pairs.take().expect("pair work");
    let mut result = Ok(());
    pw.next.clear();
    let with_friction = model.contact.settings.friction > 0.0;
    for c in &pw.active {
        let rb = radius_at(model, c.b, c.sb);
        let bound = FAILURE_PENETRATION * c.radius_a.min(rb);
        if result.is_ok() && -c.gap > bound {
            result = Err(DynamicsError::Penetration {
                rod: model.rod_id(c.a),
                s: c.sa,
                other: model.contactee_name(&Contactee::Rod { rod: c.b, s: c.sb }),
                t,
                depth: -c.gap,
                bound,
            });
        }
        if !with_friction {
            continue;
        }
        let kept = pw.anchors.iter().find(|k| {
            k.a == c.a
                && k.b == c.b
                && (k.sa - c.sa).abs() < c.radius_a + rb
                && (k.sb - c.sb).abs() < c.radius_a + rb
        });
        let anchor = match kept {
            Some(k) if c.sticking => *k,
            _ => {
                // New, or sliding: anchor the touching points, offset so
                // the stretch carries the sliding force (zero if new).
                let (pa, gb) = pair_poses(model, data, work, q, c);
                let ft = match kept {
                    Some(_) => (c.force - c.normal * c.normal.dot(&c.force)) / c.k,
                    None => Vec3::zeros(),
                };
                PairAnchor {
                    a: c.a,
                    sa: c.sa,
                    b: c.b,
                    sb: c.sb,
                    offset: gb.rotation.transpose() * (pa - gb.translation + ft),
                }
            }
        };
        pw.next.push(anchor);
    }
    std::mem::swap(&mut pw.anchors, &mut pw.next);
    work.pairs = Some(pw);
    result
}
