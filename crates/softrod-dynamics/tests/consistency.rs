//! Cross-algorithm consistency of the dynamics (docs/theory.md §8, cross-checks 2–4):
//! every algorithm checked against an independent one — the O(N) recursion
//! against the mass-matrix path, the composite `M` against `∫JᵀMJ` from
//! explicit Jacobians, inverse dynamics against the Euler–Lagrange equations
//! of finite-differenced energies, and the power balance.

use nalgebra::{DMatrix, DVector, Matrix6xX};
use softrod_dynamics::*;
use softrod_kinematics::{Basis, Frame, PieceSpec, RodGeometry, RodKinematics, Strain, straight};
use softrod_lie::{Pose, Vec3, Vec6, exp_twist};
use softrod_mechanics::reference::{
    generalized_gravity_by_jacobian, line_load_force_by_jacobian, point_load_force_by_jacobian,
};
use softrod_mechanics::{
    Cable, DistributedLoad, Drag, LoadFrame, Material, PointLoad, RodProperties, Routing, Section,
    Tension,
};

/// Small deterministic generator (tests must be reproducible).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64) / ((1u64 << 53) as f64) * 2.0 - 1.0
    }
    fn vec(&mut self, n: usize, scale: f64) -> Vec<f64> {
        (0..n).map(|_| scale * self.next()).collect()
    }
}

fn bases() -> Vec<Basis> {
    vec![
        Basis::all(),
        Basis::select(&[Strain::Ky]).unwrap(),
        Basis::select(&[Strain::Ky, Strain::Qx, Strain::Qz]).unwrap(),
        Basis::select(&[Strain::Kx, Strain::Kz, Strain::Qy]).unwrap(),
        Basis::kirchhoff(),
        // k ≥ 4 takes the block-accumulation path: a permuted selection and
        // general (non-selection) matrices exercise its projections.
        Basis::select(&[Strain::Qz, Strain::Kx, Strain::Qx, Strain::Kz, Strain::Ky]).unwrap(),
        Basis::from_matrix(Matrix6xX::from_fn(4, |i, j| {
            ((i * 4 + j) as f64 * 0.9 + 0.3).sin() + if i == j { 1.5 } else { 0.0 }
        }))
        .unwrap(),
        Basis::from_matrix(Matrix6xX::from_fn(6, |i, j| {
            ((i * 6 + j) as f64 * 0.7).cos() * 0.4 + if i == j { 1.0 } else { 0.0 }
        }))
        .unwrap(),
    ]
}

/// What to switch on in a test model.
#[derive(Clone, Copy)]
struct Terms {
    gravity: bool,
    damping: bool,
    loads: bool,
    cable: bool,
    drag: bool,
}

const ALL: Terms = Terms {
    gravity: true,
    damping: true,
    loads: true,
    cable: true,
    drag: true,
};
const CONSERVATIVE: Terms = Terms {
    gravity: true,
    damping: false,
    loads: false,
    cable: false,
    drag: false,
};

/// A rod of `n` pieces, bases cycling through `bases()` when `mixed`,
/// precurved rest strain, tilted base, soft silicone-like material.
fn model(n: usize, mixed: bool, terms: Terms) -> Model {
    let length = 0.4;
    let b = bases();
    let specs: Vec<PieceSpec> = (0..n)
        .map(|i| PieceSpec {
            length: length / n as f64,
            basis: if mixed {
                b[i % b.len()].clone()
            } else {
                Basis::all()
            },
            rest_strain: Vec6::new(0.1, 0.5, -0.3, 1.0, 0.0, 0.0),
        })
        .collect();
    let base = exp_twist(1.0, &Vec6::new(0.2, -0.4, 0.1, 0.0, 0.05, 0.1));
    let rod = RodGeometry::from_pieces(specs, base).unwrap();
    let viscosity = if terms.damping { 30.0 } else { 0.0 };
    let body = RodProperties::new(
        Section::Circle { radius: 0.012 },
        Material::builder()
            .density(1100.0)
            .young(2e6)
            .poisson(0.45)
            .viscosity(viscosity)
            .build()
            .unwrap(),
        length,
    )
    .unwrap();
    let mut spec = Rod::new("arm", rod, body);
    if terms.loads {
        spec.point_loads = vec![
            PointLoad {
                s: length,
                force: Vec3::new(0.1, -0.2, 0.3),
                moment: Vec3::new(0.01, 0.0, -0.02),
                frame: LoadFrame::World,
            },
            PointLoad {
                s: 0.37 * length,
                force: Vec3::new(-0.05, 0.1, 0.0),
                moment: Vec3::new(0.0, 0.01, 0.0),
                frame: LoadFrame::Body,
            },
        ];
        spec.distributed_loads = vec![
            DistributedLoad {
                force: Vec3::new(0.0, 0.3, 0.1),
                moment: Vec3::zeros(),
                frame: LoadFrame::World,
            },
            DistributedLoad {
                force: Vec3::new(0.0, 0.0, -0.2),
                moment: Vec3::new(0.01, 0.0, 0.0),
                frame: LoadFrame::Body,
            },
        ];
    }
    if terms.drag {
        spec.drag = Some(Drag {
            translational: 0.5,
            rotational: 1e-4,
        });
    }
    if terms.cable {
        spec.cables = vec![
            Cable::new(
                Routing::Path(vec![[0.0, 0.008, 0.0], [length, 0.002, 0.004]]),
                Tension::Constant(1.5),
            )
            .between(0.0, 0.8 * length),
        ];
    }
    let gravity = terms.gravity.then(|| Vec3::new(0.3, -1.0, -9.81));
    Model::new(vec![spec], gravity, 5).unwrap()
}

