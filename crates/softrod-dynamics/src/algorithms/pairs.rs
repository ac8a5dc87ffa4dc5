//! Rod–rod and self contact in the equations of motion
//! (docs/theory-contact.md CT8–CT11): the broadphase over the segments of
//! the rods' contact-point polylines (bounding spheres of each segment's
//! swept surface, sort and sweep along x), the exact closest points of two
//! centreline arcs (segment–segment seed, Gauss–Newton on the two arc
//! lengths), the force law of `crate::forces::contact` at each touching
//! pair, and its generalized force `J_a(s_a)ᵀ f − J_b(s_b)ᵀ f`. On the
//! chain it reads the rods' kinematics in `ContactWork::kin`; on a tree the
//! node data of the last outward sweep.

use super::contact::{Ask, point_velocity, rod_frame, shared_pose};
use super::frames::{add_frame_wrench, frame_pose, frame_state, inward_wrenches};
use crate::forces::contact::{Distance, Law, closest_on_segments, force};
use crate::model::Model;
use crate::model::closure::{ResolvedFrame, Target};
use crate::model::contact::ContactWork;
use crate::model::data::Data;
use crate::model::pairs::{
    BROADPHASE_MARGIN, PairActive, PairWork, SegmentBox, exclusion, may_touch, radius_at,
    radius_slope,
};
use softrod_kinematics::{Frame, RodGeometry};
use softrod_lie::{Mat3, Pose, Vec3};

/// Iterations of the closest-point refinement (CT8); it stops earlier when
/// the step falls below `1e-14` of the rods' lengths.
const REFINE_ITERATIONS: usize = 30;

/// Where one evaluation reads the rods' sections: the chain's kinematics
/// or the tree's frames.
struct Sections<'a> {
    model: &'a Model,
    data: &'a Data,
    work: &'a ContactWork,
    q: &'a [f64],
    qd: Option<&'a [f64]>,
    /// On a tree: `work`'s piece strains and maps are this state's
    /// (`super::contact::sample_poses` ran), so a pose-only section is
    /// read from them.
    shared: bool,
}

/// A rod section as contact needs it: pose, the centreline's tangent
/// `∂p/∂s = R ν` (stretch included) and the point's velocity.
struct At {
    pose: Pose,
    tangent: Vec3,
    velocity: Vec3,
    /// The section's angular velocity, world axes (zero without `q̇`).
    omega: Vec3,
}

/// `RodGeometry::locate(s)` when `s` is likely on piece `n` (a closest-point
/// iteration held to its piece, CT8): the same piece and abscissa, to the
/// bit, from the two boundaries of piece `n` instead of a search — and the
/// search itself when `s` is not on it.
fn locate_near(g: &RodGeometry, n: usize, s: f64) -> (usize, f64) {
    let pieces = g.pieces();
    let p = &pieces[n];
    // `locate` takes the first piece whose end is ≥ s (s within [0, L]).
    if s >= 0.0 && s <= g.length() && s <= p.end() && (n == 0 || pieces[n - 1].end() < s) {
        let x = if s >= p.end() {
            p.length
        } else {
            (s - p.start).clamp(0.0, p.length)
        };
        return (n, x);
    }
    g.locate(s).expect("a contact point lies on its rod")
}

