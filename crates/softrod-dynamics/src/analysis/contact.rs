//! What contact outputs and checks ask of a state (docs/theory-contact.md):
//! the contacts with their forces, the deepest penetration, the check of an
//! initial state, and the commit of the friction anchors after an accepted
//! step (CT5).

use crate::algorithms::contact::{law, parent_pose};
use crate::algorithms::pairs::{mass_at, pair_law, pair_poses};
use crate::algorithms::{check_vec, contact_force};
use crate::error::DynamicsError;
use crate::forces::contact::Law;
use crate::forces::{Drives, Forces};
use crate::model::Model;
use crate::model::contact::{
    Active, ContactWork, HEAL_PERIODS, Hold, IMPACT_LIMIT, RAISE_HEADROOM, REST_TARGET,
};
use crate::model::data::Data;
use crate::model::pairs::{PairActive, PairAnchor, PairHold, PairSlide, radius_at};
use softrod_lie::Vec3;
use softrod_mechanics::contact::{ContactPoint, Contactee};

/// The stiffness state of a contact after an accepted step at `t` (CT15),
/// and the depth \[m\] that stops the run: `prev` the state the step used
/// (`None`: it starts touching), `base` its law of CT3, `mass` the mass
/// that law was set by, `radius` the surface radius, `depth` the
/// penetration. First the offset heals (`× e^(−Δt/τ)`, `τ` =
/// [`HEAL_PERIODS`] periods of the base law; zero below `ε/10`). Then, if
/// the spring carries its force `f` beyond [`REST_TARGET`] of the radius
/// (`f/k > target`), the scale rises so that `f` would sit at the target
/// divided by [`RAISE_HEADROOM`], and the offset is set so that the raised
/// penalty carries the same `f` at this depth: the force is continuous, the
/// unloading path steeper than the loading one (a raise only dissipates).
/// Any contact deeper than [`IMPACT_LIMIT`] of its radius stops the run.
fn next_hold(
    prev: Option<Hold>,
    base: &Law,
    (mass, radius): (f64, f64),
    depth: f64,
    t: f64,
) -> (Hold, f64) {
    let mut h = prev.unwrap_or_else(|| Hold::new(t));
    let tau = HEAL_PERIODS * 2.0 * std::f64::consts::PI * (mass / base.k).sqrt();
    let spring = base.scaled(h.scale, h.offset).penalty(depth).0;
    h.offset *= (-(t - h.t).max(0.0) / tau).exp();
    if h.offset < 0.1 * base.eps {
        h.offset = 0.0;
    }
    h.t = t;
    let target = REST_TARGET * radius;
    let k = base.k * h.scale;
    if spring > k * target {
        h.scale *= RAISE_HEADROOM * spring / (k * target);
        let raised = base.scaled(h.scale, 0.0);
        h.offset = (depth - raised.depth_of(spring)).max(0.0);
    }
    (h, IMPACT_LIMIT * radius)
}

/// The scale of a contact's stiffness at a static equilibrium (CT15):
/// `prev` raised, as in [`next_hold`], if the spring of the law it scales
/// carries its force deeper than [`REST_TARGET`] of the radius (no offset:
/// statics solves again from there).
fn static_scale(prev: f64, base: &Law, radius: f64, depth: f64) -> f64 {
    let law = base.scaled(prev, 0.0);
    let spring = law.penalty(depth).0;
    let target = REST_TARGET * radius;
    if spring > law.k * target {
        prev * RAISE_HEADROOM * spring / (law.k * target)
    } else {
        prev
    }
}

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
/// touches, a contact that opened forgets it), raises the stiffness of
/// contacts whose spring carries more than its target (CT15) and checks
/// the penetration: [`DynamicsError::Penetration`] (naming the rod, `s`,
/// the obstacle or other rod, `t` and the depth) if a contact is deeper
/// than [`IMPACT_LIMIT`] of its radius. Returns whether a stiffness rose
/// or an offset moved (the law changed: cached derivatives no longer
/// hold; [`commit_contact_change`] tells the two apart). Nothing for a
/// model without contact. A rejected step must not be committed: the
/// anchors and stiffnesses are read, never written, by the evaluations of
/// a step.
pub fn commit_contact(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<bool, DynamicsError> {
    commit_contact_change(model, data, t, q, qd).map(|c| c.scale_rose || c.offset_moved)
}

/// What [`commit_contact_change`] changed in the contact law (CT15).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ContactChange {
    /// A contact's stiffness scale changed (a raise, or a contact that
    /// starts or stops at a raised scale): the law's slope changed.
    pub scale_rose: bool,
    /// Only penalty offsets moved (healing, CT15 step 1): the force at a
    /// given depth changed, its slope did not.
    pub offset_moved: bool,
}