fn rel_err(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1e-300)
}

fn state(rng: &mut Lcg, n: usize) -> (Vec<f64>, Vec<f64>) {
    (rng.vec(n, 0.8), rng.vec(n, 2.0))
}

#[test]
fn mass_matrix_is_spd_and_equals_jacobian_integral() {
    let mut rng = Lcg(7);
    for (n, mixed) in [(1, false), (3, true), (8, true), (5, false)] {
        let m = model(n, mixed, CONSERVATIVE);
        let mut data = Data::new(&m);
        let (q, _) = state(&mut rng, m.n_dof());
        let mass = mass_matrix(&m, &mut data, &q).unwrap().clone();
        let asym = (&mass - mass.transpose()).amax() / mass.amax();
        assert!(asym < 1e-14, "asymmetry {asym:e}");
        assert!(mass.clone().cholesky().is_some(), "not positive definite");
        // Independent: M = Σ_g w Jᵀ 𝓜 J with J from the kinematics layer.
        let rm = &m.rods()[0];
        let rod = &rm.spec.geometry;
        let mut kin = RodKinematics::new(rod);
        kin.update(rod, &q, None, None).unwrap();
        let mut j = Matrix6xX::zeros(rod.n_dof());
        let mut reference = DMatrix::zeros(rod.n_dof(), rod.n_dof());
        for piece in rod.pieces() {
            for (x, w) in m.quadrature().on_interval(piece.length) {
                let s = piece.start + x;
                kin.jacobian_at(rod, s, Frame::Body, &mut j).unwrap();
                let md = DMatrix::from_diagonal(&DVector::from_column_slice(
                    rm.spec.properties.screw_inertia(s).as_slice(),
                ));
                let jd = DMatrix::from_column_slice(6, rod.n_dof(), j.as_slice());
                reference += jd.transpose() * md * jd * w;
            }
        }
        let err = (&mass - &reference).amax() / reference.amax();
        assert!(err < 1e-13, "N = {n}: composite M vs ∫JᵀMJ: {err:e}");
    }
}

#[test]
fn inverse_dynamics_is_linear_in_acceleration() {
    // ID(q, q̇, q̈) = M q̈ + ID(q, q̇, 0), all terms on (docs/theory.md §8(c)).
    let mut rng = Lcg(11);
    let m = model(4, true, ALL);
    let mut data = Data::new(&m);
    let (q, qd) = state(&mut rng, m.n_dof());
    let qdd = rng.vec(m.n_dof(), 5.0);
    let full = inverse_dynamics(&m, &mut data, 0.3, &q, &qd, &qdd)
        .unwrap()
        .clone();
    let zero = vec![0.0; m.n_dof()];
    let bias = inverse_dynamics(&m, &mut data, 0.3, &q, &qd, &zero)
        .unwrap()
        .clone();
    let mass = mass_matrix(&m, &mut data, &q).unwrap().clone();
    let lin = &mass * DVector::from_column_slice(&qdd) + bias;
    assert!(rel_err(&full, &lin) < 1e-12, "{:e}", rel_err(&full, &lin));
}

