//! Tests of `pairs.rs` (a file of their own: the layout test's length bound).

// Test code only (the layout test reads no further than this marker).
#[cfg(test)]
use super::{Sections, before, candidates, could_touch, past};
use crate::algorithms::contact_force;
use crate::commit_contact;
use crate::forces::Forces;
use crate::model::pairs::PairAnchor;
use crate::model::pairs::{PairWork, SegmentBox};
use crate::model::{Attachment, Data, Joint, JointKind, Model, Rod};
use softrod_kinematics::Strain;
use softrod_lie::{Pose, Vec3, Vec6, exp_twist};
use softrod_mechanics::Material;
use softrod_mechanics::contact::ContactSettings;

/// A straight rod of `pieces` pieces along x, offset by `y`.
fn straight(name: &str, pieces: usize, y: f64) -> Rod {
    let material = Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .build()
        .unwrap();
    Rod::builder(0.4)
        .name(name)
        .pieces(pieces)
        .base(Pose::new(
            softrod_lie::Mat3::identity(),
            Vec3::new(0.0, y, 0.0),
        ))
        .circle(0.01)
        .material(material)
        .build()
        .unwrap()
}

/// `locate_near` is `RodGeometry::locate` to the bit for every guess of
/// the piece: at, just before and just past every piece boundary
/// (`past`, `before`), inside the pieces, and at the rod's ends.
#[test]
fn locate_near_is_locate() {
    let rod = straight("a", 7, 0.0);
    let g = &rod.geometry;
    let l = g.length();
    let mut at = vec![0.0, l, 0.5 * l, 1e-3 * l];
    for p in g.pieces() {
        for s in [p.start, p.end(), past(p.end(), l), before(p.start, l)] {
            at.push(s.clamp(0.0, l));
        }
        at.push(p.start + 0.37 * p.length);
    }
    for &s in &at {
        for n in 0..g.pieces().len() {
            assert_eq!(
                super::locate_near(g, n, s),
                g.locate(s).unwrap(),
                "s {s}, n {n}"
            );
        }
    }
}

/// The candidate pairs of a sweep along z (boxes spread along z, the
/// hanging rope) and along x are those of the x sweep the narrowphase
/// took them from before, in the same order: scattered boxes on two
/// rods with self contact, checked against that sweep written out.
#[test]
fn the_candidates_are_the_x_sweeps_in_its_order() {
    let settings = ContactSettings {
        rods: true,
        self_contact: true,
        ..Default::default()
    };
    let model = Model::builder()
        .rod(straight("a", 30, 0.0))
        .rod(straight("b", 30, 0.5))
        .build()
        .unwrap()
        .with_contact(vec![], settings)
        .unwrap();
    let mut pw = PairWork::new(&model).unwrap();
    let segs: Vec<usize> = model.contact.samples.iter().map(|s| s.len() - 1).collect();
    let mut state = 12345u64;
    let mut rnd = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for stretch in [Vec3::new(0.02, 0.03, 0.6), Vec3::new(0.3, 0.25, 0.3)] {
        pw.boxes.clear();
        for (rod, &n) in segs.iter().enumerate() {
            for seg in 0..n {
                let c = Vec3::new(rnd() * stretch.x, rnd() * stretch.y, rnd() * stretch.z);
                pw.boxes.push(SegmentBox {
                    rod,
                    seg,
                    center: c,
                    radius: 0.02 + 0.06 * rnd(),
                });
            }
        }
        pw.boxes
            .sort_unstable_by(|a, b| (a.center.x - a.radius).total_cmp(&(b.center.x - b.radius)));
        let mut expected = Vec::new();
        let n = pw.boxes.len();
        for i in 0..n {
            let bi = pw.boxes[i];
            let reach = bi.center.x + bi.radius;
            for j in i + 1..n {
                let bj = pw.boxes[j];
                if bj.center.x - bj.radius > reach {
                    break;
                }
                if (bi.center - bj.center).norm() > bi.radius + bj.radius
                    || !could_touch(&model, &bi, &bj)
                {
                    continue;
                }
                expected.push((i as u32, j as u32));
            }
        }
        candidates(&model, &mut pw);
        assert!(expected.len() > 20, "{} pairs", expected.len());
        assert_eq!(pw.candidates, expected, "spread {stretch:?}");
    }
}

/// The stretch `e = p_a(σ_a) − p_b(σ_b) − R_b(σ_b) o` of anchor `k`
/// at `q` (CT10), from the sections' poses alone.
fn stretch(model: &Model, data: &mut Data, q: &[f64], k: &PairAnchor) -> Vec3 {
    assert!(contact_force(model, data, Forces::ALL, 0.0, q, None));
    let work = data.contact.as_ref().unwrap();
    let sec = Sections {
        model,
        data,
        work,
        q,
        qd: None,
        shared: false,
    };
    let gb = sec.at(k.b, k.sb, false).pose;
    sec.at(k.a, k.sa, false).pose.translation - gb.translation - gb.rotation * k.offset
}