impl Sections<'_> {
    fn at(&self, rod: usize, s: f64, velocity: bool) -> At {
        let (piece, x) = self.model.rods[rod]
            .spec
            .geometry
            .locate(s)
            .expect("a contact point lies on its rod");
        self.at_on(rod, piece, x, s, velocity)
    }

    /// [`Self::at`] with the piece and abscissa of `s` known.
    fn at_on(&self, rod: usize, piece: usize, x: f64, s: f64, velocity: bool) -> At {
        let rm = &self.model.rods[rod];
        let g = &rm.spec.geometry;
        match &self.model.tree {
            None => {
                let kin = &self.work.kin[rod];
                let pose = kin.pose_at(g, s).expect("on the rod");
                let xi = kin.strains()[piece];
                let (velocity, omega) = match (velocity, self.qd) {
                    (true, Some(_)) => {
                        let eta = kin.velocity_at(g, s, Frame::Mixed).expect("on the rod");
                        (
                            Vec3::new(eta[3], eta[4], eta[5]),
                            Vec3::new(eta[0], eta[1], eta[2]),
                        )
                    }
                    _ => (Vec3::zeros(), Vec3::zeros()),
                };
                At {
                    tangent: pose.rotation * Vec3::new(xi[3], xi[4], xi[5]),
                    pose,
                    velocity,
                    omega,
                }
            }
            Some(tree) => {
                let frame = ResolvedFrame {
                    target: Target::Rod {
                        rod,
                        piece,
                        x,
                        node: tree.rod_nodes[rod][piece],
                    },
                    offset: Pose::identity(),
                };
                let qd = if velocity { self.qd } else { None };
                let xi = if self.shared {
                    self.work.strains[rod][piece]
                } else {
                    g.strain(piece, &self.q[rm.dofs()])
                };
                if qd.is_none() {
                    // Positions and tangents only (the broadphase, the
                    // closest points): the pose alone, the same bits.
                    let pose = if self.shared {
                        shared_pose(tree, self.data, self.work, rod, piece, x)
                    } else {
                        frame_pose(self.model, self.data, &frame, self.q)
                    };
                    return At {
                        tangent: pose.rotation * Vec3::new(xi[3], xi[4], xi[5]),
                        pose,
                        velocity: Vec3::zeros(),
                        omega: Vec3::zeros(),
                    };
                }
                let fs = frame_state(self.model, tree, self.data, &frame, self.q, qd);
                At {
                    tangent: fs.pose.rotation * Vec3::new(xi[3], xi[4], xi[5]),
                    velocity: if qd.is_some() {
                        point_velocity(&fs.vel, &fs.pose.translation)
                    } else {
                        Vec3::zeros()
                    },
                    omega: if qd.is_some() {
                        Vec3::new(fs.vel[0], fs.vel[1], fs.vel[2])
                    } else {
                        Vec3::zeros()
                    },
                    pose: fs.pose,
                }
            }
        }
    }
}

/// Which pairs an evaluation looks at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Search {
    /// All: the broadphase over every segment.
    All,
    /// Only the segment pairs that seeded the pairs touching when
    /// [`seed_differences`] was called (the central differences of CT11:
    /// a pair that does not touch there adds nothing to the Jacobian).
    Seeded,
}

/// Keeps the seeds of the pairs touching now for [`Search::Seeded`].
pub(crate) fn seed_differences(work: &mut ContactWork) {
    if let Some(pw) = work.pairs.as_mut() {
        let PairWork {
            active, fd_seeds, ..
        } = &mut **pw;
        fd_seeds.clear();
        fd_seeds.extend(active.iter().map(|c| c.seeds));
    }
}

