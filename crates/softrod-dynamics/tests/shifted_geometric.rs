//! The geometric stiffness in the O(N) shifted solve
//! (`ShiftedSolver::set_geometric`, docs/theory-contact.md CT19–CT23)
//! against a dense LU of `M + a(K + K_g) + bD`, `K_g = ∂G/∂q` from central
//! differences of `generalized_gravity` (`G = ∂V_g/∂q`, independent of the
//! recursion): exact on a chain of rigid bodies on revolute and universal
//! joints, and on PCS rods (a hanging rod on a spherical joint, a clamped
//! rod), where the within-piece second derivatives of the piece maps
//! (CT22) are what makes it exact.

mod common;

use common::{Lcg, soft_rod};
use nalgebra::{DMatrix, DVector};
use softrod_dynamics::{
    Attachment, BodySpec, Data, Joint, Model, ShiftedSolver, damping_matrix, generalized_gravity,
    mass_matrix, stiffness_matrix,
};
use softrod_kinematics::Strain;
use softrod_lie::{Mat3, Pose, Vec3};

/// `∂G/∂q` by central differences (step 1e-6).
fn gravity_hessian(model: &Model, q: &[f64]) -> DMatrix<f64> {
    let n = model.n_dof();
    let mut data = Data::new(model);
    let h = 1e-6;
    let mut k = DMatrix::zeros(n, n);
    for j in 0..n {
        let mut qp = q.to_vec();
        qp[j] += h;
        let gp = generalized_gravity(model, &mut data, &qp).unwrap();
        qp[j] -= 2.0 * h;
        let gm = generalized_gravity(model, &mut data, &qp).unwrap();
        k.set_column(j, &((gp - gm) / (2.0 * h)));
    }
    k
}

/// `(‖x − x_ref‖∞/‖x_ref‖∞` with the geometric terms, the same without)`
/// over the coordinates `rows` for a random right-hand side, `x_ref` the
/// dense LU solve of `M + a(K + K_g) + bD`.
fn gaps(model: &Model, q: &[f64], a: f64, b: f64) -> (f64, f64) {
    gaps_over(model, q, a, b, 0..model.n_dof())
}

fn gaps_over(model: &Model, q: &[f64], a: f64, b: f64, rows: std::ops::Range<usize>) -> (f64, f64) {
    let n = model.n_dof();
    let mut data = Data::new(model);
    let mass = mass_matrix(model, &mut data, q).unwrap().clone();
    let s = &mass
        + (stiffness_matrix(model) + gravity_hessian(model, q)) * a
        + damping_matrix(model) * b;
    let r = DVector::from_vec(Lcg(7).vec(n, 1.0));
    let reference = s.lu().solve(&r).expect("S is invertible");
    let mut solver = ShiftedSolver::new(model);
    let mut out = [0.0; 2];
    for (i, on) in [true, false].into_iter().enumerate() {
        solver.set_geometric(model, on).unwrap();
        solver.factor(model, q, a, b).unwrap();
        assert_eq!(solver.geometric_in_factor(), on);
        let mut x = r.as_slice().to_vec();
        solver.solve(model, &mut x).unwrap();
        let d = DVector::from_vec(x) - &reference;
        out[i] = d.rows_range(rows.clone()).amax() / reference.rows_range(rows.clone()).amax();
    }
    (out[0], out[1])
}

/// Five rigid links hanging from the world on revolute joints (one a
/// universal joint), centres of mass off the joint axes; and, as a model
/// needs a rod, a short rod clamped to the world on its own branch (its
/// coordinates are not compared: its within-piece terms are CT22's).
fn rigid_chain() -> Model {
    let mut b = Model::builder().rod_on(soft_rod("post", 0.1, 1), Attachment::world());
    let mut parent = None::<String>;
    for i in 0..5 {
        let name = format!("link{i}");
        let mut body = BodySpec::principal(&name, 0.1 + 0.02 * i as f64, [1e-4, 2e-4, 1.5e-4]);
        body.center_of_mass = Vec3::new(0.05, 0.01 * i as f64, -0.02);
        if parent.is_some() {
            body.base = Pose::new(Mat3::identity(), Vec3::new(0.1, 0.0, -0.01));
        }
        let joint = if i == 2 {
            Joint::universal([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])
        } else {
            Joint::revolute([0.1 * i as f64, 1.0, 0.2]).with_stiffness(&[0.05])
        };
        let att = match &parent {
            None => Attachment::world_joint(joint),
            Some(p) => Attachment::to(p, joint),
        };
        b = b.body(body, att);
        parent = Some(name);
    }
    b.gravity([0.5, -1.0, -9.81]).build().unwrap()
}