#[test]
fn forward_inverts_inverse_and_recursions_agree() {
    // forward(inverse(q̈)) = q̈ and O(N) = Cholesky, for N = 1…50, mixed
    // bases, every term on.
    //
    // Measure: the elastic force K q is orders of magnitude larger than
    // M q̈ for these soft, sheared states, so τ − b cancels and q̈ can only be
    // recovered to ε·cond(M)·‖b‖/‖Mq̈‖. We therefore check the backward
    // error — the residual force M(q̈_fd − q̈) relative to the forces present
    // — which a correct algorithm keeps at round-off (~1e-16·n); and the two
    // forward paths against each other on q̈ itself.
    let mut rng = Lcg(3);
    for (n, mixed) in [
        (1, false),
        (1, true),
        (2, true),
        (3, false),
        (5, true),
        (8, true),
        (13, true),
        (20, false),
        (50, true),
    ] {
        let m = model(n, mixed, ALL);
        let mut data = Data::new(&m);
        let (q, qd) = state(&mut rng, m.n_dof());
        let qdd = DVector::from_vec(rng.vec(m.n_dof(), 3.0));
        let tau = inverse_dynamics(&m, &mut data, 0.1, &q, &qd, qdd.as_slice())
            .unwrap()
            .clone();
        let zero = vec![0.0; m.n_dof()];
        let bias = inverse_dynamics(&m, &mut data, 0.1, &q, &qd, &zero)
            .unwrap()
            .clone();
        let mass = mass_matrix(&m, &mut data, &q).unwrap().clone();
        let force_scale = tau.amax().max(bias.amax());
        let fd = forward_dynamics(&m, &mut data, 0.1, &q, &qd, Some(tau.as_slice()))
            .unwrap()
            .clone();
        let e1 = (&mass * (&fd - &qdd)).amax() / force_scale;
        let ch = forward_dynamics_cholesky(&m, &mut data, 0.1, &q, &qd, Some(tau.as_slice()))
            .unwrap()
            .clone();
        let e2 = (&mass * (&ch - &qdd)).amax() / force_scale;
        assert!(
            e1 < 1e-13 && e2 < 1e-13,
            "N = {n}: backward errors {e1:e} {e2:e}"
        );
        // Random actuation, no ID involved: the two forward paths agree on q̈
        // to the conditioning of M: 1e-10, or ε·cond(M) for the long chains.
        let tau_r = rng.vec(m.n_dof(), 0.5);
        let a = forward_dynamics(&m, &mut data, 0.1, &q, &qd, Some(&tau_r))
            .unwrap()
            .clone();
        let b = forward_dynamics_cholesky(&m, &mut data, 0.1, &q, &qd, Some(&tau_r))
            .unwrap()
            .clone();
        let e3 = rel_err(&a, &b);
        let evq = mass.clone().symmetric_eigen().eigenvalues;
        let cond_q = evq.max() / evq.min();
        let bound3 = (1e-16 * cond_q).max(1e-10);
        assert!(
            e3 < bound3,
            "N = {n}: O(N) vs Cholesky {e3:e} (cond {cond_q:e})"
        );
        // forward(inverse(q̈)) = q̈ itself, at the stress-free shape (no
        // elastic preload), within the forward-error bound cond(M)·(backward
        // error): 1e-10 for short chains, growing with cond(M) for long ones.
        let q0 = vec![0.0; m.n_dof()];
        let tau0 = inverse_dynamics(&m, &mut data, 0.1, &q0, &qd, qdd.as_slice())
            .unwrap()
            .clone();
        let bias0 = inverse_dynamics(&m, &mut data, 0.1, &q0, &qd, &zero)
            .unwrap()
            .clone();
        let back = forward_dynamics(&m, &mut data, 0.1, &q0, &qd, Some(tau0.as_slice()))
            .unwrap()
            .clone();
        let m0 = mass_matrix(&m, &mut data, &q0).unwrap().clone();
        let ev = m0.clone().symmetric_eigen().eigenvalues;
        let cond = ev.max() / ev.min();
        let mqdd = (&m0 * &qdd).amax();
        let bound = (4e-16 * cond * tau0.amax().max(bias0.amax()) / mqdd).max(1e-10);
        let e4 = rel_err(&back, &qdd);
        assert!(
            e4 < bound,
            "N = {n}: forward(inverse(q̈)) at rest shape {e4:e} (bound {bound:e}, cond {cond:e})"
        );
        if n <= 5 {
            assert!(e4 < 1e-10, "N = {n}: {e4:e}");
        }
    }
}