/// The touching pairs at `(q, q̇)` and their generalized force into
/// `pairs.tau` (`pairs.active` lists them). The chain's kinematics in
/// `work.kin`, or the tree's node data in `data` (and for [`Search::All`]
/// the sample poses of `super::contact::sample_poses`), must be this
/// state's.
pub(crate) fn evaluate_pairs(
    model: &Model,
    data: &Data,
    work: &mut ContactWork,
    q: &[f64],
    qd: Option<&[f64]>,
    ask: Ask,
    search: Search,
) {
    let Some(mut pw) = work.pairs.take() else {
        return;
    };
    pw.active.clear();
    pw.tau.fill(0.0);
    pw.narrow_tests = 0;
    if search == Search::Seeded {
        let sec = Sections {
            model,
            data,
            work,
            q,
            qd,
            shared: false,
        };
        for k in 0..pw.fd_seeds.len() {
            let (ba, bb) = pw.fd_seeds[k];
            for b in [ba, bb] {
                let smp = &model.contact.samples[b.rod];
                for i in [b.seg, b.seg + 1] {
                    pw.points[b.rod][i] = sec.at(b.rod, smp[i].s, false).pose.translation;
                }
            }
            narrowphase(model, &sec, &mut pw, &ba, &bb, ask);
        }
    } else {
        let sec = Sections {
            model,
            data,
            work,
            q,
            qd,
            shared: model.tree.is_some(),
        };
        broadphase(model, &sec, &mut pw);
        candidates(model, &mut pw);
        for k in 0..pw.candidates.len() {
            let (i, j) = pw.candidates[k];
            let (bi, bj) = (pw.boxes[i as usize], pw.boxes[j as usize]);
            pw.narrow_tests += 1;
            narrowphase(model, &sec, &mut pw, &bi, &bj, ask);
        }
    }
    // The generalized force: J_a(s_a)ᵀ f − J_b(s_b)ᵀ f — on a tree as the
    // forces ±f at the two sections, projected in one inward sweep (CT28).
    match &model.tree {
        None => {
            for k in 0..pw.active.len() {
                let c = pw.active[k];
                for (rod, s, sign) in [(c.a, c.sa, 1.0), (c.b, c.sb, -1.0)] {
                    let f = c.force * sign;
                    let rm = &model.rods[rod];
                    work.kin[rod]
                        .jacobian_at(&rm.spec.geometry, s, Frame::Mixed, &mut work.jac[rod])
                        .expect("on the rod");
                    let jac = &work.jac[rod];
                    for col in 0..rm.n_dof() {
                        let jc = jac.column(col);
                        pw.tau[rm.dof_offset + col] += jc[3] * f[0] + jc[4] * f[1] + jc[5] * f[2];
                    }
                }
            }
        }
        Some(tree) => {
            let tau = pw.tau.as_mut_slice();
            for c in &pw.active {
                for (rod, s, sign) in [(c.a, c.sa, 1.0), (c.b, c.sb, -1.0)] {
                    let fs = frame_state(model, tree, data, &rod_frame(model, rod, s), q, None);
                    let (p, f) = (fs.pose.translation, c.force * sign);
                    add_frame_wrench(tree, &fs, &p, &f, &mut work.wrenches, tau);
                }
            }
            inward_wrenches(tree, data, &mut work.wrenches, tau);
        }
    }
    work.pairs = Some(pw);
}

/// The contact points' positions, each segment's true arc length and the
/// bounding sphere of its swept surface (an arc of length `ℓ` between two
/// points lies within `ℓ/2` of their midpoint), sorted by lowest x.
fn broadphase(model: &Model, sec: &Sections, pw: &mut PairWork) {
    pw.boxes.clear();
    for (r, samples) in model.contact.samples.iter().enumerate() {
        match &model.tree {
            None => {
                for (i, smp) in samples.iter().enumerate() {
                    pw.points[r][i] = sec.at(r, smp.s, false).pose.translation;
                }
            }
            // This evaluation's poses, filled after its outward sweep.
            Some(_) => {
                for (p, pose) in pw.points[r].iter_mut().zip(&sec.work.poses[r]) {
                    *p = pose.translation;
                }
            }
        }
        for i in 0..samples.len().saturating_sub(1) {
            let (s0, s1) = (samples[i].s, samples[i + 1].s);
            let piece = samples[i].segment_piece;
            let stretch = match &model.tree {
                None => {
                    let xi = sec.work.kin[r].strains()[piece];
                    Vec3::new(xi[3], xi[4], xi[5]).norm()
                }
                Some(_) => sec.work.stretch[r][piece],
            };
            let arc = stretch * (s1 - s0);
            pw.arcs[r][i] = arc;
            let radius = samples[i].radius.max(samples[i + 1].radius);
            pw.boxes.push(SegmentBox {
                rod: r,
                seg: i,
                center: 0.5 * (pw.points[r][i] + pw.points[r][i + 1]),
                radius: 0.5 * arc + radius * (1.0 + BROADPHASE_MARGIN),
            });
        }
    }
    pw.boxes
        .sort_unstable_by(|a, b| (a.center.x - a.radius).total_cmp(&(b.center.x - b.radius)));
}

