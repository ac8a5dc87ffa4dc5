//! Contact in the equations of motion (docs/theory-contact.md CT1–CT6):
//! every contact point of every rod against every obstacle, the force law
//! of `crate::forces::contact` at each touching one, and the generalized
//! force `τ_contact = Σ J_relᵀ f` it adds — on the chain with the rods'
//! kinematics, on the tree with the frames of [`super::frames`] (joints,
//! parents and the bodies that carry obstacles).

use super::frames::{
    RowBlock, add_frame_columns, add_frame_wrench, add_prescribed_wrench, frame_state,
    inward_wrenches,
};
use super::pairs::Search;
use super::tree::outward;
use super::{Motion, Pass};
use crate::forces::Forces;
use crate::forces::contact::{Distance, Law, distance, force};
use crate::model::Model;
use crate::model::closure::{ResolvedFrame, Target};
use crate::model::contact::{Active, ContactWork, Sample};
use crate::model::data::Data;
use crate::model::tree::Tree;
use nalgebra::DMatrix;
use softrod_kinematics::Frame;
use softrod_lie::{Mat3, Mat6, PieceMaps, Pose, Vec3, Vec6, skew};

/// What one evaluation asks of contact.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Ask {
    /// Friction on (dynamics with moving drives).
    pub friction: bool,
}

impl Ask {
    pub(crate) fn of(forces: Forces, has_velocity: bool) -> Option<Self> {
        if forces.gravity_only {
            return None;
        }
        Some(Self {
            friction: has_velocity && forces.drives_move(),
        })
    }
}

/// The law of a rod point against obstacle `o` (CT3–CT5).
pub(crate) fn law(model: &Model, rod: usize, sample: usize, o: usize, friction: bool) -> Law {
    let smp = &model.contact.samples[rod][sample];
    let ob = &model.contact.obstacles[o];
    let g = model.gravity.map_or(0.0, |g| g.norm());
    Law::new(
        smp.mass,
        smp.radius,
        g,
        ob.restitution,
        if friction { ob.friction } else { 0.0 },
    )
}

/// The relative translational Jacobian (3 × n_dof, into `out`) of a rod
/// point against the obstacle's parent on a tree model: the rod's section
/// at `s` minus the body point at the same place (zero for the world).
/// Each frame's spatial columns on its path to the root go straight into
/// their point rows `J_p = J_v − [p]× J_ω` (the row operator
/// `[−[p]×, I]`). For the dense two-sided terms of the shifted solve
/// (CT17) and as the reference of the inward sweep (CT28).
pub(crate) fn tree_point_jacobian(
    model: &Model,
    data: &Data,
    q: &[f64],
    rod: usize,
    s: f64,
    body: Option<usize>,
    out: &mut DMatrix<f64>,
) -> Vec3 {
    let tree = model.tree.as_ref().expect("a tree model");
    let fs = frame_state(model, tree, data, &rod_frame(model, rod, s), q, None);
    let p = fs.pose.translation;
    let mut rows = Mat6::zeros();
    rows.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-skew(&p)));
    rows.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&Mat3::identity());
    let block = RowBlock {
        c: &rows,
        m: 3,
        row: 0,
        sign: 1.0,
    };
    out.fill(0.0);
    add_frame_columns(tree, data, &fs, block, out);
    if let Some(b) = body {
        let frame = ResolvedFrame {
            target: Target::Body {
                node: tree.body_nodes[b],
            },
            offset: Pose::identity(),
        };
        let fb = frame_state(model, tree, data, &frame, q, None);
        add_frame_columns(
            tree,
            data,
            &fb,
            RowBlock {
                sign: -1.0,
                ..block
            },
            out,
        );
    }
    p
}

/// Finds the contacts at `(q, q̇)` and their generalized force into
/// `work.tau` (`work.active` lists them). On a tree this runs an outward
/// sweep (the node poses and twists in `data.nodes` are this state's
/// afterwards). Arguments checked by the caller.
pub(crate) fn evaluate(
    model: &Model,
    data: &mut Data,
    work: &mut ContactWork,
    q: &[f64],
    qd: Option<&[f64]>,
    ask: Ask,
) {
    work.active.clear();
    work.tau.fill(0.0);
    let obstacles = !model.contact.obstacles.is_empty();
    match &model.tree {
        None => {
            update_chain(model, work, q, qd);
            if obstacles {
                evaluate_chain(model, work, qd, ask);
            }
        }
        Some(tree) => {
            outward(
                model,
                tree,
                data,
                Motion::new(q, qd, None),
                Pass::Inverse,
                Forces::ALL,
            );
            sample_poses(model, data, work, q);
            if obstacles {
                evaluate_tree(model, data, work, q, qd, ask);
            }
        }
    }
    if work.pairs.is_some() {
        super::pairs::evaluate_pairs(model, data, work, q, qd, ask, Search::All);
        let pairs = work.pairs.as_ref().expect("pair work");
        work.tau += &pairs.tau;
    }
}