/// [`commit_contact`], telling a raised stiffness from a healed offset
/// (CT25: an integrator keeps its Newton matrix across the second and
/// across friction anchors, and refreshes it after the first).
pub fn commit_contact_change(
    model: &Model,
    data: &mut Data,
    t: f64,
    q: &[f64],
    qd: &[f64],
) -> Result<ContactChange, DynamicsError> {
    check_vec(model, "q", q)?;
    check_vec(model, "qdot", qd)?;
    if !contact_force(model, data, Forces::ALL, t, q, Some(qd)) {
        return Ok(ContactChange::default());
    }
    let mut work = data.contact.take().expect("contact work");
    let n_obs = model.contact.obstacles.len();
    let mut result = Ok(());
    let mut change = ContactChange::default();
    let mut next: Vec<(usize, usize, softrod_lie::Vec3)> = Vec::with_capacity(work.active.len());
    let mut holds: Vec<(usize, usize, Hold)> = Vec::with_capacity(work.active.len());
    for a in &work.active {
        let smp = &model.contact.samples[a.rod][a.sample];
        let idx = a.sample * n_obs + a.obstacle;
        let prev = work.holds[a.rod][idx];
        let base = law(model, a.rod, a.sample, a.obstacle, true);
        let (hold, limit) = next_hold(prev, &base, (smp.mass, smp.radius), -a.gap, t);
        let before = prev.map_or((1.0, 0.0), |p| (p.scale, p.offset));
        change.scale_rose |= hold.scale != before.0;
        change.offset_moved |= hold.offset != before.1;
        holds.push((a.rod, idx, hold));
        if result.is_ok() && -a.gap > limit {
            result = Err(DynamicsError::Penetration {
                rod: model.rod_id(a.rod),
                s: smp.s,
                other: model.contactee_name(&Contactee::Obstacle(a.obstacle)),
                t,
                depth: -a.gap,
                bound: limit,
            });
        }
        if base.mu <= 0.0 {
            continue;
        }
        // The tangential spring has the normal stiffness: after a raise
        // the stretch shrinks by the same factor (CT15), so the
        // tangential force is continuous like the normal one.
        let k = base.k * hold.scale;
        let shrink = before.0 / hold.scale;
        let frame = parent_pose(model, data, a.obstacle);
        let anchor_world = match work.anchors[a.rod][idx] {
            Some(k0) if a.sticking => {
                let k0 = frame.transform_point(&k0);
                Some(a.point - (a.point - k0) * shrink)
            }
            Some(_) => {
                // Slip: the stretch that carries the tangential force.
                let ft = a.force - a.normal * a.normal.dot(&a.force);
                Some(a.point + ft / k)
            }
            None => Some(a.point),
        };
        if let Some(w) = anchor_world {
            next.push((a.rod, idx, frame.inverse().transform_point(&w)));
        }
    }
    for anchors in &mut work.anchors {
        anchors.fill(None);
    }
    for (rod, idx, a) in next {
        work.anchors[rod][idx] = Some(a);
    }
    for h in &mut work.holds {
        h.fill(None);
    }
    for (rod, idx, h) in holds {
        work.holds[rod][idx] = Some(h);
    }
    if work.pairs.is_some() {
        let pair_result = commit_pairs(model, data, &mut work, t, q);
        match pair_result {
            Ok(c) => {
                change.scale_rose |= c.scale_rose;
                change.offset_moved |= c.offset_moved;
            }
            Err(e) if result.is_ok() => result = Err(e),
            Err(_) => {}
        }
    }
    data.contact = Some(work);
    result.map(|()| change)
}