/// A one-piece rod bent to radii down to 2e-8 m — bend angles across the
/// piece `ψ = θL` from 1e-8 to 1e6 rad, among them the 8e-8 m radius of the
/// CLI's fuzzed scene (softrod-cli tests/watch.rs) — on the six strains and
/// on `(ky, qz)`, clamped (the chain's sums) and on a revolute joint (the
/// tree's): the articulated inertia stays positive definite (the O(N)
/// forward dynamics succeeds, `q̈` finite), bending about a coordinate axis
/// (where the isotropic `Σ m T_aᵀT_a` is exact across `k`, D91) and about a
/// general one, and `q̈` inverts the inverse dynamics to the backward error
/// of a stable factorization (the residual `M(q̈_fd − q̈)` with `M` from the
/// composite algorithm, relative to the forces present, as
/// [`forward_inverts_inverse_and_recursions_agree`]).
#[test]
fn forward_dynamics_is_defined_at_extreme_bends() {
    let len = 0.02;
    let material = Material::with_poisson(1100.0, 1e6, 0.5, 500.0).unwrap();
    let mut rng = Lcg(37);
    let axes = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.36, -0.8, 0.48)];
    let psis = [1e-8, 1e-3, 1.0, 3.0, 6.3, 30.0, 1e3, 1e4, 2.5e5, 1e6];
    let strain_sets = [
        vec![Strain::Ky, Strain::Qz],
        vec![
            Strain::Kx,
            Strain::Ky,
            Strain::Kz,
            Strain::Qx,
            Strain::Qy,
            Strain::Qz,
        ],
    ];
    for axis in &axes {
        for &psi in &psis {
            for strains in &strain_sets {
                for joint in [false, true] {
                    let k = axis * (psi / len);
                    let rod = Rod::builder(len)
                        .pieces(1)
                        .strains(strains.iter().copied())
                        .circle(0.008)
                        .material(material)
                        .rest_strain(Vec6::new(k[0], k[1], k[2], 1.0, 0.0, 0.7));
                    let b = Model::builder().gravity([0.0, 0.0, -9.81]);
                    let m = if joint {
                        b.rod_on(
                            rod,
                            Attachment::world_joint(Joint::revolute([0.0, 1.0, 0.0])),
                        )
                    } else {
                        b.rod(rod)
                    }
                    .build()
                    .unwrap();
                    let at = format!("ψ = {psi:e}, axis {axis:?}, {strains:?}, joint {joint}");
                    let mut data = Data::new(&m);
                    let n = m.n_dof();
                    let (q, qd) = (rng.vec(n, 1e-3), rng.vec(n, 0.1));
                    let qdd = DVector::from_vec(rng.vec(n, 1.0));
                    let tau = inverse_dynamics(&m, &mut data, 0.0, &q, &qd, qdd.as_slice())
                        .unwrap()
                        .clone();
                    let zero = vec![0.0; n];
                    let bias = inverse_dynamics(&m, &mut data, 0.0, &q, &qd, &zero)
                        .unwrap()
                        .clone();
                    let mass = mass_matrix(&m, &mut data, &q).unwrap().clone();
                    let fd =
                        match forward_dynamics(&m, &mut data, 0.0, &q, &qd, Some(tau.as_slice())) {
                            Ok(fd) => fd.clone(),
                            Err(e) => panic!("{at}: {e}"),
                        };
                    assert!(fd.iter().all(|v| v.is_finite()), "{at}: {fd}");
                    let scale = tau.amax().max(bias.amax()).max((&mass * &qdd).amax());
                    let e = (&mass * (&fd - &qdd)).amax() / scale;
                    // Six strains on a joint bent about a general axis: the
                    // backward error grows with the bend (1e-14 at 1e3 rad,
                    // 1e-7 at 1e6, the same with the polynomial 𝓓₂₂ of D91,
                    // so not from these sums); checked for definiteness only.
                    let general_tree = axis[0] != 0.0 && joint && strains.len() == 6;
                    if !general_tree || psi <= 30.0 {
                        assert!(e < 1e-13, "{at}: backward error {e:e}");
                    }
                }
            }
        }
    }
}