/// The rods' kinematics at `(q, q̇)` into `work.kin` (chain models).
fn update_chain(model: &Model, work: &mut ContactWork, q: &[f64], qd: Option<&[f64]>) {
    for (r, rm) in model.rods.iter().enumerate() {
        let dofs = rm.dofs();
        work.kin[r]
            .update(
                &rm.spec.geometry,
                &q[dofs.clone()],
                qd.map(|v| &v[dofs.clone()]),
                None,
            )
            .expect("checked coordinates");
    }
}

/// Rod–rod contact alone at `(q, q̇)` into the pair work's `tau` (the
/// central differences of its Jacobian on the chain, CT11), looking at
/// the pairs `search` names. Nothing without rod–rod contact.
pub(crate) fn evaluate_pairs_only(
    model: &Model,
    data: &mut Data,
    work: &mut ContactWork,
    q: &[f64],
    qd: Option<&[f64]>,
    ask: Ask,
    search: Search,
) {
    if work.pairs.is_none() {
        return;
    }
    match &model.tree {
        None => update_chain(model, work, q, qd),
        Some(tree) => {
            outward(
                model,
                tree,
                data,
                Motion::new(q, qd, None),
                Pass::Inverse,
                Forces::ALL,
            );
            if search == Search::All {
                sample_poses(model, data, work, q);
            }
        }
    }
    super::pairs::evaluate_pairs(model, data, work, q, qd, ask, search);
}

/// The force at one touching point, pushed onto `work.active`; `None` if
/// the point is apart.
#[allow(clippy::too_many_arguments)]
fn touch(
    model: &Model,
    work: &mut ContactWork,
    rod: usize,
    sample: usize,
    o: usize,
    dist: &Distance,
    p: &Vec3,
    v: &Vec3,
    frame: &Pose,
    ask: Ask,
) -> bool {
    let radius = model.contact.samples[rod][sample].radius;
    let gap = dist.d - radius;
    if gap >= 0.0 {
        return false;
    }
    let n_obs = model.contact.obstacles.len();
    // The stiffness this contact's state holds (CT15), frozen in a step.
    let (scale, offset) = work.held(rod, sample * n_obs + o);
    let law = law(model, rod, sample, o, ask.friction).scaled(scale, offset);
    let stretch = if law.mu > 0.0 {
        work.anchors[rod][sample * n_obs + o].map(|a| p - frame.transform_point(&a))
    } else {
        None
    };
    let cf = force(&law, dist, radius, v, stretch);
    let tangential = stretch.map_or_else(Vec3::zeros, |e| e - dist.normal * dist.normal.dot(&e));
    work.active.push(Active {
        rod,
        sample,
        obstacle: o,
        point: *p,
        normal: dist.normal,
        gap,
        force: cf.f,
        dp: cf.dp,
        dv: cf.dv,
        sticking: cf.sticking,
        velocity: *v,
        stretch: tangential,
        k: law.k,
    });
    true
}

fn evaluate_chain(model: &Model, work: &mut ContactWork, qd: Option<&[f64]>, ask: Ask) {
    let world = Pose::identity();
    for (r, rm) in model.rods.iter().enumerate() {
        let g = &rm.spec.geometry;
        for (i, smp) in model.contact.samples[r].iter().enumerate() {
            let p = work.kin[r]
                .pose_at(g, smp.s)
                .expect("a sample lies on its rod")
                .translation;
            let mut v = None;
            for (o, ob) in model.contact.obstacles.iter().enumerate() {
                let dist = distance(&ob.shape, &world, &p);
                if dist.d - smp.radius >= 0.0 {
                    continue;
                }
                let vel = *v.get_or_insert_with(|| {
                    if qd.is_some() {
                        let eta = work.kin[r]
                            .velocity_at(g, smp.s, Frame::Mixed)
                            .expect("on the rod");
                        Vec3::new(eta[3], eta[4], eta[5])
                    } else {
                        Vec3::zeros()
                    }
                });
                if touch(model, work, r, i, o, &dist, &p, &vel, &world, ask) {
                    let f = work.active.last().expect("just pushed").force;
                    work.kin[r]
                        .jacobian_at(g, smp.s, Frame::Mixed, &mut work.jac[r])
                        .expect("on the rod");
                    let jac = &work.jac[r];
                    for c in 0..rm.n_dof() {
                        let col = jac.column(c);
                        work.tau[rm.dof_offset + c] +=
                            col[3] * f[0] + col[4] * f[1] + col[5] * f[2];
                    }
                }
            }
        }
    }
}

