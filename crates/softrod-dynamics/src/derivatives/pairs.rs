//! The analytic linearization of rod–rod and self contact
//! (docs/theory-contact.md CT13–CT14): the force of CT10–CT11 acts between
//! the closest points `s_a`, `s_b` of two centrelines, which move with `q`
//! as the stationarity of the distance dictates (or stay at a rod's end
//! where they are clamped); the friction stretch moves with the anchor's
//! two material points. On the chain and on the tree, through the point
//! paths of [`super::second`].

use super::contact::column;
use super::second;
use crate::model::Model;
use crate::model::contact::ContactWork;
use crate::model::data::Data;
use crate::model::pairs::{radius_at, radius_slope};
use crate::model::second::{Gathered, PointPath};
use nalgebra::DMatrix;
use softrod_lie::Vec3;

/// Whether the analytic path covers every touching pair (CT14): pairs of
/// uniform rods, and frictionless pairs of tapered ones except where the
/// two radii are equal while their slopes differ (the kink of the law's
/// `min(r_a, r_b)`, no derivative there). Tapered pairs with friction are
/// still differenced: there the analytic columns were 1e-9 relative off
/// the central differences, above their error, not yet explained.
pub(crate) fn analytic_applies(model: &Model, work: &ContactWork) -> bool {
    let friction = model.contact.settings.friction > 0.0;
    work.pairs.as_ref().is_none_or(|pw| {
        pw.active.iter().all(|c| {
            let (sa, sb) = (radius_slope(model, c.a), radius_slope(model, c.b));
            sa == 0.0 && sb == 0.0
                || !friction && (radius_at(model, c.b, c.sb) != c.radius_a || sa == sb)
        })
    })
}

/// The path of rod `rod`'s material point at `s`, `offset` in its section
/// frame, on the chain or the tree.
#[allow(clippy::too_many_arguments)]
fn path(
    model: &Model,
    data: &Data,
    kin: &[softrod_kinematics::RodKinematics],
    q: &[f64],
    qd: &[f64],
    rod: usize,
    s: f64,
    offset: Vec3,
    out: &mut PointPath,
) -> Vec3 {
    match &model.tree {
        None => second::chain_rod(model, &kin[rod], q, Some(qd), rod, s, offset, out),
        Some(_) => second::tree_rod(model, data, q, Some(qd), rod, s, offset, out),
    }
}