#[test]
fn rigid_chain_is_exact() {
    let model = rigid_chain();
    let q: Vec<f64> = (0..model.n_dof())
        .map(|i| 0.3 + 0.4 * (1.3 * i as f64).sin())
        .collect();
    // Shifts where the geometric term is small, comparable and dominant
    // against the links' masses (a·m g ℓ / (m ℓ²) = a g/ℓ ≈ 1e-2, 1, 1e2).
    let first = model
        .elements()
        .iter()
        .map(|e| e.joint_dofs.start)
        .filter(|&s| s > 0)
        .min();
    let rows = first.unwrap_or(0)..model.n_dof();
    eprintln!("rigid links: coordinates {rows:?} of {}", model.n_dof());
    for (a, b) in [(1e-4, 1e-2), (1e-2, 1e-1), (1.0, 1.0)] {
        let (with, without) = gaps_over(&model, &q, a, b, rows.clone());
        eprintln!("rigid chain a = {a:e}: gap with K_g {with:.3e}, without {without:.3e}");
        // Central differences of G with step 1e-6: ~1e-9 relative.
        assert!(with < 1e-6, "a = {a}: geometric gap {with:e}");
        assert!(
            without > 1e-3,
            "a = {a}: the test sees the term ({without:e})"
        );
    }
}

/// A soft rod (20 pieces, all six strains) hanging from a spherical joint
/// (gravity along its axis `x`: a stable configuration, where `M + a(K +
/// K_g) + bD` stays positive definite), swung and bent.
fn hanging_rod() -> Model {
    Model::builder()
        .rod_on(
            soft_rod("rope", 0.5, 20),
            Attachment::world_joint(Joint::spherical()),
        )
        .gravity([9.81, 0.0, 0.0])
        .build()
        .unwrap()
}

#[test]
fn pcs_rod_is_exact_with_the_map_hessians() {
    let model = hanging_rod();
    let n = model.n_dof();
    let mut q = vec![0.0; n];
    // Swung off the vertical at the joint, a gentle bend along the rod.
    q[1] = 0.4;
    q[2] = 0.2;
    for (i, v) in q.iter_mut().enumerate().skip(3) {
        *v = 0.3 * (0.7 * i as f64).sin() * if (i - 3) % 6 < 3 { 1.0 } else { 0.01 };
    }
    for (a, b) in [(1e-5, 1e-3), (1e-4, 1e-2)] {
        let (with, without) = gaps(&model, &q, a, b);
        eprintln!("hanging rod a = {a:e}: gap with K_g {with:.3e}, without {without:.3e}");
        // Central differences of G: ~1e-9 relative; the map Hessians
        // (CT22) make the rod exact as well.
        assert!(with < 1e-6, "a = {a}: geometric gap {with:e}");
        assert!(
            without > 1e-3,
            "a = {a}: the test sees the term ({without:e})"
        );
    }
}