fn evaluate_tree(
    model: &Model,
    data: &Data,
    work: &mut ContactWork,
    q: &[f64],
    qd: Option<&[f64]>,
    ask: Ask,
) {
    let tree = model.tree.as_ref().expect("a tree model");
    for (r, samples) in model.contact.samples.iter().enumerate() {
        for (i, smp) in samples.iter().enumerate() {
            let p = work.poses[r][i].translation;
            if !near_an_obstacle(model, tree, data, &p, smp.radius) {
                continue;
            }
            let frame = sample_frame(tree, r, smp);
            let fs = frame_state(model, tree, data, &frame, q, qd);
            let p = fs.pose.translation;
            let vp = point_velocity(&fs.vel, &p);
            for (o, ob) in model.contact.obstacles.iter().enumerate() {
                let parent = model.contact.parents[o];
                let fb = parent.map(|b| {
                    frame_state(
                        model,
                        tree,
                        data,
                        &ResolvedFrame {
                            target: Target::Body {
                                node: tree.body_nodes[b],
                            },
                            offset: Pose::identity(),
                        },
                        q,
                        qd,
                    )
                });
                let (pose, vb) = match &fb {
                    None => (Pose::identity(), Vec3::zeros()),
                    Some(fb) => (fb.pose, point_velocity(&fb.vel, &p)),
                };
                let dist = distance(&ob.shape, &pose, &p);
                if dist.d - smp.radius >= 0.0 {
                    continue;
                }
                if touch(model, work, r, i, o, &dist, &p, &(vp - vb), &pose, ask) {
                    // The force on the rod's section, the opposite on the
                    // obstacle's body; projected with the others below (CT28).
                    let f = work.active.last().expect("just pushed").force;
                    let tau = work.tau.as_mut_slice();
                    add_frame_wrench(tree, &fs, &p, &f, &mut work.wrenches, tau);
                    if let Some(fb) = &fb {
                        add_frame_wrench(tree, fb, &p, &(-f), &mut work.wrenches, tau);
                    }
                }
            }
        }
    }
    inward_wrenches(tree, data, &mut work.wrenches, work.tau.as_mut_slice());
}

/// The world pose of every contact point of a tree model into
/// `work.poses` and every piece's stretch `|ν|` into `work.stretch`, after
/// the outward sweep at `q`: [`super::frames::frame_pose`]'s pose to the bit (the same
/// strain, exponential and compositions), with the strain and the
/// piece's `PieceMaps` built once per piece instead of once per point;
/// the strains and maps are kept in `work` for [`shared_pose`].
pub(crate) fn sample_poses(model: &Model, data: &Data, work: &mut ContactWork, q: &[f64]) {
    let tree = model.tree.as_ref().expect("a tree model");
    for (r, samples) in model.contact.samples.iter().enumerate() {
        let rm = &model.rods[r];
        let qr = &q[rm.dofs()];
        for (n, pc) in rm.spec.geometry.pieces().iter().enumerate() {
            let xi = pc.strain(qr);
            work.strains[r][n] = xi;
            work.stretch[r][n] = Vec3::new(xi[3], xi[4], xi[5]).norm();
            work.maps[r][n] = PieceMaps::new(&xi, None);
        }
        for (i, smp) in samples.iter().enumerate() {
            work.poses[r][i] = shared_pose(tree, data, work, r, smp.piece, smp.x);
        }
    }
}

/// The world pose of rod `rod`'s section at abscissa `x` of piece `piece`
/// from the piece maps [`sample_poses`] stored: `frame_pose` of that
/// section to the bit.
#[inline]
pub(crate) fn shared_pose(
    tree: &Tree,
    data: &Data,
    work: &ContactWork,
    rod: usize,
    piece: usize,
    x: f64,
) -> Pose {
    let (gl, _) = work.maps[rod][piece].exp_and_tangent_minus(x);
    let base = &data.nodes[tree.rod_nodes[rod][piece]].base_world;
    base.compose(&gl).compose(&Pose::identity())
}

/// The frame of contact point `smp` of rod `rod` on a tree model (its
/// piece and abscissa fixed with the model): [`rod_frame`] at `smp.s`.
pub(crate) fn sample_frame(tree: &Tree, rod: usize, smp: &Sample) -> ResolvedFrame {
    ResolvedFrame {
        target: Target::Rod {
            rod,
            piece: smp.piece,
            x: smp.x,
            node: tree.rod_nodes[rod][smp.piece],
        },
        offset: Pose::identity(),
    }
}