/// Subtracts `∂τ_c/∂q`, `∂τ_c/∂q̇` of the touching pairs (CT14) from
/// `dq`, `dqd`. The rods' kinematics (chain) or the node data (tree) are
/// those of `(q, q̇)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn linearize(
    model: &Model,
    data: &Data,
    work: &mut ContactWork,
    q: &[f64],
    qd: &[f64],
    dq: &mut DMatrix<f64>,
    dqd: &mut DMatrix<f64>,
) {
    let ContactWork {
        kin, pairs, second, ..
    } = work;
    let Some(pw) = pairs.as_ref() else {
        return;
    };
    let sw = &mut **second;
    for c in &pw.active {
        let pa = path(model, data, kin, q, qd, c.a, c.sa, Vec3::zeros(), &mut sw.a);
        let pb = path(model, data, kin, q, qd, c.b, c.sb, Vec3::zeros(), &mut sw.b);
        let anchored = c.anchor.filter(|_| c.de.iter().any(|x| *x != 0.0));
        if let Some(k) = anchored {
            path(
                model,
                data,
                kin,
                q,
                qd,
                c.a,
                k.sa,
                Vec3::zeros(),
                &mut sw.ea,
            );
            path(model, data, kin, q, qd, c.b, k.sb, k.offset, &mut sw.eb);
        }
        sw.dofs.clear();
        for p in [&sw.a, &sw.b] {
            sw.dofs.extend(p.cols.iter().map(|c| c.dof));
        }
        if anchored.is_some() {
            for p in [&sw.ea, &sw.eb] {
                sw.dofs.extend(p.cols.iter().map(|c| c.dof));
            }
        }
        sw.dofs.sort_unstable();
        sw.dofs.dedup();
        for m in [&mut sw.jw, &mut sw.vq, &mut sw.je, &mut sw.ta, &mut sw.tb] {
            m.fill(0.0);
        }
        sw.a.add_jacobian(1.0, &mut sw.jw);
        sw.b.add_jacobian(-1.0, &mut sw.jw);
        sw.a.add_velocity_derivative(qd, 1.0, &mut sw.vq);
        sw.b.add_velocity_derivative(qd, -1.0, &mut sw.vq);
        sw.a.add_tangent_derivative(1.0, &mut sw.ta);
        sw.b.add_tangent_derivative(1.0, &mut sw.tb);
        if anchored.is_some() {
            sw.ea.add_jacobian(1.0, &mut sw.je);
            sw.eb.add_jacobian(-1.0, &mut sw.je);
        }
        // How the closest points move (CT13): the stationarity
        // g_a = w·t_a = 0, g_b = −w·t_b = 0 differentiated, a parameter
        // clamped at its rod's end held.
        let w = pa - pb;
        let (ta, tb) = (sw.a.tangent(), sw.b.tangent());
        let (ka, kb) = (sw.a.curvature(), sw.b.curvature());
        let haa = ta.dot(&ta) + w.dot(&ka);
        let hbb = tb.dot(&tb) - w.dot(&kb);
        let hab = -ta.dot(&tb);
        let gn = ta.dot(&ta) * tb.dot(&tb);
        let parallel = ta.dot(&ta) * tb.dot(&tb) - hab * hab <= 1e-10 * gn;
        let la = model.rods[c.a].spec.geometry.length();
        let lb = model.rods[c.b].spec.geometry.length();
        let clamped_a = c.sa <= 0.0 || c.sa >= la;
        let clamped_b = c.sb <= 0.0 || c.sb >= lb;
        let det = haa * hbb - hab * hab;
        for &l in &sw.dofs {
            let jl = column(&sw.jw, l);
            let ga = ta.dot(&jl) + w.dot(&column(&sw.ta, l));
            let gb = -tb.dot(&jl) - w.dot(&column(&sw.tb, l));
            let (da, db) = match (clamped_a, clamped_b) {
                (true, true) => (0.0, 0.0),
                (true, false) => (0.0, -gb / hbb),
                (false, true) => (-ga / haa, 0.0),
                // Parallel arcs: the refinement moves only s_a (CT8).
                _ if parallel => (-ga / haa, 0.0),
                _ => ((-ga * hbb + gb * hab) / det, (-gb * haa + ga * hab) / det),
            };
            sw.dsa[l] = da;
            sw.dsb[l] = db;
        }
        let (tda, tdb) = (sw.a.tangent_rate(), sw.b.tangent_rate());
        let f = c.force;
        // A tapered rod's radius moves with its closest point (CT14): the
        // gap `|w| − r_a − r_b` by `f_w n` (∂f/∂|w| at a fixed direction),
        // the law's radius `min(r_a, r_b)` by `∂f/∂r`.
        let (slope_a, slope_b) = (radius_slope(model, c.a), radius_slope(model, c.b));
        let law_on_a = c.radius_a <= radius_at(model, c.b, c.sb);
        let fwn = c.dw * c.normal;
        sw.gather.clear();
        for &l in &sw.dofs {
            let (da, db) = (sw.dsa[l], sw.dsb[l]);
            let jl = column(&sw.jw, l);
            let dw = jl + ta * da - tb * db;
            let dv = column(&sw.vq, l) + tda * da - tdb * db;
            let dgap = slope_a * da + slope_b * db;
            let dlaw = if law_on_a { slope_a * da } else { slope_b * db };
            sw.gather.push(Gathered {
                j: jl,
                f: c.dw * dw + c.de * column(&sw.je, l) + c.dv * dv - fwn * dgap + c.dr * dlaw,
                g: c.dv * jl,
                // J_w's own motion with s: ∂J_a/∂s = ∂t_a/∂q.
                u: Vec3::new(column(&sw.ta, l).dot(&f), column(&sw.tb, l).dot(&f), 0.0),
                a: da,
                b: db,
            });
        }
        let n = dq.nrows();
        let (mq, mqd) = (dq.as_mut_slice(), dqd.as_mut_slice());
        for (gl, &l) in sw.gather.iter().zip(&sw.dofs) {
            for (gi, &i) in sw.gather.iter().zip(&sw.dofs) {
                let moving = gi.u.x * gl.a - gi.u.y * gl.b;
                mq[l * n + i] -= gi.j.dot(&gl.f) + moving;
                mqd[l * n + i] -= gi.j.dot(&gl.g);
            }
        }
        sw.a.add_hessian_contraction(&f, -1.0, dq);
        sw.b.add_hessian_contraction(&f, 1.0, dq);
    }
}