/// A contact's slide rate along its tangential stretch `ṡ = ė·ê` \[m/s\]
/// (`ê = P e/|P e|`, `ė` the stretch's rate, world axes) and pre-slip
/// `|f_t|/k` \[m\] (CT29, CT30), if it is on the slip branch with an
/// anchor and carries friction: a contact whose normal force is zero (an
/// opening one, its damping holding it at `f_n = 0`) carries none, so it
/// pushes nothing back.
fn slide_rate(
    sticking: bool,
    k: f64,
    normal: &Vec3,
    force: &Vec3,
    stretch: &Vec3,
    rate: &Vec3,
) -> Option<(f64, f64)> {
    let e = stretch.norm();
    if sticking || e <= 0.0 || k <= 0.0 {
        return None;
    }
    let ft = (force - normal * normal.dot(force)).norm();
    if ft <= 0.0 {
        return None;
    }
    let vt = rate - normal * normal.dot(rate);
    Some((vt.dot(stretch) / e, ft / k))
}

/// Where a slide stopped inside a step (docs/theory-contact.md CT29): the
/// fraction `θ ∈ (0, 1)` of the step `h` from `(t0, q0, q̇0)` to
/// `(t1, q1, q̇1)` at which a sliding contact's tangential velocity
/// crossed zero, if the step must be retried at `θ h`; `None` if it may be
/// accepted. Read at the committed anchors, without writing them.
///
/// Within a step the anchors are fixed (CT5), so a sliding point that
/// stops inside the step is still held on the slip branch by the stretch
/// it slid out in the step: friction `μ f_n` pushes it back toward its
/// anchor by up to the distance it slid in the step — the continuous law
/// would have stuck it within its pre-slip `μ f_n/k`. A contact on the
/// slip branch at the step end whose stretch shrinks (`s₁ = ė·ê < 0`,
/// `ê` the stretch's direction, `ė` its rate) while it grew at the step
/// start (`s₀ > 0`) marks such a stop; `θ` is the zero of the secant of
/// `s` (exact for a constant friction force). The step is retried if the
/// slide back it caused, `½ |s₁| (1 − θ) h`, exceeds that contact's
/// pre-slip `μ f_n/k` (the elastic give CT5 already allows): a stop is
/// located to the law's own resolution, whatever the tolerances. A
/// contact without friction force at the step end (`f_n = 0`) is skipped.
/// Rod–obstacle contacts (`ė` the point's velocity), and rod–rod and self
/// contact pairs (CT10, CT30: `ė` the relative velocity of the anchor's
/// material points, `b`'s turning with its section). Nothing for a model
/// without friction.
#[allow(clippy::too_many_arguments)]
pub fn friction_stop(
    model: &Model,
    data: &mut Data,
    h: f64,
    t0: f64,
    q0: &[f64],
    qd0: &[f64],
    t1: f64,
    q1: &[f64],
    qd1: &[f64],
) -> Result<Option<f64>, DynamicsError> {
    let pair_friction = model.contact.settings.any() && model.contact.settings.friction > 0.0;
    if !model.has_contact()
        || !(pair_friction || model.obstacles().iter().any(|o| o.friction > 0.0))
    {
        return Ok(None);
    }
    check_vec(model, "q", q1)?;
    check_vec(model, "qdot", qd1)?;
    check_vec(model, "q", q0)?;
    check_vec(model, "qdot", qd0)?;
    // The pairs' stretch rates for these two evaluations only.
    let set_rates = |data: &mut Data, on: bool| {
        if let Some(pw) = data.contact.as_mut().and_then(|w| w.pairs.as_mut()) {
            pw.rates = on;
        }
    };
    set_rates(data, true);
    let theta = locate_stop(model, data, h, t0, q0, qd0, t1, q1, qd1);
    set_rates(data, false);
    Ok(theta)
}