#[test]
fn gravity_and_point_loads_match_jacobian_projections() {
    let mut rng = Lcg(5);
    let m = model(3, true, CONSERVATIVE);
    let mut data = Data::new(&m);
    let (q, _) = state(&mut rng, m.n_dof());
    let g = generalized_gravity(&m, &mut data, &q).unwrap();
    let rm = &m.rods()[0];
    let grav = m.gravity().unwrap();
    let reference = -generalized_gravity_by_jacobian(
        &rm.spec.geometry,
        &rm.spec.properties,
        &grav,
        &q,
        m.quadrature(),
    );
    assert!(
        rel_err(&g, &reference) < 1e-12,
        "{:e}",
        rel_err(&g, &reference)
    );

    // Point loads alone: ID(q, 0, 0) − ID without them = −Σ J(s̄)ᵀ𝓕_p.
    let with = model(
        3,
        true,
        Terms {
            loads: true,
            ..CONSERVATIVE
        },
    );
    let mut d2 = Data::new(&with);
    let zero = vec![0.0; m.n_dof()];
    let a = inverse_dynamics(&with, &mut d2, 0.0, &q, &zero, &zero)
        .unwrap()
        .clone();
    let b = inverse_dynamics(&m, &mut data, 0.0, &q, &zero, &zero)
        .unwrap()
        .clone();
    let mut loads = DVector::zeros(m.n_dof());
    let rw = &with.rods()[0];
    for l in &rw.spec.point_loads {
        loads += point_load_force_by_jacobian(&rw.spec.geometry, l, &q);
    }
    for d in &rw.spec.distributed_loads {
        loads += line_load_force_by_jacobian(
            &rw.spec.geometry,
            &q,
            None,
            with.quadrature(),
            |_, pose, _| d.wrench_density(pose),
        );
    }
    let diff = &a - &b;
    let e = rel_err(&diff, &(-loads));
    assert!(e < 1e-11, "point/distributed loads: {e:e}");
}

/// Central difference of a scalar function in coordinate `j`.
fn fd(f: &mut dyn FnMut(&[f64]) -> f64, x: &[f64], j: usize, h: f64) -> f64 {
    let mut xp = x.to_vec();
    xp[j] = x[j] + h;
    let p = f(&xp);
    xp[j] = x[j] - h;
    let mm = f(&xp);
    xp[j] = x[j] + 2.0 * h;
    let p2 = f(&xp);
    xp[j] = x[j] - 2.0 * h;
    let m2 = f(&xp);
    (8.0 * (p - mm) - (p2 - m2)) / (12.0 * h)
}

#[test]
fn equations_of_motion_are_euler_lagrange_of_the_energies() {
    // ID(q, q̇, q̈) = d/dt ∂T/∂q̇ − ∂T/∂q + ∂V/∂q, with T, V from `energies`
    // (a separate kinematic pass) and every derivative by 4th-order finite
    // differences — independent of both recursions.
    let mut rng = Lcg(17);
    for (n, mixed) in [(1, false), (3, true)] {
        let m = model(n, mixed, CONSERVATIVE);
        let nd = m.n_dof();
        let mut data = Data::new(&m);
        let (q, qd) = state(&mut rng, nd);
        let qdd = rng.vec(nd, 2.0);
        let id = inverse_dynamics(&m, &mut data, 0.0, &q, &qd, &qdd)
            .unwrap()
            .clone();
        let mut d2 = Data::new(&m);
        let h = 1e-4;
        let mut el = DVector::zeros(nd);
        for j in 0..nd {
            // p_j(q, q̇) = ∂T/∂q̇_j; d/dt along q(t) = q + t q̇ + t²/2 q̈.
            let mut p_j = |t: f64| {
                let qt: Vec<f64> = (0..nd)
                    .map(|i| q[i] + t * qd[i] + 0.5 * t * t * qdd[i])
                    .collect();
                let vt: Vec<f64> = (0..nd).map(|i| qd[i] + t * qdd[i]).collect();
                let mut ke = |v: &[f64]| energies(&m, &mut d2, &qt, v).unwrap().kinetic;
                fd(&mut ke, &vt, j, 1e-3)
            };
            let dpdt = (8.0 * (p_j(h) - p_j(-h)) - (p_j(2.0 * h) - p_j(-2.0 * h))) / (12.0 * h);
            let mut lag = |x: &[f64]| {
                let e = energies(&m, &mut d2, x, &qd).unwrap();
                e.kinetic - e.elastic - e.gravitational
            };
            el[j] = dpdt - fd(&mut lag, &q, j, 1e-4);
        }
        let e = rel_err(&id, &el);
        assert!(e < 1e-7, "N = {n}: Euler–Lagrange residual {e:e}");
    }
}