/// The stretch rate the stop location reads (CT30) against central
/// differences of the stretch along `q̇` at the committed anchor: two
/// crossing rods of all six strains, pressed together, anchored at
/// rest, then moved to a bent state with every coordinate moving —
/// their sections turn. On a chain model and on a tree (the upper rod
/// on a free joint). The closest points' relative velocity
/// `v_a(s_a) − v_b(s_b)` (what the location read before) misses `b`'s
/// section turning the anchor's offset `o ≈ (r_a + r_b) n`.
#[test]
fn the_pair_stretch_rate_matches_central_differences() {
    let r = 0.01;
    let material = Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .build()
        .unwrap();
    let rod = |name: &str, base: Pose| {
        Rod::builder(0.3)
            .name(name)
            .pieces(3)
            .strains(Strain::ALL)
            .base(base)
            .circle(r)
            .material(material)
    };
    let w = Vec3::z() * 1.2;
    let turned = exp_twist(1.0, &Vec6::new(w.x, w.y, w.z, 0.0, 0.0, 0.0)).rotation;
    for tree in [false, true] {
        let b = rod(
            "b",
            Pose::new(turned, Vec3::new(0.2, -0.15, 2.0 * r - 5e-4)),
        );
        let builder = Model::builder().rod(rod("a", Pose::identity()));
        let builder = if tree {
            builder.rod_on(b, Attachment::world_joint(Joint::new(JointKind::Free)))
        } else {
            builder.rod(b)
        };
        let settings = ContactSettings {
            rods: true,
            friction: 0.3,
            ..Default::default()
        };
        let model = builder
            .build()
            .unwrap()
            .with_contact(Vec::new(), settings)
            .unwrap();
        let n = model.n_dof();
        let mut data = Data::new(&model);
        let zero = vec![0.0; n];
        commit_contact(&model, &mut data, 0.0, &zero, &zero).unwrap();
        let anchors = &data
            .contact
            .as_ref()
            .unwrap()
            .pairs
            .as_ref()
            .unwrap()
            .anchors;
        assert_eq!(anchors.len(), 1, "tree {tree}: {anchors:?}");
        let k = anchors[0];
        // Bent a little (still touching, within the anchor's reach),
        // every coordinate moving.
        let q: Vec<f64> = (0..n).map(|i| 2e-3 * ((i as f64) * 1.3).sin()).collect();
        let qd: Vec<f64> = (0..n).map(|i| 0.5 * ((i as f64) * 0.7).cos()).collect();
        data.contact.as_mut().unwrap().pairs.as_mut().unwrap().rates = true;
        assert!(contact_force(
            &model,
            &mut data,
            Forces::ALL,
            0.0,
            &q,
            Some(&qd)
        ));
        let pw = data.contact.as_mut().unwrap().pairs.as_mut().unwrap();
        pw.rates = false;
        assert_eq!(pw.active.len(), 1, "tree {tree}");
        let c = pw.active[0];
        assert!(c.anchor.is_some(), "tree {tree}");
        let rate = c.stretch_rate;
        // The closest points' relative velocity at (q, q̇).
        let closest = {
            let work = data.contact.as_ref().unwrap();
            let sec = Sections {
                model: &model,
                data: &data,
                work,
                q: &q,
                qd: Some(&qd),
                shared: false,
            };
            sec.at(c.a, c.sa, true).velocity - sec.at(c.b, c.sb, true).velocity
        };
        let eps = 1e-6;
        let at = |sign: f64| -> Vec<f64> {
            q.iter().zip(&qd).map(|(x, v)| x + sign * eps * v).collect()
        };
        let reference = (stretch(&model, &mut data, &at(1.0), &k)
            - stretch(&model, &mut data, &at(-1.0), &k))
            / (2.0 * eps);
        let err = (rate - reference).norm();
        let off = (closest - reference).norm();
        eprintln!(
            "tree {tree}: rate {rate:?}, central differences {reference:?}, error {err:.2e}; closest points' v_a − v_b off by {off:.2e}"
        );
        assert!(
            err <= 1e-6 * reference.norm(),
            "tree {tree}: {rate:?} vs {reference:?}"
        );
        // The test tells the two apart (4.5 % and 1.7 % of the rate
        // here, 10⁴ times the tolerance of the check).
        assert!(off > 1e-2 * reference.norm(), "tree {tree}: {off}");
    }
}