#[cfg(test)]
mod tests {
    //! The analytic contact linearization (CT6, CT12–CT14) against central
    //! differences of the generalized contact force `τ_c` itself, with the
    //! friction anchors committed a moment before so that contacts stick or
    //! slide. Each column's bound is the differencing error, estimated as
    //! `|D(h) − D(2h)|` (three times the truncation error of `D(h)`, plus
    //! its round-off), plus a round-off floor of `1e-9` of the matrix.
    use crate::algorithms::contact_force;
    use crate::derivatives::contact::subtract_contact;
    use crate::forces::Forces;
    use crate::model::{Attachment, BodySpec, Data, Joint, JointKind, Model, Rod};
    use nalgebra::{DMatrix, DVector};
    use softrod_kinematics::Strain;
    use softrod_lie::{Pose, Vec3, Vec6, exp_twist};
    use softrod_mechanics::Material;
    use softrod_mechanics::contact::{ContactSettings, Obstacle, Shape};

    fn silicone() -> Material {
        Material::builder()
            .density(1000.0)
            .young(1.0e6)
            .poisson(0.5)
            .build()
            .unwrap()
    }

    fn placed(axis: Vec3, angle: f64, at: Vec3) -> Pose {
        let w = axis * angle;
        Pose::new(
            exp_twist(1.0, &Vec6::new(w.x, w.y, w.z, 0.0, 0.0, 0.0)).rotation,
            at,
        )
    }

    fn wiggle(n: usize, amp: f64, f: f64) -> Vec<f64> {
        (0..n).map(|i| amp * ((i as f64) * f).sin()).collect()
    }

    fn tau_c(model: &Model, data: &mut Data, q: &[f64], qd: &[f64]) -> DVector<f64> {
        assert!(contact_force(model, data, Forces::ALL, 0.0, q, Some(qd)));
        data.contact.as_ref().unwrap().tau.clone()
    }