#[test]
fn coriolis_matrix_reproduces_bias_and_is_passive() {
    let mut rng = Lcg(23);
    let m = model(3, true, CONSERVATIVE);
    let nd = m.n_dof();
    let mut data = Data::new(&m);
    let (q, qd) = state(&mut rng, nd);
    let zero = vec![0.0; nd];
    let b = inverse_dynamics(&m, &mut data, 0.0, &q, &qd, &zero)
        .unwrap()
        .clone();
    let g = inverse_dynamics(&m, &mut data, 0.0, &q, &zero, &zero)
        .unwrap()
        .clone();
    let c = coriolis_matrix(&m, &q, &qd).unwrap();
    let cqd = &c * DVector::from_column_slice(&qd);
    let e = rel_err(&(b - g), &cqd);
    assert!(e < 1e-11, "C q̇ vs ID(q, q̇, 0) − ID(q, 0, 0): {e:e}");
    // Ṁ − 2C skew-symmetric, Ṁ by a central difference along q̇.
    let h = 1e-6;
    let qp: Vec<f64> = (0..nd).map(|i| q[i] + h * qd[i]).collect();
    let qm: Vec<f64> = (0..nd).map(|i| q[i] - h * qd[i]).collect();
    let mp = mass_matrix(&m, &mut data, &qp).unwrap().clone();
    let mm = mass_matrix(&m, &mut data, &qm).unwrap().clone();
    let mdot = (mp - mm) / (2.0 * h);
    let s = &mdot - &c * 2.0;
    let skew = (&s + s.transpose()).amax() / mdot.amax();
    assert!(skew < 1e-7, "Ṁ − 2C symmetric part {skew:e}");
}

#[test]
fn power_balance_along_a_path() {
    // dE/dt = −q̇ᵀDq̇ + q̇ᵀτ_c (drag and other loads off; the cable has
    // constant tension): integrate E and the power with RK4 over a short
    // path and compare ΔE with ∫P dt. RK4 at dt = 2e-6 s gives ~1e-10 J.
    let terms = Terms {
        gravity: true,
        damping: true,
        loads: false,
        cable: true,
        drag: false,
    };
    let m = model(2, true, terms);
    let nd = m.n_dof();
    let mut data = Data::new(&m);
    let mut rng = Lcg(29);
    let (q0, qd0) = state(&mut rng, nd);
    let (mut q, mut qd) = (DVector::from_vec(q0), DVector::from_vec(qd0));
    let dmat = damping_matrix(&m);
    let power = |data: &mut Data, q: &DVector<f64>, qd: &DVector<f64>| {
        let a = actuation_matrix(&m, q.as_slice()).unwrap();
        let tc = a.column(0) * 1.5;
        let _ = data;
        -qd.dot(&(&dmat * qd)) + qd.dot(&tc)
    };
    let energy = |data: &mut Data, q: &DVector<f64>, qd: &DVector<f64>| {
        energies(&m, data, q.as_slice(), qd.as_slice())
            .unwrap()
            .total()
    };
    let e0 = energy(&mut data, &q, &qd);
    let dt = 2e-6;
    let mut work = 0.0;
    let acc = |data: &mut Data, q: &DVector<f64>, qd: &DVector<f64>| {
        forward_dynamics(&m, data, 0.0, q.as_slice(), qd.as_slice(), None)
            .unwrap()
            .clone()
    };
    for _ in 0..200 {
        // RK4 on (q, q̇, W) with W' = P.
        let k1q = qd.clone();
        let k1v = acc(&mut data, &q, &qd);
        let k1w = power(&mut data, &q, &qd);
        let (q2, v2) = (&q + &k1q * (dt / 2.0), &qd + &k1v * (dt / 2.0));
        let k2q = v2.clone();
        let k2v = acc(&mut data, &q2, &v2);
        let k2w = power(&mut data, &q2, &v2);
        let (q3, v3) = (&q + &k2q * (dt / 2.0), &qd + &k2v * (dt / 2.0));
        let k3q = v3.clone();
        let k3v = acc(&mut data, &q3, &v3);
        let k3w = power(&mut data, &q3, &v3);
        let (q4, v4) = (&q + &k3q * dt, &qd + &k3v * dt);
        let k4q = v4.clone();
        let k4v = acc(&mut data, &q4, &v4);
        let k4w = power(&mut data, &q4, &v4);
        q += (k1q + k2q * 2.0 + k3q * 2.0 + k4q) * (dt / 6.0);
        qd += (k1v + k2v * 2.0 + k3v * 2.0 + k4v) * (dt / 6.0);
        work += (k1w + 2.0 * k2w + 2.0 * k3w + k4w) * (dt / 6.0);
    }
    let e1 = energy(&mut data, &q, &qd);
    let scale = work.abs().max((e1 - e0).abs());
    let mismatch = (e1 - e0 - work).abs();
    assert!(
        mismatch < 1e-6 * scale,
        "ΔE = {:e}, ∫P dt = {work:e}, mismatch {mismatch:e}",
        e1 - e0
    );
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let m = model(2, false, CONSERVATIVE);
    let mut data = Data::new(&m);
    let nd = m.n_dof();
    let short = vec![0.0; nd - 1];
    let ok = vec![0.0; nd];
    assert!(matches!(
        forward_dynamics(&m, &mut data, 0.0, &short, &ok, None),
        Err(DynamicsError::SizeMismatch { .. })
    ));
    let mut nan = ok.clone();
    nan[3] = f64::NAN;
    assert!(matches!(
        inverse_dynamics(&m, &mut data, 0.0, &ok, &nan, &ok),
        Err(DynamicsError::NotFinite { .. })
    ));
    let _ = Pose::identity();
    let _ = straight();
}

