//! The O(N) shifted solve with the contact's stiffness and damping
//! (`ShiftedSolver::linearize_contact`, docs/theory-contact.md CT17)
//! against a dense solve of `M + a(K + K_c) + b(D + D_c)` assembled from
//! independent pieces: the dense `mass_matrix`, `stiffness_matrix`,
//! `damping_matrix`, and each contact's term from central differences of
//! what `Model::contacts_with` reports — for a frictionless flat contact
//! the force is `f_n n` with `n` fixed, so `J_wᵀ K_p J_w = −g_qᵀ ∂f_n/∂q`
//! and `J_wᵀ C_p J_w = −g_qᵀ ∂f_n/∂q̇` with `g_q = ∂gap/∂q` (the gap's
//! gradient is `nᵀJ_w`). Contacts at every contact point of the rods,
//! piece boundaries included, on a chain (one-sided blocks) and on a tree
//! whose body carries an obstacle pressing from above (two-sided: the
//! Woodbury part).

use nalgebra::{DMatrix, DVector};
use softrod_dynamics::{
    Attachment, BodySpec, Data, Joint, Model, Rod, ShiftedSolver, damping_matrix, mass_matrix,
    stiffness_matrix,
};
use softrod_kinematics::Strain;
use softrod_lie::Vec3;
use softrod_mechanics::Material;
use softrod_mechanics::contact::{Contactee, Obstacle, Shape};

fn silicone() -> Material {
    Material::builder()
        .density(1000.0)
        .young(1.0e6)
        .poisson(0.5)
        .viscosity(50.0)
        .build()
        .unwrap()
}

fn plane(z: f64, up: bool) -> Shape {
    Shape::Plane {
        point: Vec3::new(0.0, 0.0, z),
        normal: if up { Vec3::z() } else { -Vec3::z() },
    }
}

/// `(gap, normal force)` of every contact at `(q, q̇)`, in the model's order.
fn report(model: &Model, q: &[f64], qd: &[f64]) -> Vec<(f64, f64)> {
    let mut data = Data::new(model);
    model
        .contacts_with(&mut data, 0.0, q, qd)
        .unwrap()
        .iter()
        .map(|c| (c.gap, c.force.dot(&c.normal)))
        .collect()
}

/// `Σ −g_qᵀ (a ∂f_n/∂q + b ∂f_n/∂q̇)` by central differences.
fn contact_terms(model: &Model, q: &[f64], a: f64, b: f64) -> DMatrix<f64> {
    let n = model.n_dof();
    let zero = vec![0.0; n];
    let base = report(model, q, &zero);
    let m = base.len();
    let (mut gq, mut fq, mut fv) = (
        DMatrix::zeros(m, n),
        DMatrix::zeros(m, n),
        DMatrix::zeros(m, n),
    );
    let h = 1e-7;
    for j in 0..n {
        let mut x = q.to_vec();
        x[j] += h;
        let plus = report(model, &x, &zero);
        x[j] -= 2.0 * h;
        let minus = report(model, &x, &zero);
        let mut v = zero.clone();
        v[j] = h;
        let vplus = report(model, q, &v);
        v[j] = -h;
        let vminus = report(model, q, &v);
        assert!(plus.len() == m && minus.len() == m && vplus.len() == m && vminus.len() == m);
        for i in 0..m {
            gq[(i, j)] = (plus[i].0 - minus[i].0) / (2.0 * h);
            fq[(i, j)] = (plus[i].1 - minus[i].1) / (2.0 * h);
            fv[(i, j)] = (vplus[i].1 - vminus[i].1) / (2.0 * h);
        }
    }
    -(gq.transpose() * (fq * a + fv * b))
}

