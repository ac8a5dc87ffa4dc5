//! Generalized forces: conservative terms against −∂V/∂q, cables against
//! −T ∂ℓ/∂q and against the wrench form of (D15), the uniform-strain cable
//! equilibrium, and quadrature convergence for a tapered rod.
//!
//! Run with `--nocapture` to see the measured errors.

mod common;

use common::*;
use nalgebra::{DVector, Matrix6, Matrix6xX};
use softrod_kinematics::{Basis, Frame, GaussLegendre, RodGeometry, RodKinematics, straight};
use softrod_lie::{Vec3, Vec6, Wrench, angular, coad_vec, join, linear};
use softrod_mechanics::reference::*;
use softrod_mechanics::*;
use std::f64::consts::PI;

const L: f64 = 0.5;

fn fmt(v: &[f64]) -> String {
    v.iter()
        .map(|e| format!("{e:.1e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn random_q(rod: &RodGeometry, rng: &mut Rng, scale: f64) -> Vec<f64> {
    rng.vec(rod.n_dof(), scale)
}

#[test]
fn gravity_force_is_minus_gradient_of_potential() {
    let rod = mixed_rod(L, oblique_base());
    let quad = gauss(5);
    let mut worst: f64 = 0.0;
    for (body, gw) in [
        (taper_body(L), Vec3::new(1.0, -3.0, -9.0)),
        (
            RodProperties::new(Section::Circle { radius: 0.01 }, soft_material(), L).unwrap(),
            Vec3::new(0.0, 0.0, -9.81),
        ),
    ] {
        let g = gw;
        let mut rng = Rng::new(11);
        for _ in 0..3 {
            let q = random_q(&rod, &mut rng, 0.8);
            let f = generalized_gravity_by_jacobian(&rod, &body, &g, &q, &quad);
            let fd = -fd_gradient(&q, 1e-6, |x| gravity_potential(&rod, &body, &g, x, &quad));
            let e = rel_err(&f, &fd);
            worst = worst.max(e);
            // The generic line-load projection gives the same vector.
            let ll = line_load_force_by_jacobian(&rod, &q, None, &quad, |s, pose, _| {
                gravity_wrench_density(body.mass_per_length(s), pose, &g)
            });
            assert!((&ll - &f).amax() <= 1e-15 * f.amax());
        }
    }
    eprintln!("gravity: Jᵀ𝓕_g vs −∂V_g/∂q (central FD, h = 1e-6): {worst:.1e}");
    assert!(worst < 1e-8, "{worst}");
}

#[test]
fn dead_point_force_is_minus_gradient_of_potential() {
    let rod = mixed_rod(L, oblique_base());
    let mut rng = Rng::new(5);
    let mut worst: f64 = 0.0;
    // Mid-piece, on a piece boundary, in the last piece, at the tip.
    for s in [0.07, 0.3 * L, 0.42, L] {
        for _ in 0..2 {
            let q = random_q(&rod, &mut rng, 0.8);
            let load = PointLoad {
                s,
                force: rng.vec3(2.0),
                moment: Vec3::zeros(),
                frame: LoadFrame::World,
            };
            let f = point_load_force_by_jacobian(&rod, &load, &q);
            let fd = -fd_gradient(&q, 1e-6, |x| dead_load_potential(&rod, &load, x));
            worst = worst.max(rel_err(&f, &fd));
        }
    }
    eprintln!("dead point force: J(s)ᵀ𝓕 vs −∂V/∂q: {worst:.1e}");
    assert!(worst < 1e-8, "{worst}");
}

#[test]
fn follower_and_dead_loads_agree_in_the_reference_configuration() {
    // With q = 0 and an identity base the straight rod's frames are the world
    // axes, so a dead and a follower load give the same force.
    let rod = RodGeometry::uniform(L, 2, Basis::all(), straight(), identity_base()).unwrap();
    let q = vec![0.0; rod.n_dof()];
    let dead = PointLoad {
        s: 0.4,
        force: Vec3::new(0.0, 0.0, -1.0),
        moment: Vec3::new(0.1, 0.0, 0.0),
        frame: LoadFrame::World,
    };
    let follower = PointLoad {
        frame: LoadFrame::Body,
        ..dead
    };
    let a = point_load_force_by_jacobian(&rod, &dead, &q);
    let b = point_load_force_by_jacobian(&rod, &follower, &q);
    assert!((&a - &b).amax() < 1e-15);
    // Positive ky turns the tangent x toward −z, so a downward force does
    // positive work on it. Piece 0 (x ∈ [0, 0.25]) bent by a unit ky moves the
    // point s = 0.4 by ∫₀^0.25 e_y × (0.4 − x) e_x dx = −0.06875 e_z, so
    // τ_ky = 0.06875 N·m; the torsional moment 0.1 N·m gives τ_kx = 0.1 × 0.25
    // on piece 0 and 0.1 × 0.15 on piece 1 (up to s = 0.4).
    assert!((a[1] - 0.06875).abs() < 1e-15, "{}", a[1]);
    assert!((a[0] - 0.025).abs() < 1e-15 && (a[6] - 0.015).abs() < 1e-15);
}

#[test]
fn drag_dissipates() {
    let rod = mixed_rod(L, oblique_base());
    let mut rng = Rng::new(3);
    let q = random_q(&rod, &mut rng, 0.5);
    let qd = random_q(&rod, &mut rng, 2.0);
    let drag = Drag {
        translational: 3.0,
        rotational: 0.2,
    };
    let f = line_load_force_by_jacobian(&rod, &q, Some(&qd), &gauss(5), |_, _, eta| {
        drag.wrench_density(eta)
    });
    let power = f.dot(&DVector::from_column_slice(&qd));
    assert!(power < 0.0, "{power}");
}

#[test]
fn elastic_force_is_gradient_of_energy() {
    let rod = mixed_rod(L, oblique_base());
    let mut rng = Rng::new(17);
    let mut worst: f64 = 0.0;
    for body in [
        taper_body(L),
        RodProperties::new(
            Section::Rectangle {
                width: 0.02,
                height: 0.01,
            },
            soft_material(),
            L,
        )
        .unwrap(),
    ] {
        let quad = gauss(4);
        // Precurved stress-free strains that differ from the rest strains.
        let sf: Vec<Vec6> = (0..rod.n_pieces())
            .map(|n| rod.pieces()[n].rest_strain + Vec6::from_fn(|_, _| 0.3 * rng.sym()))
            .collect();
        for stress_free in [None, Some(sf.as_slice())] {
            let pm = piece_matrices(&rod, &body, stress_free, &quad);
            for _ in 0..2 {
                let q = random_q(&rod, &mut rng, 0.5);
                let mut f = vec![0.0; rod.n_dof()];
                add_elastic_force(&rod, &pm, &q, &mut f);
                let f = DVector::from_vec(f);
                let fd = fd_gradient(&q, 1e-6, |x| {
                    elastic_energy(&rod, &body, stress_free, x, &quad)
                });
                worst = worst.max(rel_err(&f, &fd));
            }
            // K symmetric positive definite; the force vanishes at q̄ = −K⁻¹e
            // (piece-wise), and for ξ* = ξ̄ at q = 0.
            for (p, m) in rod.pieces().iter().zip(&pm) {
                assert!((&m.stiffness - m.stiffness.transpose()).amax() == 0.0);
                assert!(m.stiffness.clone().cholesky().is_some());
                let qbar = m.stress_free_coordinates();
                let r = &m.stiffness * &qbar + &m.elastic_offset;
                assert!(r.amax() <= 1e-12 * m.elastic_offset.amax().max(1e-300));
                if stress_free.is_none() {
                    assert_eq!(m.elastic_offset.amax(), 0.0);
                }
                assert_eq!(m.stiffness.nrows(), p.basis.dof());
            }
        }
    }
    eprintln!("elastic: K q + e vs ∂V_e/∂q (central FD): {worst:.1e}");
    assert!(worst < 1e-8, "{worst}");
}

#[test]
fn uniform_piece_matrices_are_length_times_projection() {
    let rod = mixed_rod(L, identity_base());
    let body = RodProperties::new(
        Section::Tube {
            radius: 0.02,
            inner_radius: 0.012,
        },
        soft_material(),
        L,
    )
    .unwrap();
    let pm = piece_matrices(&rod, &body, None, &gauss(1));
    let mut v = vec![0.0; rod.n_dof()];
    let qd: Vec<f64> = (0..rod.n_dof()).map(|i| i as f64 - 2.0).collect();
    add_damping_force(&rod, &pm, &qd, &mut v);
    for (p, m) in rod.pieces().iter().zip(&pm) {
        let b = p.basis.matrix();
        let gam = Matrix6::from_diagonal(&body.stiffness(0.0));
        let vis = Matrix6::from_diagonal(&body.viscosity(0.0));
        let k = b.transpose() * gam * b * p.length;
        let d = b.transpose() * vis * b * p.length;
        assert!((&m.stiffness - &k).amax() <= 1e-14 * k.amax());
        assert!((&m.damping - &d).amax() <= 1e-14 * d.amax());
        let dq = &d * DVector::from_column_slice(&qd[p.dofs()]);
        for (i, c) in p.dofs().enumerate() {
            assert!((v[c] - dq[i]).abs() <= 1e-14 * dq.amax());
        }
    }
}

#[test]
fn taper_integrals_converge_with_quadrature_order() {
    let rod = mixed_rod(L, oblique_base());
    let body = taper_body(L);
    let (rb, rt) = (0.02, 0.008);
    let dr = (rt - rb) / L;
    let r = |s: f64| rb + dr * s;
    // Exact ∫ r⁴ and ∫ r² over a piece.
    let int_pow =
        |a: f64, b: f64, k: i32| (r(b).powi(k + 1) - r(a).powi(k + 1)) / ((k + 1) as f64 * dr);
    let mat = *body.material();
    let mut errs_k = Vec::new();
    for ng in 1..=5 {
        let mut e: f64 = 0.0;
        for p in rod.pieces() {
            let (gi, vi) = integrated_constitutive(p, &body, &GaussLegendre::new(ng));
            let i4 = int_pow(p.start, p.end(), 4);
            let i2 = int_pow(p.start, p.end(), 2);
            let exact_g = Vec6::new(
                mat.shear_modulus() * PI * i4 / 2.0,
                mat.young() * PI * i4 / 4.0,
                mat.young() * PI * i4 / 4.0,
                mat.young() * PI * i2,
                mat.shear_modulus() * PI * i2,
                mat.shear_modulus() * PI * i2,
            );
            let exact_v = Vec6::new(
                mat.viscosity() * PI * i4 / 2.0,
                3.0 * mat.viscosity() * PI * i4 / 4.0,
                3.0 * mat.viscosity() * PI * i4 / 4.0,
                3.0 * mat.viscosity() * PI * i2,
                mat.viscosity() * PI * i2,
                mat.viscosity() * PI * i2,
            );
            for i in 0..6 {
                e = e.max((gi[i] - exact_g[i]).abs() / exact_g[i]);
                e = e.max((vi[i] - exact_v[i]).abs() / exact_v[i]);
            }
        }
        errs_k.push(e);
    }
    eprintln!(
        "taper ∫Γ, ∫γ per piece vs exact, n_g = 1..5: {}",
        fmt(&errs_k)
    );
    assert!(errs_k[0] > 1e-4 && errs_k[1] > 1e-8 && errs_k[1] < errs_k[0]);
    assert!(
        errs_k[2..].iter().all(|&e| e < 1e-14),
        "degree 4 is exact from 3 points"
    );

    // Gravity on a bent tapered rod: not polynomial in s; converges spectrally.
    let g = Vec3::new(0.5, -2.0, -9.81);
    let q = random_q(&rod, &mut Rng::new(23), 1.0);
    let reference = generalized_gravity_by_jacobian(&rod, &body, &g, &q, &gauss(20));
    let errs: Vec<f64> = (1..=7)
        .map(|n| {
            rel_err(
                &generalized_gravity_by_jacobian(&rod, &body, &g, &q, &gauss(n)),
                &reference,
            )
        })
        .collect();
    eprintln!(
        "taper gravity force vs 20-point rule, n_g = 1..7: {}",
        fmt(&errs)
    );
    assert!(
        errs.windows(2).all(|w| w[1] < w[0] || w[0] < 1e-14),
        "monotone convergence down to round-off"
    );
    assert!(errs[6] < 1e-11, "{}", errs[6]);
    let pot_ref = gravity_potential(&rod, &body, &g, &q, &gauss(20));
    let pot5 = gravity_potential(&rod, &body, &g, &q, &gauss(5));
    assert!((pot5 - pot_ref).abs() < 1e-8 * pot_ref.abs());
}

/// The cables of the FD tests: a varying routing with knots inside pieces,
/// spans starting and ending mid-piece, and a constant offset.
fn test_cables() -> Vec<Cable> {
    vec![
        Cable {
            routing: Routing::Path(vec![
                [0.02, 0.005, -0.003],
                [0.1, -0.004, 0.006],
                [0.2, 0.006, 0.002],
                [0.33, 0.0, -0.005],
            ]),
            tension: Tension::Constant(1.0),
            friction: 0.0,
            span: Span::Between {
                from: 0.04,
                to: 0.31,
            },
        },
        Cable {
            routing: Routing::Path(vec![
                [0.0, 0.0, 0.008],
                [0.25, 0.008, 0.0],
                [0.5, 0.0, -0.008],
            ]),
            tension: Tension::Constant(1.0),
            friction: 0.0,
            span: Span::Between {
                from: 0.0,
                to: 0.45,
            },
        },
        Cable {
            routing: Routing::Offset {
                y: 0.006,
                z: -0.004,
            },
            tension: Tension::Constant(1.0),
            friction: 0.0,
            span: Span::Between { from: 0.1, to: 0.4 },
        },
    ]
}

#[test]
fn cable_force_is_minus_gradient_of_length() {
    let mut worst: f64 = 0.0;
    for rod in [
        mixed_rod(L, oblique_base()),
        RodGeometry::uniform(L, 4, Basis::all(), straight(), identity_base()).unwrap(),
    ] {
        let quad = gauss(4);
        let mut rng = Rng::new(29);
        for cable in test_cables() {
            cable.validate(L).unwrap();
            for _ in 0..3 {
                let q = random_q(&rod, &mut rng, 0.5);
                let mut f = vec![0.0; rod.n_dof()];
                cable.add_force_per_tension(&rod, &q, &quad, &mut f);
                let f = DVector::from_vec(f);
                let fd = -fd_gradient(&q, 1e-6, |x| cable.length(&rod, x, &quad));
                worst = worst.max(rel_err(&f, &fd));
                // Coordinates of pieces wholly outside the span get nothing.
                let (from, to) = cable.bounds(L);
                for p in rod.pieces() {
                    if p.end() <= from || p.start >= to {
                        assert!(p.dofs().all(|c| f[c] == 0.0));
                    }
                }
            }
        }
    }
    eprintln!("cable: force per tension vs −∂ℓ_c/∂q (central FD): {worst:.1e}");
    assert!(worst < 1e-8, "{worst}");
}

#[test]
fn cable_straight_rod_sign_check() {
    // (D15) sign check: straight rod, d = (0, d, 0): τ_kz = +T d ℓ, τ_qx = −T ℓ.
    let rod = RodGeometry::uniform(L, 1, Basis::all(), straight(), identity_base()).unwrap();
    let c = Cable {
        routing: Routing::Offset { y: 0.01, z: 0.0 },
        tension: Tension::Constant(2.0),
        friction: 0.0,
        span: Span::Between { from: 0.0, to: L },
    };
    let mut f = vec![0.0; 6];
    c.add_force_per_tension(&rod, &[0.0; 6], &gauss(2), &mut f);
    let t = c.tension_at(0.0);
    assert!((t * f[2] - 2.0 * 0.01 * L).abs() < 1e-16);
    assert!((t * f[3] + 2.0 * L).abs() < 1e-15);
    assert_eq!([f[0], f[1], f[4], f[5]], [0.0; 4]);
    assert!((c.length(&rod, &[0.0; 6], &gauss(2)) - L).abs() < 1e-15);
}

/// Test-local cable wrench per tension `(d × t̂; t̂)` and its s-derivative for
/// given strain, `d`, `d′` (with `d″ = 0`).
fn wrench_and_derivative(xi: &Vec6, d: &Vec3, dp: &Vec3) -> (Wrench, Wrench) {
    let (k, q) = (angular(xi), linear(xi));
    let v = q + k.cross(d) + dp;
    let n = v.norm();
    let t = v / n;
    let vp = k.cross(dp);
    let tp = (vp - t * t.dot(&vp)) / n;
    (
        join(&d.cross(&t), &t),
        join(&(dp.cross(&t) + d.cross(&tp)), &tp),
    )
}

#[test]
fn cable_force_equals_projected_wrench_form() {
    // (D15), wrench form: distributed 𝓦′ + ad*_ξ 𝓦 on the span, point wrenches
    // 𝓦(b⁺) − 𝓦(b⁻) at every break (piece boundary, routing knot), −𝓦(to) at
    // the anchor and +𝓦(from) where the cable enters; projected with the
    // kinematics' Jacobian Jᵀ. Must equal −∂ℓ_c/∂q (per unit tension).
    let rod = mixed_rod(L, oblique_base());
    let ng = 12;
    let quad = gauss(ng);
    let mut rng = Rng::new(41);
    let mut kin = RodKinematics::new(&rod);
    let mut j = Matrix6xX::zeros(rod.n_dof());
    let mut worst: f64 = 0.0;
    for cable in test_cables() {
        let q = random_q(&rod, &mut rng, 0.5);
        kin.update(&rod, &q, None, None).unwrap();
        let mut breaks: Vec<f64> = rod.pieces().iter().map(|p| p.end()).collect();
        if let Routing::Path(pts) = &cable.routing {
            breaks.extend(pts.iter().map(|p| p[0]));
        }
        let (from, to) = cable.bounds(L);
        breaks.retain(|&b| b > from && b < to);
        breaks.push(from);
        breaks.push(to);
        breaks.sort_by(f64::total_cmp);
        breaks.dedup();
        let piece_of = |s: f64| {
            rod.pieces()
                .iter()
                .position(|p| s >= p.start && s < p.end())
                .unwrap()
        };
        // (strain, d, d′) at s on the sub-interval [lo, hi].
        let local = |s: f64, lo: f64, hi: f64| {
            let xi = rod.strain(piece_of(0.5 * (lo + hi)), &q);
            let dp = cable.offset(0.5 * (lo + hi)).1;
            (xi, cable.offset(s).0, dp)
        };
        let mut tau = DVector::zeros(rod.n_dof());
        let mut add = |s: f64, w: &Wrench, tau: &mut DVector<f64>| {
            kin.jacobian_at(&rod, s, Frame::Body, &mut j).unwrap();
            *tau += j.tr_mul(w);
        };
        for win in breaks.windows(2) {
            let (lo, hi) = (win[0], win[1]);
            for (x, wq) in quad.on_interval(hi - lo) {
                let s = lo + x;
                let (xi, d, dp) = local(s, lo, hi);
                let (w, wp) = wrench_and_derivative(&xi, &d, &dp);
                add(s, &((wp + coad_vec(&xi, &w)) * wq), &mut tau);
            }
            // Ends of the sub-interval: −𝓦(hi⁻) and +𝓦(lo⁺); interior breaks
            // thus get 𝓦(b⁺) − 𝓦(b⁻), the anchor −𝓦(to), the entry +𝓦(from).
            let (xi, d, dp) = local(hi, lo, hi);
            add(hi, &-wrench_and_derivative(&xi, &d, &dp).0, &mut tau);
            let (xi, d, dp) = local(lo, lo, hi);
            add(lo, &wrench_and_derivative(&xi, &d, &dp).0, &mut tau);
        }
        let mut f = vec![0.0; rod.n_dof()];
        cable.add_force_per_tension(&rod, &q, &quad, &mut f);
        let f = DVector::from_vec(f);
        worst = worst.max(rel_err(&tau, &f));
        // And the crate's wrench function is the same 𝓦/T.
        let s = 0.5 * (from + to);
        let (xi, d, _) = local(s, s - 1e-9, s + 1e-9);
        let dp = cable.offset(s).1;
        let w_here = wrench_and_derivative(&xi, &d, &dp).0;
        assert!((cable.wrench_per_tension(&xi, s) - w_here).amax() < 1e-15);
    }
    eprintln!(
        "cable: Jᵀ-projected wrench form vs strain-space (D15), {ng} Gauss points: {worst:.1e}"
    );
    assert!(worst < 1e-11, "{worst}");
}

/// Residual of the uniform-strain equilibrium of one piece, written out here
/// independently of the crate: `R(ξ) = Γ(ξ − ξ̄) + T (d × t̂; t̂)(ξ)`,
/// `t̂ = (q + k × d)/|q + k × d|` (the per-length version of
/// `Γ(ξ−ξ̄)ℓ = −Tℓ(d×t̂; t̂)`).
fn equilibrium_residual(gamma: &Vec6, rest: &Vec6, tension: f64, d: &Vec3, xi: &Vec6) -> Vec6 {
    let v = linear(xi) + angular(xi).cross(d);
    let t = v / v.norm();
    gamma.component_mul(&(xi - rest)) + join(&d.cross(&t), &t) * tension
}

/// Newton's method with a finite-difference Jacobian.
fn solve_equilibrium(gamma: &Vec6, rest: &Vec6, tension: f64, d: &Vec3) -> Vec6 {
    let mut xi = *rest;
    for _ in 0..50 {
        let r = equilibrium_residual(gamma, rest, tension, d, &xi);
        let mut jac = Matrix6::zeros();
        for c in 0..6 {
            let h = 1e-7;
            let mut xp = xi;
            xp[c] += h;
            let mut xm = xi;
            xm[c] -= h;
            let col = (equilibrium_residual(gamma, rest, tension, d, &xp)
                - equilibrium_residual(gamma, rest, tension, d, &xm))
                / (2.0 * h);
            jac.set_column(c, &col);
        }
        let step = jac.lu().solve(&r).unwrap();
        xi -= step;
        if step.amax() < 1e-15 {
            break;
        }
    }
    xi
}

#[test]
fn cable_uniform_strain_equilibrium() {
    let len = 0.2;
    let (e, nu) = (1e6, 0.45);
    let mat = Material::builder()
        .density(1000.0)
        .young(e)
        .poisson(nu)
        .build()
        .unwrap();
    let g_mod = e / (2.0 * (1.0 + nu));
    let quad = gauss(3);
    let mut report = Vec::new();
    for (section, (y, z), rest, tension) in [
        // Straight rod, rectangle (Jy ≠ Jz), offset in y and z.
        (
            Section::Rectangle {
                width: 0.02,
                height: 0.012,
            },
            (0.006, -0.004),
            straight(),
            0.5,
        ),
        // Precurved, twisted, sheared rest strain: t̂ leaves the x axis,
        // the equilibrium is genuinely nonlinear.
        (
            Section::Circle { radius: 0.01 },
            (0.007, 0.003),
            Vec6::new(2.0, 0.3, -0.4, 1.0, 0.05, -0.02),
            2.0,
        ),
    ] {
        let body = RodProperties::new(section, mat, len).unwrap();
        let rod = RodGeometry::uniform(len, 1, Basis::all(), rest, identity_base()).unwrap();
        let p = section.properties(0.0);
        // Γ from the textbook formulas, not from the crate.
        let gamma = Vec6::new(
            g_mod * (p.jy + p.jz),
            e * p.jy,
            e * p.jz,
            e * p.area,
            g_mod * p.area,
            g_mod * p.area,
        );
        let d = Vec3::new(0.0, y, z);
        let xi = solve_equilibrium(&gamma, &rest, tension, &d);
        // The crate's total force K q + e − T·(−∂ℓ/∂q) vanishes there.
        let q: Vec<f64> = (xi - rest).iter().copied().collect();
        let pm = piece_matrices(&rod, &body, None, &quad);
        let mut f = vec![0.0; 6];
        add_elastic_force(&rod, &pm, &q, &mut f);
        let mut fc = vec![0.0; 6];
        let cable = Cable {
            routing: Routing::Offset { y, z },
            tension: Tension::Constant(tension),
            friction: 0.0,
            span: Span::Between { from: 0.0, to: len },
        };
        cable.add_force_per_tension(&rod, &q, &quad, &mut fc);
        let t = cable.tension_at(0.0);
        let scale = t * len * (1.0 + d.norm());
        let res = f
            .iter()
            .zip(&fc)
            .map(|(a, b)| (a - t * b).abs())
            .fold(0.0, f64::max)
            / scale;
        report.push(res);
        assert!(res < 1e-12, "residual {res}");
        if rest == straight() {
            // First order (exact here, t̂ stays on x): κ = T d / (E J).
            let ky = -tension * z / (e * p.jy);
            let kz = tension * y / (e * p.jz);
            assert!((xi[1] - ky).abs() < 1e-12 * ky.abs(), "{} vs {ky}", xi[1]);
            assert!((xi[2] - kz).abs() < 1e-12 * kz.abs(), "{} vs {kz}", xi[2]);
            assert!((xi[3] - (1.0 - tension / (e * p.area))).abs() < 1e-14);
            assert!(xi[0].abs() < 1e-14 && xi[4].abs() < 1e-14 && xi[5].abs() < 1e-14);
        } else {
            // The nonlinearity matters: the linear (t̂ = x̂) guess is off.
            let lin_kz = rest[2] + tension * y / (e * p.jz);
            assert!((xi[2] - lin_kz).abs() > 1e-4 * lin_kz.abs());
        }
    }
    eprintln!(
        "cable equilibrium: crate residual at the independent Newton solution (rel): {}",
        fmt(&report)
    );
}

#[test]
fn constant_offset_cable_force_equals_gauss_rule_on_the_same_path() {
    // A constant offset integrates each piece in one evaluation (the
    // integrand is constant there); the same cable given as a two-point path
    // at that offset takes the general route, a Gauss rule per piece
    // (D15). The two must agree to rounding, whatever the span's overlap.
    let mut worst: f64 = 0.0;
    let mut rng = Rng::new(53);
    for rod in [
        mixed_rod(L, oblique_base()),
        RodGeometry::uniform(L, 4, Basis::all(), straight(), identity_base()).unwrap(),
    ] {
        let quad = gauss(4);
        for (y, z, span) in [
            (0.006, -0.004, Span::Between { from: 0.1, to: 0.4 }),
            (-0.008, 0.0, Span::Whole),
            (0.0, 0.007, Span::Between { from: 0.0, to: 0.2 }),
        ] {
            let offset = Cable {
                routing: Routing::Offset { y, z },
                tension: Tension::Constant(1.0),
                friction: 0.0,
                span,
            };
            let path = Cable {
                routing: Routing::Path(vec![[0.0, y, z], [L, y, z]]),
                ..offset.clone()
            };
            for _ in 0..4 {
                let q = random_q(&rod, &mut rng, 0.5);
                let mut a = vec![0.0; rod.n_dof()];
                let mut b = vec![0.0; rod.n_dof()];
                offset.add_force_per_tension(&rod, &q, &quad, &mut a);
                path.add_force_per_tension(&rod, &q, &quad, &mut b);
                let (a, b) = (DVector::from_vec(a), DVector::from_vec(b));
                assert!(b.amax() > 0.0);
                worst = worst.max(rel_err(&a, &b));
            }
        }
    }
    assert!(worst < 1e-13, "{worst}");
}