#[test]
fn statics_defaults_reach_round_off_and_failures_carry_the_residual() {
    // A follower tip moment on a straight one-piece rod: the exact solution
    // is the uniform curvature κ = M/(EI) (a circle arc), every other strain
    // at rest. The default tolerance must land at round-off, not one Newton
    // step early.
    let length = 0.3;
    let rod = RodGeometry::uniform(length, 1, Basis::all(), straight(), Pose::identity()).unwrap();
    let material = Material::builder()
        .density(1000.0)
        .young(5e6)
        .poisson(0.4)
        .viscosity(0.0)
        .build()
        .unwrap();
    let body = RodProperties::new(Section::Circle { radius: 0.01 }, material, length).unwrap();
    let ei = material.young() * std::f64::consts::PI * 0.01f64.powi(4) / 4.0;
    let kappa = 2.0 * std::f64::consts::PI / length; // a full circle
    let mut spec = Rod::new("arm", rod, body);
    spec.point_loads = vec![PointLoad {
        s: length,
        force: Vec3::zeros(),
        moment: Vec3::new(0.0, 0.0, kappa * ei),
        frame: LoadFrame::Body,
    }];
    let m = Model::new(vec![spec], None, 4).unwrap();
    let mut data = Data::new(&m);
    let res = statics(&m, &mut data, &[0.0; 6], &StaticsOptions::default()).unwrap();
    // Converged: the residual recomputed at the result is within the
    // default relative tolerance 1e-12 of the applied moment κEI, times the
    // 1e3 that statics allows when the line search stagnates at round-off.
    let r = inverse_dynamics(&m, &mut data, 0.0, res.q.as_slice(), &[0.0; 6], &[0.0; 6])
        .unwrap()
        .amax();
    assert!(r <= 1e-9 * kappa * ei, "residual {r:e}");
    assert!((res.q[2] - kappa).abs() < 1e-12 * kappa, "κ = {}", res.q[2]);
    for i in [0, 1, 3, 4, 5] {
        assert!(res.q[i].abs() < 1e-12, "q[{i}] = {}", res.q[i]);
    }
    // A hopeless budget: the error reports the residual it stopped at.
    let opts = StaticsOptions {
        max_iterations: 1,
        max_load_steps: 2,
        ..StaticsOptions::default()
    };
    let heavy = model(6, false, CONSERVATIVE);
    let mut d2 = Data::new(&heavy);
    let m2 = heavy
        .clone()
        .with_gravity(Some(Vec3::new(0.0, 0.0, -2000.0)))
        .unwrap();
    match statics(&m2, &mut d2, &vec![0.0; heavy.n_dof()], &opts) {
        Err(DynamicsError::StaticsFailed { residual, .. }) => {
            assert!(
                residual.is_finite() && residual > 0.0,
                "residual {residual}"
            )
        }
        other => panic!("expected StaticsFailed, got {other:?}"),
    }
}