/// [`friction_stop`] after its checks, with the pairs' rates on.
#[allow(clippy::too_many_arguments)]
fn locate_stop(
    model: &Model,
    data: &mut Data,
    h: f64,
    t0: f64,
    q0: &[f64],
    qd0: &[f64],
    t1: f64,
    q1: &[f64],
    qd1: &[f64],
) -> Option<f64> {
    let n_obs = model.contact.obstacles.len();
    let rate = |a: &Active| {
        slide_rate(
            a.sticking,
            a.k,
            &a.normal,
            &a.force,
            &a.stretch,
            &a.velocity,
        )
    };
    let pair_rate = |c: &PairActive| {
        slide_rate(
            c.sticking,
            c.k,
            &c.normal,
            &c.force,
            &c.stretch,
            &c.stretch_rate,
        )
    };
    if !contact_force(model, data, Forces::ALL, t1, q1, Some(qd1)) {
        return None;
    }
    let mut work = data.contact.take().expect("contact work");
    work.slides.clear();
    for a in &work.active {
        if let Some((s1, pre_slip)) = rate(a)
            && s1 < 0.0
        {
            let idx = a.sample * n_obs + a.obstacle;
            work.slides.push((a.rod, idx, s1, pre_slip));
        }
    }
    let mut any = !work.slides.is_empty();
    if let Some(pw) = &mut work.pairs {
        pw.slides.clear();
        for c in &pw.active {
            if let Some((s1, pre_slip)) = pair_rate(c)
                && s1 < 0.0
            {
                pw.slides.push(PairSlide {
                    a: c.a,
                    sa: c.sa,
                    b: c.b,
                    sb: c.sb,
                    reach: c.radius_a + radius_at(model, c.b, c.sb),
                    rate: s1,
                    pre_slip,
                });
            }
        }
        any |= !pw.slides.is_empty();
    }
    data.contact = Some(work);
    if !any || !contact_force(model, data, Forces::ALL, t0, q0, Some(qd0)) {
        return None;
    }
    let work = data.contact.as_ref().expect("contact work");
    let mut theta: Option<f64> = None;
    // Retried at the earliest stop whose slide back exceeds its pre-slip.
    let mut stop = |s0: f64, s1: f64, pre_slip: f64| {
        if s0 <= 0.0 {
            return;
        }
        let th = s0 / (s0 - s1);
        let back = 0.5 * (-s1) * (1.0 - th) * h;
        if back > pre_slip {
            theta = Some(theta.map_or(th, |m: f64| m.min(th)));
        }
    };
    // The start's own rate: on either branch, its stretch's rate along the
    // stretch (a sticking start has a stretch too).
    let start = |stretch: &Vec3, normal: &Vec3, rate: &Vec3| {
        let e = stretch.norm();
        (e > 0.0).then(|| (rate - normal * normal.dot(rate)).dot(stretch) / e)
    };
    // Rod pairs (CT30): the same pair at the step start is the one the
    // anchors' rule (CT10) matches, its two arc lengths within `r_a + r_b`.
    if let Some(pw) = &work.pairs {
        for sl in &pw.slides {
            let Some(c) = pw.active.iter().find(|c| {
                c.a == sl.a
                    && c.b == sl.b
                    && (c.sa - sl.sa).abs() < sl.reach
                    && (c.sb - sl.sb).abs() < sl.reach
            }) else {
                continue;
            };
            if let Some(s0) = start(&c.stretch, &c.normal, &c.stretch_rate) {
                stop(s0, sl.rate, sl.pre_slip);
            }
        }
    }
    for &(rod, idx, s1, pre_slip) in &work.slides {
        let Some(a) = work
            .active
            .iter()
            .find(|a| a.rod == rod && a.sample * n_obs + a.obstacle == idx)
        else {
            continue;
        };
        if let Some(s0) = start(&a.stretch, &a.normal, &a.velocity) {
            stop(s0, s1, pre_slip);
        }
    }
    theta
}

