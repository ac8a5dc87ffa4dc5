//! Contact in the equations of motion (docs/theory-contact.md CT1–CT6):
//! every contact point of every rod against every obstacle, the force law
//! of `crate::forces::contact` at each touching one, and the generalized
//! force `τ_contact = Σ J_relᵀ f` it adds — on the chain with the rods'
//! kinematics, on the tree with the frames of [`super::frames`] (joints,
//! parents and the bodies that carry obstacles).

use super::frames::{RowBlock, add_frame_columns, add_prescribed_wrench, frame_state};
use super::pairs::Search;
use super::tree::outward;
use super::{Motion, Pass};
use crate::forces::Forces;
use crate::forces::contact::{Distance, Law, distance, force};
use crate::model::Model;
use crate::model::closure::{ResolvedFrame, Target};
use crate::model::contact::{Active, ContactWork};
use crate::model::data::Data;
use nalgebra::DMatrix;
use softrod_kinematics::Frame;
use softrod_lie::{Mat6, Pose, Vec3, Vec6, skew};

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

/// The translational Jacobian of the world point `p` moving with a frame
/// whose spatial Jacobian is `spatial` (6 × n, angular rows first):
/// `J_p = J_v − [p]× J_ω`, added with `sign` into `out` (3 × n).
fn point_rows(spatial: &DMatrix<f64>, p: &Vec3, sign: f64, out: &mut DMatrix<f64>) {
    let px = skew(p);
    for c in 0..spatial.ncols() {
        let w = Vec3::new(spatial[(0, c)], spatial[(1, c)], spatial[(2, c)]);
        let v = Vec3::new(spatial[(3, c)], spatial[(4, c)], spatial[(5, c)]);
        let j = v - px * w;
        for r in 0..3 {
            out[(r, c)] += sign * j[r];
        }
    }
}

/// The relative translational Jacobian (3 × n_dof, into `out`) of a rod
/// point against the obstacle's parent on a tree model: the rod's section
/// at `s` minus the body point at the same place (zero for the world).
#[allow(clippy::too_many_arguments)]
pub(crate) fn tree_point_jacobian(
    model: &Model,
    data: &Data,
    work: &mut ContactWork,
    q: &[f64],
    rod: usize,
    s: f64,
    body: Option<usize>,
    out: &mut DMatrix<f64>,
) -> Vec3 {
    let tree = model.tree.as_ref().expect("a tree model");
    let (piece, x) = model.rods[rod]
        .spec
        .geometry
        .locate(s)
        .expect("a contact sample lies on its rod");
    let frame = ResolvedFrame {
        target: Target::Rod {
            rod,
            piece,
            x,
            node: tree.rod_nodes[rod][piece],
        },
        offset: Pose::identity(),
    };
    let fs = frame_state(model, tree, data, &frame, q, None);
    let identity = Mat6::identity();
    let block = RowBlock {
        c: &identity,
        m: 6,
        row: 0,
        sign: 1.0,
    };
    work.dense.fill(0.0);
    add_frame_columns(tree, data, &fs, block, &mut work.dense);
    let p = fs.pose.translation;
    out.fill(0.0);
    point_rows(&work.dense, &p, 1.0, out);
    if let Some(b) = body {
        let frame = ResolvedFrame {
            target: Target::Body {
                node: tree.body_nodes[b],
            },
            offset: Pose::identity(),
        };
        let fb = frame_state(model, tree, data, &frame, q, None);
        work.dense_body.fill(0.0);
        add_frame_columns(tree, data, &fb, block, &mut work.dense_body);
        point_rows(&work.dense_body, &p, -1.0, out);
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
    let mut jrel = std::mem::take(&mut work.jrel);
    for (r, rm) in model.rods.iter().enumerate() {
        let g = &rm.spec.geometry;
        for (i, smp) in model.contact.samples[r].iter().enumerate() {
            let (piece, x) = g.locate(smp.s).expect("a sample lies on its rod");
            let frame = ResolvedFrame {
                target: Target::Rod {
                    rod: r,
                    piece,
                    x,
                    node: tree.rod_nodes[r][piece],
                },
                offset: Pose::identity(),
            };
            let fs = frame_state(model, tree, data, &frame, q, qd);
            let p = fs.pose.translation;
            let vp = point_velocity(&fs.vel, &p);
            for (o, ob) in model.contact.obstacles.iter().enumerate() {
                let parent = model.contact.parents[o];
                let (pose, vb) = match parent {
                    None => (Pose::identity(), Vec3::zeros()),
                    Some(b) => {
                        let fb = frame_state(
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
                        );
                        (fb.pose, point_velocity(&fb.vel, &p))
                    }
                };
                let dist = distance(&ob.shape, &pose, &p);
                if dist.d - smp.radius >= 0.0 {
                    continue;
                }
                if touch(model, work, r, i, o, &dist, &p, &(vp - vb), &pose, ask) {
                    let f = work.active.last().expect("just pushed").force;
                    tree_point_jacobian(model, data, work, q, r, smp.s, parent, &mut jrel);
                    for c in 0..jrel.ncols() {
                        work.tau[c] +=
                            jrel[(0, c)] * f[0] + jrel[(1, c)] * f[1] + jrel[(2, c)] * f[2];
                    }
                }
            }
        }
    }
    work.jrel = jrel;
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
    let rod_frame = |rod: usize, s: f64| {
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
    };
    let wrench = |p: &Vec3, f: &Vec3| {
        let m = p.cross(f);
        Vec6::new(m.x, m.y, m.z, f.x, f.y, f.z)
    };
    let out = work.tau_p.as_mut_slice();
    for a in &work.active {
        let s = model.contact.samples[a.rod][a.sample].s;
        let fs = frame_state(model, tree, data, &rod_frame(a.rod, s), q, None);
        let w = wrench(&fs.pose.translation, &a.force);
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
                let fs = frame_state(model, tree, data, &rod_frame(rod, s), q, None);
                let w = wrench(&fs.pose.translation, &(c.force * sign));
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