    /// Checks `∂τ_c/∂q`, `∂τ_c/∂q̇` at `(q, q̇)` after committing the
    /// anchors at `q_before`; returns the numbers of sticking and sliding
    /// contacts (obstacle and pair ones).
    fn check(model: &Model, q: &[f64], qd: &[f64], q_before: &[f64], what: &str) -> (usize, usize) {
        let n = model.n_dof();
        let mut data = Data::new(model);
        crate::commit_contact(model, &mut data, 0.0, q_before, qd).unwrap();
        let (mut tau, mut dq, mut dqd) = (
            DVector::zeros(n),
            DMatrix::zeros(n, n),
            DMatrix::zeros(n, n),
        );
        subtract_contact(
            model,
            &mut data,
            Forces::ALL,
            0.0,
            q,
            qd,
            &mut tau,
            &mut dq,
            &mut dqd,
        );
        let w = data.contact.as_ref().unwrap();
        let mut counts = (0, 0);
        let mut count = |s: bool| if s { counts.0 += 1 } else { counts.1 += 1 };
        for a in &w.active {
            count(a.sticking);
        }
        if let Some(pw) = &w.pairs {
            for c in &pw.active {
                count(c.sticking);
            }
        }
        assert!(counts.0 + counts.1 > 0, "{what}: nothing touches");
        for (which, analytic) in [(0, &dq), (1, &dqd)] {
            let scale = analytic.abs().max();
            let mut worst: f64 = 0.0;
            for l in 0..n {
                let base = if which == 0 { q[l] } else { qd[l] };
                let step = if which == 0 { 1e-7 } else { 1e-5 };
                let h = step * (1.0 + base.abs());
                let mut diff = |h: f64| {
                    let (mut a, mut b) = ((q.to_vec(), qd.to_vec()), (q.to_vec(), qd.to_vec()));
                    if which == 0 {
                        a.0[l] += h;
                        b.0[l] -= h;
                    } else {
                        a.1[l] += h;
                        b.1[l] -= h;
                    }
                    (tau_c(model, &mut data, &a.0, &a.1) - tau_c(model, &mut data, &b.0, &b.1))
                        / (2.0 * h)
                };
                let (d1, d2) = (diff(h), diff(2.0 * h));
                // dq holds −∂τ_c.
                let err = (&d1 + analytic.column(l)).norm();
                let bound = 10.0 * (&d1 - &d2).norm() + 1e-9 * scale;
                worst = worst.max(err / (d1.norm() + 1e-300));
                assert!(
                    err <= bound,
                    "{what}: column {l} of d/d{}: error {err:.3e}, differencing error {:.3e}, |col| {:.3e}",
                    ["q", "qd"][which],
                    (&d1 - &d2).norm(),
                    d1.norm()
                );
            }
            eprintln!(
                "{what} d/d{}: worst relative error {worst:.2e}",
                ["q", "qd"][which]
            );
        }
        counts
    }

    /// An arm on a revolute joint pressing on a tilted table with friction,
    /// sticking and sliding (a tree: CT12).
    #[test]
    fn arm_on_a_joint_pressing_on_a_table() {
        let arm = Rod::builder(0.3)
            .pieces(4)
            .strains(Strain::ALL)
            .circle(0.01)
            .material(silicone());
        let joint = Joint::new(JointKind::Revolute { axis: Vec3::y() });
        let bare = Model::builder()
            .rod_on(arm, Attachment::world_joint(joint))
            .gravity([0.0, 0.0, -9.81])
            .build()
            .unwrap();
        let n = bare.n_dof();
        let mut q = wiggle(n, 1e-3, 1.3);
        // Turn the arm down by 0.1 rad.
        q[0] = 0.1;
        let qd = wiggle(n, 0.05, 0.7);
        let mut data = Data::new(&bare);
        let (tip, _) = crate::section_jacobian(&bare, &mut data, &q, 0, 0.3).unwrap();
        let normal = Vec3::new(0.05, 0.02, 1.0).normalize();
        // The tip's surface 2e-4 m into the table.
        let point = tip.translation - normal * (0.01 - 2e-4);
        for (friction, by) in [(0.5, 1e-7), (0.05, 3e-4)] {
            let table = Obstacle::new("table", Shape::Plane { point, normal })
                .friction(friction)
                .restitution(0.3);
            let model = bare
                .clone()
                .with_contact(vec![table], ContactSettings::default())
                .unwrap();
            let what = format!("arm, friction {friction}");
            let (stick, slip) = check(&model, &q, &qd, &shifted(&q, by), &what);
            assert!(
                if by < 1e-6 { stick > 0 } else { slip > 0 },
                "{what}: {stick} {slip}"
            );
        }
    }