/// The stiffness of resting contacts for statics (CT15): at the
/// equilibrium `q` (drives at rest at `t`), every contact whose spring
/// carries its force deeper than [`REST_TARGET`] of its radius has its
/// scale raised as in [`commit_contact`] (a state held in `data`, read by
/// the next solve); contacts apart forget theirs. Returns whether any
/// scale rose (the equilibrium must be solved again).
pub(crate) fn raise_for_rest(model: &Model, data: &mut Data, t: f64, q: &[f64]) -> bool {
    let zero = vec![0.0; model.n_dof()];
    let forces = Forces::ALL.with_drives(Drives::AtRest);
    if !contact_force(model, data, forces, t, q, Some(&zero)) {
        return false;
    }
    let mut work = data.contact.take().expect("contact work");
    let n_obs = model.contact.obstacles.len();
    let mut raised = false;
    let at_rest = |scale: f64| Hold {
        scale,
        offset: 0.0,
        t: f64::NEG_INFINITY,
    };
    let mut holds = Vec::with_capacity(work.active.len());
    for a in &work.active {
        let smp = &model.contact.samples[a.rod][a.sample];
        let idx = a.sample * n_obs + a.obstacle;
        let prev = work.holds[a.rod][idx].map_or(1.0, |h| h.scale);
        let base = law(model, a.rod, a.sample, a.obstacle, false);
        let scale = static_scale(prev, &base, smp.radius, -a.gap);
        raised |= scale != prev;
        holds.push((a.rod, idx, at_rest(scale)));
    }
    for h in &mut work.holds {
        h.fill(None);
    }
    for (rod, idx, h) in holds {
        work.holds[rod][idx] = Some(h);
    }
    if let Some(pw) = &mut work.pairs {
        pw.next_holds.clear();
        for c in &pw.active {
            let rb = radius_at(model, c.b, c.sb);
            let reach = c.radius_a + rb;
            let prev = pw
                .holds
                .iter()
                .find(|h| h.matches(c.a, c.sa, c.b, c.sb, reach))
                .map_or(1.0, |h| h.hold.scale);
            let radius = c.radius_a.min(rb);
            let (base, _) = pair_base(model, c.a, c.sa, c.b, c.sb, radius);
            let scale = static_scale(prev, &base, radius, -c.gap);
            raised |= scale != prev;
            pw.next_holds.push(PairHold {
                a: c.a,
                sa: c.sa,
                b: c.b,
                sb: c.sb,
                hold: at_rest(scale),
            });
        }
        std::mem::swap(&mut pw.holds, &mut pw.next_holds);
    }
    data.contact = Some(work);
    raised
}

/// The base law of a rod pair (CT11, frictionless) and the mass its
/// stiffness is set by (the smaller side's).
fn pair_base(model: &Model, a: usize, sa: f64, b: usize, sb: f64, radius: f64) -> (Law, f64) {
    let law = pair_law(model, a, sa, b, sb, radius, false);
    (law, mass_at(model, a, sa).min(mass_at(model, b, sb)))
}

/// The commit of rod–rod contact (CT10, CT15): the stiffness states, the
/// penetration check against [`IMPACT_LIMIT`] of the smaller radius, and
/// the pairs' friction anchors — kept while
/// sticking, moved to carry `μ f_n` while sliding, set where a new pair
/// touches, dropped when it opens.
fn commit_pairs(
    model: &Model,
    data: &Data,
    work: &mut ContactWork,
    t: f64,
    q: &[f64],
) -> Result<ContactChange, DynamicsError> {
    let mut pw = work.pairs.take().expect("pair work");
    let mut result = Ok(());
    let mut change = ContactChange::default();
    pw.next.clear();
    pw.next_holds.clear();
    let with_friction = model.contact.settings.friction > 0.0;
    for c in &pw.active {
        let rb = radius_at(model, c.b, c.sb);
        let radius = c.radius_a.min(rb);
        let prev = pw
            .holds
            .iter()
            .find(|h| h.matches(c.a, c.sa, c.b, c.sb, c.radius_a + rb))
            .map(|h| h.hold);
        let (base, mass) = pair_base(model, c.a, c.sa, c.b, c.sb, radius);
        let (hold, bound) = next_hold(prev, &base, (mass, radius), -c.gap, t);
        let before = prev.map_or((1.0, 0.0), |p| (p.scale, p.offset));
        change.scale_rose |= hold.scale != before.0;
        change.offset_moved |= hold.offset != before.1;
        pw.next_holds.push(PairHold {
            a: c.a,
            sa: c.sa,
            b: c.b,
            sb: c.sb,
            hold,
        });
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
    std::mem::swap(&mut pw.holds, &mut pw.next_holds);
    work.pairs = Some(pw);
    result.map(|()| change)
}