/// The segment pairs the narrowphase tests into `pw.candidates`: bounding
/// spheres overlapping and [`could_touch`], in the order of a sweep along
/// x over `pw.boxes` (sorted by lowest x) — pairs `(i, j)`, `i < j`, by
/// `i` then `j`, the order that fixes the touching pairs' list and its
/// sums. The sweep runs along y or z where the boxes' centres spread over
/// more than four times their spread in x: a
/// rope hanging along z has every box overlapping every other in x, where
/// a sweep along x tests all `n²/2` pairs. A pair the x sweep would pass
/// over (`j`'s lowest x beyond `i`'s highest) is passed over here too, so
/// the pairs are the x sweep's exactly.
fn candidates(model: &Model, pw: &mut PairWork) {
    pw.candidates.clear();
    let n = pw.boxes.len();
    let keep = |bi: &SegmentBox, bj: &SegmentBox| {
        // `norm > sum` is false on NaN too, as in the x sweep's test.
        let apart = (bi.center - bj.center).norm() > bi.radius + bj.radius;
        !apart && could_touch(model, bi, bj)
    };
    let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
    for b in &pw.boxes {
        lo = lo.inf(&b.center);
        hi = hi.sup(&b.center);
    }
    let spread = hi - lo;
    // Another axis only where it thins the sweep by far: its own sort and
    // the candidates' are not free.
    let widest = if spread.y >= spread.z { 1 } else { 2 };
    let axis = if spread[widest] > 4.0 * spread.x {
        widest
    } else {
        0
    };
    if axis == 0 || !spread.iter().all(|v| v.is_finite()) {
        for i in 0..n {
            let bi = pw.boxes[i];
            let reach = bi.center.x + bi.radius;
            for j in i + 1..n {
                let bj = pw.boxes[j];
                if bj.center.x - bj.radius > reach {
                    break;
                }
                if keep(&bi, &bj) {
                    pw.candidates.push((i as u32, j as u32));
                }
            }
        }
        return;
    }
    pw.order.clear();
    pw.order.extend(
        pw.boxes
            .iter()
            .enumerate()
            .map(|(i, b)| (b.center[axis] - b.radius, i as u32)),
    );
    pw.order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    for a in 0..n {
        let ia = pw.order[a].1;
        let ba = pw.boxes[ia as usize];
        let reach = ba.center[axis] + ba.radius;
        for b in a + 1..n {
            let (low, ib) = pw.order[b];
            if low > reach {
                break;
            }
            let (i, j) = if ia < ib { (ia, ib) } else { (ib, ia) };
            let (bi, bj) = (pw.boxes[i as usize], pw.boxes[j as usize]);
            if bj.center.x - bj.radius > bi.center.x + bi.radius {
                continue;
            }
            if keep(&bi, &bj) {
                pw.candidates.push((i, j));
            }
        }
    }
    pw.candidates.sort_unstable();
}

/// Whether any points of the two segments may touch (CT9): rods and self
/// contact switched on, and on one rod not every pair of their points
/// within the exclusion arc.
fn could_touch(model: &Model, a: &SegmentBox, b: &SegmentBox) -> bool {
    let settings = &model.contact.settings;
    if a.rod != b.rod {
        return settings.rods;
    }
    if !settings.self_contact {
        return false;
    }
    let smp = &model.contact.samples[a.rod];
    let (lo, hi) = if a.seg < b.seg { (a, b) } else { (b, a) };
    let farthest = smp[hi.seg + 1].s - smp[lo.seg].s;
    let r = smp[lo.seg..=lo.seg + 1]
        .iter()
        .chain(&smp[hi.seg..=hi.seg + 1])
        .fold(f64::INFINITY, |m, x| m.min(x.radius));
    farthest >= exclusion(r, r)
}