/// The frame of rod `rod`'s section at `s` \[m\] on a tree model.
pub(crate) fn rod_frame(model: &Model, rod: usize, s: f64) -> ResolvedFrame {
    let tree = model.tree.as_ref().expect("a tree model");
    let (piece, x) = model.rods[rod]
        .spec
        .geometry
        .locate(s)
        .expect("a contact point lies on its rod");
    ResolvedFrame {
        target: Target::Rod {
            rod,
            piece,
            x,
            node: tree.rod_nodes[rod][piece],
        },
        offset: Pose::identity(),
    }
}

/// Whether a tree model's contact sample may touch an obstacle: its gap at
/// the pose-only position `p` (`frame_pose`'s, from [`sample_poses`]) below a slack of `1e-9 (1 + |p|)`
/// m. Most samples touch nothing; this spares them [`frame_state`]'s twists
/// and column blocks (CT7). The slack covers the round-off between the
/// pose-only exponential and `frame_state`'s (the same D4 pose, its
/// coefficients from another series evaluation when a rate is given), so
/// every sample the full test finds touching passes this one, and the
/// contacts and forces are those of the full test alone.
fn near_an_obstacle(model: &Model, tree: &Tree, data: &Data, p: &Vec3, radius: f64) -> bool {
    let slack = 1e-9 * (1.0 + p.norm());
    model.contact.obstacles.iter().enumerate().any(|(o, ob)| {
        let pose = model.contact.parents[o].map_or(Pose::identity(), |b| {
            data.nodes[tree.body_nodes[b]].base_world
        });
        distance(&ob.shape, &pose, p).d - radius < slack
    })
}

/// The world wrench (spatial, at the world origin, angular first) of the
/// force `f` \[N\] at the world point `p` \[m\]: `(p × f, f)`.
pub(crate) fn point_wrench(p: &Vec3, f: &Vec3) -> Vec6 {
    let m = p.cross(f);
    Vec6::new(m.x, m.y, m.z, f.x, f.y, f.z)
}

/// The contacts' share of the prescribed joints' forces (CT18) into
/// `work.tau_p`: `Σ J_pᵀ f` over the touching points of the last
/// evaluation (`work.active` and the pairs'), each force at its rod's
/// centreline point, an obstacle's body and a pair's rod `b` feeling the
/// opposite. `J_p` are the prescribed joints' columns on each point's path
/// to the root; the node poses in `data.nodes` must be this state's (any
/// sweep at the same `q`). Zero without prescribed joints.
pub(crate) fn prescribed_share(model: &Model, data: &Data, work: &mut ContactWork, q: &[f64]) {
    work.tau_p.fill(0.0);
    let Some(tree) = &model.tree else {
        return;
    };
    if model.n_prescribed() == 0 {
        return;
    }
    let out = work.tau_p.as_mut_slice();
    for a in &work.active {
        let s = model.contact.samples[a.rod][a.sample].s;
        let fs = frame_state(model, tree, data, &rod_frame(model, a.rod, s), q, None);
        let w = point_wrench(&fs.pose.translation, &a.force);
        add_prescribed_wrench(tree, data, &fs, &w, out);
        if let Some(b) = model.contact.parents[a.obstacle] {
            let body = ResolvedFrame {
                target: Target::Body {
                    node: tree.body_nodes[b],
                },
                offset: Pose::identity(),
            };
            let fb = frame_state(model, tree, data, &body, q, None);
            add_prescribed_wrench(tree, data, &fb, &(-w), out);
        }
    }
    if let Some(pw) = &work.pairs {
        for c in &pw.active {
            for (rod, s, sign) in [(c.a, c.sa, 1.0), (c.b, c.sb, -1.0)] {
                let fs = frame_state(model, tree, data, &rod_frame(model, rod, s), q, None);
                let w = point_wrench(&fs.pose.translation, &(c.force * sign));
                add_prescribed_wrench(tree, data, &fs, &w, out);
            }
        }
    }
}

/// The velocity of the world point `p` of a frame with spatial twist
/// `twist` (angular first, velocity of the point at the origin).
pub(crate) fn point_velocity(twist: &softrod_lie::Vec6, p: &Vec3) -> Vec3 {
    let w = Vec3::new(twist[0], twist[1], twist[2]);
    let v = Vec3::new(twist[3], twist[4], twist[5]);
    v + w.cross(p)
}

/// The world pose of obstacle `o`'s parent at the last evaluation (the
/// world, or its body's frame from `data.nodes`).
pub(crate) fn parent_pose(model: &Model, data: &Data, o: usize) -> Pose {
    match (model.contact.parents[o], &model.tree) {
        (Some(b), Some(tree)) => data.nodes[tree.body_nodes[b]].base_world,
        _ => Pose::identity(),
    }
}

#[cfg(test)]
#[path = "contact_tests.rs"]
mod tests;