/// Solves a random right-hand side with the O(N) solver and checks it
/// against the dense reference; returns the number of contacts.
fn check(model: &Model, q: &[f64], label: &str) -> usize {
    let n = model.n_dof();
    let zero = vec![0.0; n];
    let contacts = model.contacts(0.0, q, &zero).unwrap();
    let mut run = Data::new(model);
    let mut solver = ShiftedSolver::new(model);
    let kept = solver
        .linearize_contact(model, &mut run, 0.0, q, &zero)
        .unwrap();
    assert_eq!(kept, contacts.len(), "{label}");
    for (a, b) in [(1e-6, 1e-3), (1e-4, 1e-2), (1e-2, 1e-1)] {
        let mut data = Data::new(model);
        let dense = mass_matrix(model, &mut data, q).unwrap().clone()
            + stiffness_matrix(model) * a
            + damping_matrix(model) * b
            + contact_terms(model, q, a, b);
        let r = DVector::from_fn(n, |i, _| ((i as f64) * 0.77 + 0.3).sin());
        solver.factor(model, q, a, b).unwrap();
        let mut x = r.as_slice().to_vec();
        solver.solve(model, &mut x).unwrap();
        let x = DVector::from_vec(x);
        let reference = dense.clone().lu().solve(&r).unwrap();
        let err = (&x - &reference).amax() / reference.amax();
        // The differences are good to ~1e-9 of the contact terms.
        assert!(err < 1e-6, "{label}, a = {a:e}, b = {b:e}: {err:e}");
        // And the contact matters at these shifts: M + aK + bD alone is far.
        solver.clear_contact();
        solver.factor(model, q, a, b).unwrap();
        let mut y = r.as_slice().to_vec();
        solver.solve(model, &mut y).unwrap();
        let off = (DVector::from_vec(y) - &reference).amax() / reference.amax();
        assert!(
            off > 1e-3,
            "{label}, a = {a:e}: contact negligible ({off:e})"
        );
        solver
            .linearize_contact(model, &mut run, 0.0, q, &zero)
            .unwrap();
    }
    contacts.len()
}

#[test]
fn a_chain_lying_on_a_table_solves_like_the_dense_matrix() {
    let r = 0.01;
    let model = Model::builder()
        .rod(
            Rod::builder(0.3)
                .pieces(4)
                .strains(Strain::ALL)
                .circle(r)
                .material(silicone()),
        )
        .gravity([0.0, 0.0, -9.81])
        .obstacle(Obstacle::new("table", plane(-0.995 * r, true)))
        .build()
        .unwrap();
    let n = model.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 2e-5 * ((i as f64) * 1.3).sin()).collect();
    let touching = check(&model, &q, "chain");
    // Every contact point of the rod but its clamped base: piece
    // boundaries among them.
    assert!(touching > 20, "{touching}");
}

#[test]
fn a_tree_with_a_body_pressing_from_above_solves_like_the_dense_matrix() {
    let r = 0.01;
    let model = Model::builder()
        .rod_on(
            Rod::builder(0.2)
                .name("arm")
                .pieces(3)
                .strains(Strain::ALL)
                .circle(r)
                .material(silicone()),
            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
        )
        .body(
            BodySpec::principal("lid", 0.05, [1e-5, 1e-5, 1e-5]),
            Attachment::world_joint(Joint::prismatic([0.0, 0.0, 1.0])),
        )
        .gravity([0.0, 0.0, -9.81])
        .obstacle(Obstacle::new("table", plane(-0.995 * r, true)))
        .obstacle(Obstacle::new("lid", plane(0.996 * r, false)).on("lid"))
        .build()
        .unwrap();
    let n = model.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 1e-5 * ((i as f64) * 1.3).sin()).collect();
    let contacts = model.contacts(0.0, &q, &vec![0.0; n]).unwrap();
    let on_lid = contacts
        .iter()
        .filter(|c| c.b == Contactee::Obstacle(1))
        .count();
    assert!(on_lid > 10, "{on_lid}");
    check(&model, &q, "tree with a body");
}

/// `−∂τ_c/∂q̇` of the generalized contact force `τ_c = ID(without
/// obstacles) − ID(with)` at `(q, q̇, 0)` by central differences, with `data`'s
/// friction anchors: the contact's damping `Σ J_wᵀ(−∂f/∂v)J_w` exactly (no
/// second-order kinematic term depends on `q̇`).
fn contact_damping(
    with: &Model,
    without: &Model,
    data: &Data,
    q: &[f64],
    qd: &[f64],
) -> DMatrix<f64> {
    let n = with.n_dof();
    let zero = vec![0.0; n];
    let (mut dw, mut dn) = (data.clone(), Data::new(without));
    let mut tau = |v: &[f64]| {
        softrod_dynamics::inverse_dynamics(with, &mut dw, 0.0, q, v, &zero)
            .unwrap()
            .clone()
            - softrod_dynamics::inverse_dynamics(without, &mut dn, 0.0, q, v, &zero).unwrap()
    };
    let mut out = DMatrix::zeros(n, n);
    let h = 1e-7;
    let mut v = qd.to_vec();
    for j in 0..n {
        v[j] = qd[j] + h;
        let plus = tau(&v);
        v[j] = qd[j] - h;
        let minus = tau(&v);
        v[j] = qd[j];
        // ID(with) − ID(without) = −τ_c: its slope is `D_c = −∂τ_c/∂q̇`.
        out.set_column(j, &((plus - minus) / (2.0 * h)));
    }
    out
}