/// The exact closest points of the two segments' arcs and, if the surfaces
/// overlap there, the force of the pair (CT8, CT10, CT11).
fn narrowphase(
    model: &Model,
    sec: &Sections,
    pw: &mut PairWork,
    ba: &SegmentBox,
    bb: &SegmentBox,
    ask: Ask,
) {
    let (pa, pb) = (&pw.points[ba.rod], &pw.points[bb.rod]);
    let (sa_, sb_) = (
        &model.contact.samples[ba.rod],
        &model.contact.samples[bb.rod],
    );
    let (t, u) = closest_on_segments(&pa[ba.seg], &pa[ba.seg + 1], &pb[bb.seg], &pb[bb.seg + 1]);
    let mut sa = sa_[ba.seg].s + t * (sa_[ba.seg + 1].s - sa_[ba.seg].s);
    let mut sb = sb_[bb.seg].s + u * (sb_[bb.seg + 1].s - sb_[bb.seg].s);
    let (la, lb) = (
        model.rods[ba.rod].spec.geometry.length(),
        model.rods[bb.rod].spec.geometry.length(),
    );
    let tol = 1e-14 * (la + lb);
    // Each parameter stays on the piece of its seed segment, where the
    // centreline is smooth (one strain): across a piece boundary the
    // tangent may turn (a jump of shear), the distance then has a corner
    // there, and an iteration allowed to cross it bounces from side to side
    // without converging. A corner that is the closest point is reached
    // from both sides as a clamp and kept once (the test below).
    let (a_lo, a_hi, piece_a) =
        piece_span(model, ba.rod, 0.5 * (sa_[ba.seg].s + sa_[ba.seg + 1].s));
    let (b_lo, b_hi, piece_b) =
        piece_span(model, bb.rod, 0.5 * (sb_[bb.seg].s + sb_[bb.seg + 1].s));
    let (ga_, gb_) = (
        &model.rods[ba.rod].spec.geometry,
        &model.rods[bb.rod].spec.geometry,
    );
    let on_a = |s: f64| {
        let (n, x) = locate_near(ga_, piece_a, s);
        sec.at_on(ba.rod, n, x, s, false)
    };
    let on_b = |s: f64| {
        let (n, x) = locate_near(gb_, piece_b, s);
        sec.at_on(bb.rod, n, x, s, false)
    };
    let (mut xa, mut xb) = (on_a(sa), on_b(sb));
    for _ in 0..REFINE_ITERATIONS {
        // Gauss–Newton on ½|p_a(s_a) − p_b(s_b)|², each parameter kept on
        // its piece (a rod's round end: a clamped end is the closest point).
        let w = xa.pose.translation - xb.pose.translation;
        let (ta, tb) = (xa.tangent, xb.tangent);
        let (haa, hab, hbb) = (ta.dot(&ta), -ta.dot(&tb), tb.dot(&tb));
        let (ga, gb) = (w.dot(&ta), -w.dot(&tb));
        let det = haa * hbb - hab * hab;
        let (mut da, mut db) = if det > 1e-10 * haa * hbb {
            ((-ga * hbb + gb * hab) / det, (-gb * haa + ga * hab) / det)
        } else {
            // Parallel arcs: the closest point of a to b's point.
            (-ga / haa, 0.0)
        };
        let na = (sa + da).clamp(a_lo, a_hi);
        if na != sa + da {
            da = na - sa;
            db = -(gb + hab * da) / hbb;
        }
        let nb = (sb + db).clamp(b_lo, b_hi);
        if nb != sb + db {
            db = nb - sb;
            let na = (sa - (ga + hab * db) / haa).clamp(a_lo, a_hi);
            da = na - sa;
        }
        sa += da;
        sb += db;
        xa = on_a(sa);
        xb = on_b(sb);
        if da.abs() + db.abs() <= tol {
            break;
        }
    }
    // A parameter held at an interior piece boundary is a closest point
    // only if the distance does not fall on into the next piece (there the
    // seed of that piece finds the closest point itself): a corner.
    // Differences below the merge tolerance count as stationary.
    let w = xa.pose.translation - xb.pose.translation;
    let flat = |t: &Vec3| 0.5e-9 * (la + lb).min(1.0) * t.norm_squared();
    if sa == a_hi && a_hi < la {
        // d/ds_a ½|w|² = w·t_a; beyond the boundary, the next piece's t_a.
        let t = sec.at(ba.rod, past(a_hi, la), false).tangent;
        if w.dot(&t) < -flat(&t) {
            return;
        }
    }
    if sa == a_lo && a_lo > 0.0 {
        let t = sec.at(ba.rod, before(a_lo, la), false).tangent;
        if w.dot(&t) > flat(&t) {
            return;
        }
    }
    if sb == b_hi && b_hi < lb {
        let t = sec.at(bb.rod, past(b_hi, lb), false).tangent;
        if w.dot(&t) > flat(&t) {
            return;
        }
    }
    if sb == b_lo && b_lo > 0.0 {
        let t = sec.at(bb.rod, before(b_lo, lb), false).tangent;
        if w.dot(&t) < -flat(&t) {
            return;
        }
    }
    // One report per pair: a is the lower rod, or the lower s on one rod.
    let (a, b, sa, sb, xa, xb) = if (ba.rod, sa) <= (bb.rod, sb) {
        (ba.rod, bb.rod, sa, sb, xa, xb)
    } else {
        (bb.rod, ba.rod, sb, sa, xb, xa)
    };
    let (ra, rb) = (radius_at(model, a, sa), radius_at(model, b, sb));
    let w = xa.pose.translation - xb.pose.translation;
    let d = w.norm();
    let gap = d - ra - rb;
    if gap >= 0.0 || !may_touch(model, a, sa, b, sb, ra, rb) {
        return;
    }
    let same = 1e-9 * (ra + rb);
    if pw
        .active
        .iter()
        .any(|c| c.a == a && c.b == b && (c.sa - sa).abs() < same && (c.sb - sb).abs() < same)
    {
        return;
    }
    let normal = if d > 0.0 {
        w / d
    } else {
        let c = xa.tangent.cross(&xb.tangent);
        if c.norm() > 0.0 {
            c.normalize()
        } else {
            Vec3::z()
        }
    };
    let hessian = if d > 0.0 {
        (Mat3::identity() - normal * normal.transpose()) / d
    } else {
        Mat3::zeros()
    };
    let dist = Distance { d, normal, hessian };
    // The stiffness the pair's state holds (CT15), frozen in a step.
    let (scale, offset) = pw
        .holds
        .iter()
        .find(|h| h.matches(a, sa, b, sb, ra + rb))
        .map_or((1.0, 0.0), |h| (h.hold.scale, h.hold.offset));
    let law = pair_law(model, a, sa, b, sb, ra.min(rb), ask.friction).scaled(scale, offset);
    let anchor = if law.mu > 0.0 {
        pw.anchors.iter().copied().find(|k| {
            k.a == a && k.b == b && (k.sa - sa).abs() < ra + rb && (k.sb - sb).abs() < ra + rb
        })
    } else {
        None
    };
    let stretch = anchor.map(|k| {
        let pa = sec.at(a, k.sa, false).pose.translation;
        let gb = sec.at(b, k.sb, false).pose;
        pa - gb.translation - gb.rotation * k.offset
    });
    // The stretch's own rate (CT30), only for the stop location: the
    // relative velocity of its material points, `b`'s point turning with
    // its section (the closest points' `v_a − v_b` misses that turn, and
    // with the offset `o ≈ (r_a + r_b) n` a bending rod's `ω × R_b o` is
    // tangential and can outweigh it).
    let stretch_rate = match anchor {
        Some(k) if pw.rates => {
            let xa = sec.at(a, k.sa, true);
            let xb = sec.at(b, k.sb, true);
            xa.velocity - xb.velocity - xb.omega.cross(&(xb.pose.rotation * k.offset))
        }
        _ => Vec3::zeros(),
    };
    let va = sec.at(a, sa, true).velocity;
    let vb = sec.at(b, sb, true).velocity;
    let cf = force(&law, &dist, ra + rb, &(va - vb), stretch);
    // The law's radius moves with the closest point on a tapered rod
    // (CT14): its derivative by a central difference of the scalar law
    // (two force evaluations, only then; the branches of min and max held).
    let slope = if ra <= rb {
        radius_slope(model, a)
    } else {
        radius_slope(model, b)
    };
    let dr = if slope != 0.0 {
        let r = ra.min(rb);
        let h = 1e-4 * r;
        let at = |r: f64| {
            let law = pair_law(model, a, sa, b, sb, r, ask.friction).scaled(scale, offset);
            force(&law, &dist, ra + rb, &(va - vb), stretch).f
        };
        (at(r + h) - at(r - h)) / (2.0 * h)
    } else {
        Vec3::zeros()
    };
    pw.active.push(PairActive {
        a,
        sa,
        b,
        sb,
        point: xa.pose.translation,
        normal,
        gap,
        force: cf.f,
        sticking: cf.sticking,
        radius_a: ra,
        k: law.k,
        dr,
        seeds: (*ba, *bb),
        dw: cf.dp - cf.de,
        dv: cf.dv,
        de: cf.de,
        anchor,
        stretch: stretch.map_or(Vec3::zeros(), |e| e - normal * normal.dot(&e)),
        stretch_rate,
    });
}