    /// An arm on a prescribed revolute joint sweeping it over a table (the
    /// joint has no coordinate but moves: its rate enters `∂ṗ/∂q` through
    /// the frames' twists, CT12), sticking and sliding.
    #[test]
    fn an_arm_swept_over_a_table_by_a_prescribed_joint() {
        use crate::model::{Curve, Prescribed};
        for (friction, by) in [(0.5, 1e-7), (0.05, 3e-4)] {
            let sweep = Prescribed::new(vec![Curve::Sine {
                amplitude: 0.1,
                frequency: 1.0,
                phase: 0.0,
                offset: 0.0,
            }]);
            let joint = Joint::new(JointKind::Revolute { axis: Vec3::z() }).with_prescribed(sweep);
            let arm = Rod::builder(0.3)
                .pieces(4)
                .strains(Strain::ALL)
                .base(Pose::new(
                    softrod_lie::Mat3::identity(),
                    Vec3::new(0.0, 0.0, 0.0098),
                ))
                .circle(0.01)
                .material(silicone());
            let table = Obstacle::new(
                "table",
                Shape::Plane {
                    point: Vec3::zeros(),
                    normal: Vec3::z(),
                },
            )
            .friction(friction);
            let model = Model::builder()
                .rod_on(arm, Attachment::world_joint(joint))
                .gravity([0.0, 0.0, -9.81])
                .build()
                .unwrap()
                .with_contact(vec![table], ContactSettings::default())
                .unwrap();
            let n = model.n_dof();
            let q = wiggle(n, 1e-5, 1.3);
            let qd = wiggle(n, 0.05, 0.7);
            let what = format!("swept arm, friction {friction}");
            let (stick, slip) = check(&model, &q, &qd, &shifted(&q, by), &what);
            assert!(
                if by < 1e-6 { stick > 0 } else { slip > 0 },
                "{what}: {stick} {slip}"
            );
        }
    }

    fn shifted(q: &[f64], by: f64) -> Vec<f64> {
        q.iter()
            .enumerate()
            .map(|(i, v)| v - by * ((i as f64) * 2.1).cos())
            .collect()
    }

    /// A ball on a free joint carrying a sphere obstacle (offset from its
    /// frame) with friction, pressed by a cantilever: the body's coordinates
    /// enter the relative motion and the reaction acts on it (CT12).
    #[test]
    fn a_rod_pressing_on_an_obstacle_carried_by_a_free_body() {
        for by in [1e-7, 3e-4] {
            let model = Model::builder()
                .rod(
                    Rod::builder(0.3)
                        .pieces(3)
                        .strains(Strain::ALL)
                        .circle(0.01)
                        .material(silicone()),
                )
                .body(
                    BodySpec::principal("ball", 0.2, [1e-3, 1.2e-3, 0.8e-3]),
                    Attachment::world_joint(Joint::new(JointKind::Free)),
                )
                .gravity([0.0, 0.0, -9.81])
                .build()
                .unwrap()
                .with_contact(
                    vec![
                        Obstacle::new(
                            "shell",
                            Shape::Sphere {
                                center: Vec3::new(0.25, 0.003, -0.0595),
                                radius: 0.05,
                            },
                        )
                        .on("ball")
                        .friction(0.6),
                    ],
                    ContactSettings::default(),
                )
                .unwrap();
            let n = model.n_dof();
            let q = wiggle(n, 1e-4, 1.3);
            // The contact moves at ~1 cm/s relative to the ball: its trial
            // force `k e + c v_t` stays within μ f_n under the law the
            // commit raised (CT15: c × √s). At 5 cm/s (this test before
            // CT15) the damping alone, 0.9 N against μ f_n = 0.25 N, slides.
            let qd = wiggle(n, 0.01, 0.7);
            let mut data = Data::new(&model);
            crate::commit_contact(&model, &mut data, 0.0, &shifted(&q, by), &qd).unwrap();
            let held = data
                .contact
                .as_ref()
                .unwrap()
                .holds
                .iter()
                .flatten()
                .flatten();
            let scale = held.fold(0.0, |m: f64, h| m.max(h.scale));
            assert!(scale > 3.0, "the raised law is the one checked: {scale}");
            let (stick, slip) = check(&model, &q, &qd, &shifted(&q, by), "carried obstacle");
            assert!(
                if by < 1e-6 { stick > 0 } else { slip > 0 },
                "{stick} {slip}"
            );
        }
    }