#[test]
fn chain_models_factor_on_their_tree() {
    // A lone rod clamped to the world keeps the chain path without the
    // geometric terms and factors on its tree with them: with `a = 0` the
    // terms vanish and both solves agree to rounding.
    let model = Model::builder()
        .rod_on(soft_rod("arm", 0.4, 6), Attachment::world())
        .gravity([9.81, 0.0, -1.0])
        .build()
        .unwrap();
    let q = common::wavy(model.n_dof(), 0.1, 0.2);
    let r = Lcg(3).vec(model.n_dof(), 1.0);
    let mut solver = ShiftedSolver::new(&model);
    let mut x = [r.clone(), r.clone()];
    for (i, on) in [false, true].into_iter().enumerate() {
        solver.set_geometric(&model, on).unwrap();
        // a = 0 leaves the geometric terms out: the same matrix M + bD.
        solver.factor(&model, &q, 0.0, 1e-2).unwrap();
        solver.solve(&model, &mut x[i]).unwrap();
    }
    let d = x[0]
        .iter()
        .zip(&x[1])
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-12 * x[0].iter().fold(0.0_f64, |m, v| m.max(v.abs())));
    let (with, without) = gaps(&model, &q, 1e-2, 1e-2);
    eprintln!("clamped rod a = 1e-2: gap with K_g {with:.3e}, without {without:.3e}");
    assert!(with < 1e-6 && without > 1e-3, "{with:e} vs {without:e}");
}

/// The simplified Newton iteration of a backward-Euler step of a hanging
/// rope (40 pieces bending only, on a universal joint, 1 mm radius,
/// `E` = 1e5 Pa: tension dominates bending,
/// `T/ℓ ≫ EI/ℓ³` near the root) swung off the vertical:
/// `F(q) = M(q₀)(q − q₀)/h² + b(q, 0) = 0` with the iteration matrix
/// `S = M(q₀) + h²(K + K_g)` factored once at `q₀`. The residual's
/// contraction per iteration (mean over 6), with and without `K_g`.
fn rope_contraction(h: f64, geometric: bool) -> f64 {
    use softrod_dynamics::static_force;
    let model = Model::builder()
        .rod_on(
            softrod_dynamics::Rod::builder(0.5)
                .name("rope")
                .pieces(40)
                .circle(0.001)
                .material(common::soft_material(1e5, 1000.0))
                .strains([Strain::Ky, Strain::Kz]),
            Attachment::world_joint(Joint::universal([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])),
        )
        .gravity([9.81, 0.0, 0.0])
        .build()
        .unwrap();
    let n = model.n_dof();
    let mut q0 = vec![0.0; n];
    q0[0] = 0.3;
    for (i, v) in q0.iter_mut().enumerate().skip(2) {
        *v = 0.5 * (0.9 * i as f64).sin();
    }
    let mut data = Data::new(&model);
    let m0 = mass_matrix(&model, &mut data, &q0).unwrap().clone();
    let mut solver = ShiftedSolver::new(&model);
    solver.set_geometric(&model, geometric).unwrap();
    solver.factor(&model, &q0, h * h, 0.0).unwrap();
    assert_eq!(solver.geometric_in_factor(), geometric);
    let residual = |q: &[f64], data: &mut Data| -> DVector<f64> {
        let dq = DVector::from_iterator(n, q.iter().zip(&q0).map(|(a, b)| a - b));
        &m0 * dq / (h * h) + static_force(&model, data, 0.0, q).unwrap()
    };
    let mut q = q0.clone();
    let mut r = residual(&q, &mut data);
    let first = r.norm();
    let iterations = 6;
    for _ in 0..iterations {
        let mut dx: Vec<f64> = r.iter().map(|v| -v * h * h).collect();
        solver.solve(&model, &mut dx).unwrap();
        for (qi, d) in q.iter_mut().zip(&dx) {
            *qi += d;
        }
        r = residual(&q, &mut data);
    }
    (r.norm() / first).powf(1.0 / iterations as f64)
}

#[test]
fn hanging_rope_newton_contracts_with_the_geometric_terms() {
    let mut seen = Vec::new();
    for h in [1e-3, 3e-3, 1e-2, 3e-2] {
        let (with, without) = (rope_contraction(h, true), rope_contraction(h, false));
        eprintln!(
            "rope h = {h:e}: contraction per iteration with K_g {with:.3e}, without {without:.3e}"
        );
        seen.push((h, with, without));
    }
    for (h, with, without) in seen {
        assert!(
            with < 0.05 && with < without,
            "h = {h}: {with:e} vs {without:e}"
        );
    }
}