/// The mass a contact point of rod `rod` at `s` stands for: that of the
/// nearest contact point (CT1).
/// The bounds \[m\] of the refinement on the piece of `rod` containing `s`
/// (a seed segment's midpoint: inside one piece): its end, and its start
/// moved [`past`] it, so that every evaluation on the piece reads this
/// piece's strain — a boundary belongs to the piece that ends there, and a
/// tangent read across a corner would make the iteration cycle.
fn piece_span(model: &Model, rod: usize, s: f64) -> (f64, f64, usize) {
    let g = &model.rods[rod].spec.geometry;
    let (n, x) = g.locate(s).expect("a seed lies on its rod");
    let l = g.length();
    let start = s - x;
    let end = start + g.pieces()[n].length;
    // Round-off of `s − x` must not leave a gap at the rod's ends.
    (
        if n == 0 { 0.0 } else { past(start, l) },
        if n + 1 == g.pieces().len() { l } else { end },
        n,
    )
}

/// An abscissa just past the piece boundary `s` \[m\] on a rod of length
/// `l`, where `Sections::at` reads the next piece: `10⁻¹²·l` on, well inside
/// the pairs' merge tolerance, so the two sides' clamps are one contact.
fn past(s: f64, l: f64) -> f64 {
    (s + 1e-12 * l).min(l)
}