    fn crossing(friction: f64, tree: bool) -> Model {
        crossing_at(friction, tree, 1.2, Vec3::new(0.2, -0.15, 0.0195))
    }

    fn crossing_at(friction: f64, tree: bool, angle: f64, base_b: Vec3) -> Model {
        let rod = |name: &str, base: Pose| {
            Rod::builder(0.3)
                .name(name)
                .pieces(3)
                .strains(Strain::ALL)
                .base(base)
                .circle(0.01)
                .material(silicone())
        };
        let settings = ContactSettings {
            rods: true,
            friction,
            restitution: 0.4,
            ..Default::default()
        };
        let b = rod("b", placed(Vec3::z(), angle, base_b));
        let builder = Model::builder().rod(rod("a", Pose::identity()));
        let builder = if tree {
            builder.rod_on(b, Attachment::world_joint(Joint::new(JointKind::Free)))
        } else {
            builder.rod(b)
        };
        builder
            .gravity([0.0, 0.0, -9.81])
            .build()
            .unwrap()
            .with_contact(Vec::new(), settings)
            .unwrap()
    }

    /// Two crossing rods pressed together, frictionless, sticking and
    /// sliding, on the chain and on a tree (b on a free joint) (CT13–CT14).
    #[test]
    fn crossing_rods_pressed_together() {
        for tree in [false, true] {
            for (friction, by) in [(0.0, 0.0), (0.6, 1e-7), (0.05, 3e-4)] {
                let model = crossing(friction, tree);
                let n = model.n_dof();
                let q = wiggle(n, 1e-3, 1.3);
                let qd = wiggle(n, 0.02, 0.7);
                let what = format!("crossing, tree {tree}, friction {friction}");
                let (stick, slip) = check(&model, &q, &qd, &shifted(&q, by), &what);
                if friction > 0.1 {
                    assert!(stick > 0, "{what}");
                } else if friction > 0.0 {
                    assert!(slip > 0, "{what}");
                }
            }
        }
    }

    /// Frictionless rod–rod contact is conservative (CT41): its force is the
    /// gradient of the penalty potential `Φ(d(q))` of the exact closest
    /// points' distance (CT8), so at rest (`q̇ = 0`, no damping) its
    /// stiffness `−∂τ_c/∂q` is a Hessian and must be symmetric. Two curved
    /// rods crossing, on the chain and on the tree, pressed to several depths
    /// and crossing angles. A force applied at points that are not the
    /// distance's closest points, or a law whose constants move with where
    /// the contact sits along a rod, breaks the symmetry.
    #[test]
    fn frictionless_pair_stiffness_is_symmetric() {
        for tree in [false, true] {
            for (angle, dz, amp) in [
                (1.2, 0.0195, 1e-3),
                (1.57, 0.0198, 2e-2),
                (1.0, 0.0195, 1e-2),
            ] {
                let model = crossing_at(0.0, tree, angle, Vec3::new(0.2, -0.15, dz));
                let n = model.n_dof();
                let q = wiggle(n, amp, 1.3);
                let qd = vec![0.0; n];
                let mut data = Data::new(&model);
                let (mut tau, mut dq, mut dqd) = (
                    DVector::zeros(n),
                    DMatrix::zeros(n, n),
                    DMatrix::zeros(n, n),
                );
                subtract_contact(
                    &model,
                    &mut data,
                    Forces::ALL,
                    0.0,
                    &q,
                    &qd,
                    &mut tau,
                    &mut dq,
                    &mut dqd,
                );
                let touching = data
                    .contact
                    .as_ref()
                    .unwrap()
                    .pairs
                    .as_ref()
                    .map_or(0, |p| p.active.len());
                assert!(touching > 0, "tree {tree}, angle {angle}: nothing touches");
                let asym = (&dq - dq.transpose()).abs().max();
                let scale = dq.abs().max();
                eprintln!("tree {tree}, angle {angle}: |K − Kᵀ| {asym:.2e} of |K| {scale:.2e}");
                assert!(
                    asym <= 1e-9 * scale,
                    "tree {tree}, angle {angle}: |K − Kᵀ| {asym:.3e} against |K| {scale:.3e}"
                );
            }
        }
    }