/// CT26: a rod on a free joint sliding across a table with friction: the
/// sliding law's damping `−∂f/∂v` is not symmetric (the friction force
/// follows the normal velocity, `μ c u nᵀ`), and the tree's factorization
/// takes it whole. At `a = 0` the shifted matrix is `M + b(D + D_c)` with
/// no geometric term left out, so the O(N) solve must equal a dense LU of
/// `M + bD + b D_c`, `D_c` from central differences of the inverse
/// dynamics in `q̇` (independent of the contact law's derivatives).
#[test]
fn sliding_friction_damping_joins_the_tree_factorization_whole() {
    let r = 0.01;
    let build = |obstacle: bool| {
        let mut b = Model::builder()
            .rod_on(
                Rod::builder(0.2)
                    .name("rod")
                    .pieces(3)
                    .strains([Strain::Ky, Strain::Kz, Strain::Qx])
                    .circle(r)
                    .material(silicone()),
                Attachment::world_joint(Joint::new(softrod_dynamics::JointKind::Free)),
            )
            .gravity([0.0, 0.0, -9.81]);
        if obstacle {
            b = b.obstacle(Obstacle::new("table", plane(-0.995 * r, true)).friction(0.3));
        }
        b.build().unwrap()
    };
    let (model, free) = (build(true), build(false));
    let n = model.n_dof();
    let q: Vec<f64> = (0..n).map(|i| 1e-5 * ((i as f64) * 1.3).sin()).collect();
    // Anchored where the rod lies (CT5), then moving along the table and
    // into it: every touching point slides (`c |v_t| ≫ μ f_n`).
    let mut run = Data::new(&model);
    softrod_dynamics::commit_contact(&model, &mut run, 0.0, &q, &vec![0.0; n]).unwrap();
    let mut qd = vec![0.0; n];
    qd[3] = 0.05; // free joint: x velocity (after the three rotations)
    qd[5] = -0.002;
    qd[1] = 0.1;
    let dc = contact_damping(&model, &free, &run, &q, &qd);
    let skew = (&dc - dc.transpose()).amax() / dc.amax();
    assert!(
        skew > 1e-2,
        "the damping is not skew enough to test: {skew:e}"
    );
    let mut solver = ShiftedSolver::new(&model);
    solver.set_contact_whole(true);
    let kept = solver
        .linearize_contact(&model, &mut run, 0.0, &q, &qd)
        .unwrap();
    assert!(kept > 10, "{kept}");
    let r_vec = DVector::from_fn(n, |i, _| ((i as f64) * 0.77 + 0.3).sin());
    for b in [1e-4, 1e-3, 1e-2] {
        let mut data = Data::new(&model);
        let dense = mass_matrix(&model, &mut data, &q).unwrap().clone()
            + damping_matrix(&model) * b
            + &dc * b;
        let reference = dense.lu().solve(&r_vec).unwrap();
        solver.factor(&model, &q, 0.0, b).unwrap();
        let mut x = r_vec.as_slice().to_vec();
        solver.solve(&model, &mut x).unwrap();
        let err = (DVector::from_vec(x) - &reference).amax() / reference.amax();
        // The central differences of the sliding law are good to ~1e-6 of
        // the solution here (6.8e-7 at b = 1e-4, 1.2e-6 at 1e-3).
        assert!(err < 1e-5, "b = {b:e}: {err:e}");
        // With the geometric terms on (zero at a = 0) the blocks are CT17's
        // positive semi-definite symmetric parts: off by the skew damping.
        solver.set_geometric(&model, true).unwrap();
        solver.factor(&model, &q, 0.0, b).unwrap();
        let mut y = r_vec.as_slice().to_vec();
        solver.solve(&model, &mut y).unwrap();
        solver.set_geometric(&model, false).unwrap();
        let off = (DVector::from_vec(y) - &reference).amax() / reference.amax();
        eprintln!("b = {b:e}: whole {err:.2e}, PSD parts {off:.2e}");
        assert!(off > 100.0 * err, "b = {b:e}: {off:e} against {err:e}");
    }
}