/// Back from a start moved [`past`] its boundary: an abscissa where
/// `Sections::at` reads the piece before.
fn before(s: f64, l: f64) -> f64 {
    s - 1e-12 * l
}

pub(crate) fn mass_at(model: &Model, rod: usize, s: f64) -> f64 {
    let smp = &model.contact.samples[rod];
    let i = smp.partition_point(|x| x.s < s).min(smp.len() - 1);
    if i > 0 && (s - smp[i - 1].s) < (smp[i].s - s) {
        smp[i - 1].mass
    } else {
        smp[i].mass
    }
}

/// The law of a rod pair (CT11): the stiffness of the smaller side's mass
/// at the smaller radius, the damping of the reduced mass, the `[contact]`
/// restitution and friction.
pub(crate) fn pair_law(
    model: &Model,
    a: usize,
    sa: f64,
    b: usize,
    sb: f64,
    radius: f64,
    friction: bool,
) -> Law {
    let (ma, mb) = (mass_at(model, a, sa), mass_at(model, b, sb));
    let settings = &model.contact.settings;
    let g = model.gravity.map_or(0.0, |g| g.norm());
    Law::pair(
        ma.min(mb),
        ma * mb / (ma + mb),
        radius,
        g,
        settings.restitution,
        if friction { settings.friction } else { 0.0 },
    )
}

/// The world poses of the two anchored points of a pair, for the commit
/// of its friction anchor (CT10).
pub(crate) fn pair_poses(
    model: &Model,
    data: &Data,
    work: &ContactWork,
    q: &[f64],
    c: &PairActive,
) -> (Vec3, Pose) {
    let sec = Sections {
        model,
        data,
        work,
        q,
        qd: None,
        shared: false,
    };
    (
        sec.at(c.a, c.sa, false).pose.translation,
        sec.at(c.b, c.sb, false).pose,
    )
}

#[cfg(test)]
#[path = "pairs_tests.rs"]
mod tests;