    /// Two tapered rods crossing, pressed together (CT14 with `∂r/∂s ≠ 0`):
    /// the gap and the law's radius move with the closest points. Both
    /// ways round (the law's radius on a, then on b), frictionless,
    /// sticking and sliding, on the chain and the tree; the analytic path
    /// is the one taken. Without the radius terms the columns of the
    /// coordinates that slide the closest points are off.
    #[test]
    #[allow(clippy::single_element_loop)]
    fn tapered_rods_crossing() {
        use softrod_mechanics::Section;
        let taper = |r0: f64, r1: f64| Section::TaperedCircle {
            radius_base: r0,
            radius_tip: r1,
        };
        for (sa, sb, law_on_a) in [(taper(0.012, 0.008), taper(0.009, 0.013), true)] {
            for tree in [false, true] {
                for (friction, by) in [(0.0, 0.0)] {
                    let rod = |name: &str, base: Pose, section: Section| {
                        Rod::builder(0.3)
                            .name(name)
                            .pieces(3)
                            .strains(Strain::ALL)
                            .base(base)
                            .section(section)
                            .material(silicone())
                    };
                    let settings = ContactSettings {
                        rods: true,
                        friction,
                        restitution: 0.4,
                        ..Default::default()
                    };
                    let b = rod(
                        "b",
                        placed(Vec3::z(), 1.2, Vec3::new(0.2, -0.15, 0.0195)),
                        sb,
                    );
                    let builder = Model::builder().rod(rod("a", Pose::identity(), sa));
                    let builder = if tree {
                        builder.rod_on(b, Attachment::world_joint(Joint::new(JointKind::Free)))
                    } else {
                        builder.rod(b)
                    };
                    let model = builder
                        .gravity([0.0, 0.0, -9.81])
                        .build()
                        .unwrap()
                        .with_contact(Vec::new(), settings)
                        .unwrap();
                    let n = model.n_dof();
                    let q = wiggle(n, 1e-3, 1.3);
                    let qd = wiggle(n, 0.02, 0.7);
                    let what =
                        format!("tapered, law on a {law_on_a}, tree {tree}, friction {friction}");
                    let mut data = Data::new(&model);
                    contact_force(&model, &mut data, Forces::ALL, 0.0, &q, Some(&qd));
                    let w = data.contact.as_ref().unwrap();
                    let pw = w.pairs.as_ref().unwrap();
                    assert_eq!(pw.active.len(), 1, "{what}");
                    let c = &pw.active[0];
                    let rb = crate::model::pairs::radius_at(&model, c.b, c.sb);
                    assert_eq!(c.radius_a < rb, law_on_a, "{what}");
                    assert!(c.dr.norm() > 0.0, "{what}");
                    assert!(super::analytic_applies(&model, w), "{what}");
                    check(&model, &q, &qd, &shifted(&q, by), &what);
                }
            }
        }
    }

    /// The round end of rod b pressed on rod a from the side (a T): b's
    /// closest point is clamped at its end (`∂s_b/∂q = 0`, CT13), on the
    /// chain and the tree, frictionless and with friction.
    #[test]
    fn a_rod_end_pressed_on_another_rod() {
        use std::f64::consts::FRAC_PI_2;
        for tree in [false, true] {
            for (friction, by) in [(0.0, 0.0), (0.6, 1e-7), (0.05, 3e-4)] {
                let model = crossing_at(friction, tree, FRAC_PI_2, Vec3::new(0.15, -0.304, 0.0195));
                let n = model.n_dof();
                let q = wiggle(n, 1e-5, 1.3);
                let qd = wiggle(n, 0.02, 0.7);
                let what = format!("end on rod, tree {tree}, friction {friction}");
                check(&model, &q, &qd, &shifted(&q, by * 0.01), &what);
                let mut data = Data::new(&model);
                contact_force(&model, &mut data, Forces::ALL, 0.0, &q, Some(&qd));
                let pw = data.contact.as_ref().unwrap().pairs.as_ref().unwrap();
                assert_eq!(pw.active.len(), 1, "{what}");
                assert_eq!(pw.active[0].sb, 0.3, "{what}: clamped at b's end");
            }
        }
    }

    /// A rod curled into a tight helix touching itself a turn apart, with
    /// friction (CT13–CT14 on one rod).
    #[test]
    fn self_contact_of_a_curled_rod() {
        let r = 0.01;
        let rho = 0.05;
        let length = 2.0 * std::f64::consts::PI * rho * 1.25;
        // Turns 1.88 r apart: 0.12 r deep, inside the 15 % a run allows (CT15).
        let c = 1.88 * r / (2.0 * std::f64::consts::PI);
        let (kappa, tau) = (rho / (rho * rho + c * c), c / (rho * rho + c * c));
        for (friction, by) in [(0.0, 0.0), (0.5, 1e-7), (0.05, 3e-4)] {
            let model = Model::builder()
                .rod(
                    Rod::builder(length)
                        .pieces(12)
                        .strains(Strain::ALL)
                        .rest_strain(Vec6::new(tau, kappa, 0.0, 1.0, 0.0, 0.0))
                        .circle(r)
                        .material(silicone()),
                )
                .build()
                .unwrap()
                .with_contact(
                    Vec::new(),
                    ContactSettings {
                        self_contact: true,
                        friction,
                        ..Default::default()
                    },
                )
                .unwrap();
            let n = model.n_dof();
            let q = wiggle(n, 1e-4, 1.3);
            let qd = wiggle(n, 0.02, 0.7);
            check(
                &model,
                &q,
                &qd,
                &shifted(&q, by),
                &format!("self, friction {friction}"),
            );
        }
    }

    /// A tree of two rods on revolute joints of one hub body, the second
    /// crossing over the first and pressed onto it, with friction.
    #[test]
    fn a_tree_with_two_rods_touching() {
        let rod = |name: &str| {
            Rod::builder(0.3)
                .name(name)
                .pieces(3)
                .strains(Strain::ALL)
                .circle(0.01)
                .material(silicone())
        };
        let hub = || Joint::new(JointKind::Revolute { axis: Vec3::z() });
        let model = Model::builder()
            .body(
                BodySpec::principal("hub", 0.1, [1e-4, 1e-4, 1e-4]),
                Attachment::world_joint(Joint::new(JointKind::Revolute { axis: Vec3::x() })),
            )
            .rod_on(rod("a"), Attachment::to("hub", hub()))
            .rod_on(
                rod("b").base(placed(Vec3::z(), 1.4, Vec3::new(0.15, -0.15, 0.0195))),
                Attachment::to("hub", hub()),
            )
            .gravity([0.0, 0.0, -9.81])
            .build()
            .unwrap()
            .with_contact(
                Vec::new(),
                ContactSettings {
                    rods: true,
                    friction: 0.5,
                    ..Default::default()
                },
            )
            .unwrap();
        let n = model.n_dof();
        let q = wiggle(n, 1e-4, 1.3);
        let qd = wiggle(n, 0.02, 0.7);
        check(&model, &q, &qd, &shifted(&q, 1e-7), "tree of two rods");
    }
}
