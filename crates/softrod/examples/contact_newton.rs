//! Why the structured Newton matrix of ESDIRK fails on a contact-heavy
//! scene (docs/performance.md, "Contact-heavy scenes"): at states along a
//! run, the contraction `ρ(I − W⁻¹ W_exact)` of the simplified Newton
//! iteration for iteration matrices `W` built from the structured one
//! (`M + a(K + K_c) + b(D + D_c)`, CT17, CT19–CT23) with missing terms
//! added back one group at a time.
//!
//! `W_exact = M + a ∂r/∂q + b ∂r/∂q̇` of the force residual
//! `r = ID(q, q̇, q̈)` at the state's `q̈`, by central differences of the
//! inverse dynamics (independent of the analytic Jacobian), and split by
//! source with the same scene without friction and without obstacles:
//! friction, the normal contact law, the rest (gravity, Coriolis, tension:
//! the non-contact geometric terms), each in its `a` (stiffness) and `b`
//! (damping) part. The structured matrix's columns come from its solve
//! applied to unit vectors.
//!
//! ```sh
//! cargo run --release -p softrod --example contact_newton -- \
//!     benches/scenes/cosseratbench/capstan.toml 0.001,0.002,0.003 1e-4,3e-4
//! ```

use nalgebra::{DMatrix, DVector};
use softrod::Simulation;
use softrod_dynamics::{forward_dynamics, inverse_dynamics, mass_matrix};
use softrod_integrate::{RodSystem, SecondOrderSystem};

const GAMMA: f64 = 0.25;

fn system(text: &str, name: &str) -> RodSystem {
    let (sim, _, _) = Simulation::from_toml(text, name).expect("scene");
    let mut sys = RodSystem::new(sim.model().clone());
    // CT26 on with `SOFTROD_CONTACT_WHOLE=1` (the "S with CT26" column).
    sys.contact_active_set = std::env::var_os("SOFTROD_CONTACT_WHOLE").is_some();
    sys
}

/// `∂r/∂q`, `∂r/∂q̇` of the inverse dynamics by central differences.
fn residual_jacobians(
    sys: &mut RodSystem,
    t: f64,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = q.len();
    let mut dq = DMatrix::zeros(n, n);
    let mut dv = DMatrix::zeros(n, n);
    let (mut qp, mut vp) = (q.to_vec(), qd.to_vec());
    for j in 0..n {
        let hq = 1e-7 * (1.0 + q[j].abs());
        qp[j] = q[j] + hq;
        let rp = inverse_dynamics(&sys.model, &mut sys.data, t, &qp, qd, qdd)
            .unwrap()
            .clone();
        qp[j] = q[j] - hq;
        let rm = inverse_dynamics(&sys.model, &mut sys.data, t, &qp, qd, qdd).unwrap();
        dq.set_column(j, &((rp - rm) / (2.0 * hq)));
        qp[j] = q[j];
        let hv = 1e-7 * (1.0 + qd[j].abs());
        vp[j] = qd[j] + hv;
        let rp = inverse_dynamics(&sys.model, &mut sys.data, t, q, &vp, qdd)
            .unwrap()
            .clone();
        vp[j] = qd[j] - hv;
        let rm = inverse_dynamics(&sys.model, &mut sys.data, t, q, &vp, qdd).unwrap();
        dv.set_column(j, &((rp - rm) / (2.0 * hv)));
        vp[j] = qd[j];
    }
    (dq, dv)
}

/// The structured Newton matrix `W_s` (dense, by inverting its solve).
fn structured(
    sys: &mut RodSystem,
    t: f64,
    q: &DVector<f64>,
    qd: &DVector<f64>,
    a: f64,
    b: f64,
) -> DMatrix<f64> {
    let n = q.len();
    sys.linearize_shifted(t, q, qd).unwrap();
    assert!(sys.factor_shifted_mass(t, q, a, b).unwrap());
    let mut inv = DMatrix::zeros(n, n);
    let mut x = DVector::zeros(n);
    for j in 0..n {
        x.fill(0.0);
        x[j] = 1.0;
        sys.solve_shifted_mass(&mut x).unwrap();
        inv.set_column(j, &x);
    }
    inv.try_inverse().expect("invertible")
}

fn rho(w: &DMatrix<f64>, exact: &DMatrix<f64>) -> f64 {
    let n = w.nrows();
    let e = DMatrix::identity(n, n) - w.clone().lu().solve(exact).expect("solvable");
    e.complex_eigenvalues()
        .iter()
        .map(|z| z.norm())
        .fold(0.0, f64::max)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).expect("scene path");
    let times: Vec<f64> = args
        .get(2)
        .map_or("0.001", |s| s.as_str())
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let steps: Vec<f64> = args
        .get(3)
        .map_or("1e-4", |s| s.as_str())
        .split(',')
        .map(|s| s.parse().unwrap())
        .collect();
    let text = std::fs::read_to_string(path).expect("scene");
    let no_friction = text.replace("friction = 0.3", "friction = 0.0");
    let cut = text.find("[[obstacle]]").expect("an obstacle");
    let rest = &text[cut..];
    let end = rest.find("\n\n[").map_or(rest.len(), |e| e + 1);
    let no_contact = format!("{}{}", &text[..cut], &rest[end..]);
    println!(
        "| t [ms] | h [s] | touching | S (CT17) | S − contact | S + geometric (CT19–23) | S + friction a | S + friction b | S + normal a | S + normal b | S + rest a | S + rest b | S + all contact | S + all but rest a |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for &t_end in &times {
        let (mut sim, _, _) = Simulation::from_toml(&text, path).expect("scene");
        let traj = sim.simulate(t_end).expect("run");
        let q = traj.q.last().unwrap().clone();
        let qd = traj.qdot.last().unwrap().clone();
        let touching = sim
            .contacts(t_end, q.as_slice(), qd.as_slice())
            .unwrap()
            .len();
        let mut full = system(&text, path);
        let mut nof = system(&no_friction, path);
        let mut noc = system(&no_contact, path);
        sim.contact_state_into(&mut full.data);
        sim.contact_state_into(&mut nof.data);
        let qdd = forward_dynamics(
            &full.model,
            &mut full.data,
            t_end,
            q.as_slice(),
            qd.as_slice(),
            None,
        )
        .unwrap()
        .clone();
        let m = mass_matrix(&full.model, &mut full.data, q.as_slice())
            .unwrap()
            .clone();
        let (kq, kv) = residual_jacobians(
            &mut full,
            t_end,
            q.as_slice(),
            qd.as_slice(),
            qdd.as_slice(),
        );
        let (nq, nv) =
            residual_jacobians(&mut nof, t_end, q.as_slice(), qd.as_slice(), qdd.as_slice());
        let (cq, cv) =
            residual_jacobians(&mut noc, t_end, q.as_slice(), qd.as_slice(), qdd.as_slice());
        for &h in &steps {
            let (a, b) = (h * h * GAMMA * GAMMA, h * GAMMA);
            let exact = &m + &kq * a + &kv * b;
            // The structured matrix and its parts (linear in a, b).
            let s = structured(&mut full, t_end, &q, &qd, a, b);
            let s_a = structured(&mut full, t_end, &q, &qd, a, 0.0);
            let s0 = structured(&mut full, t_end, &q, &qd, 0.0, 0.0);
            let sf_a = &s_a - &s0;
            let sf_b = &s - &s_a;
            let sn = structured(&mut nof, t_end, &q, &qd, a, b);
            let sn_a = structured(&mut nof, t_end, &q, &qd, a, 0.0);
            let (sn_a, sn_b) = (&sn_a - &s0, &sn - &sn_a);
            let sc = structured(&mut noc, t_end, &q, &qd, a, b);
            let sc_a = structured(&mut noc, t_end, &q, &qd, a, 0.0);
            let (sc_a, sc_b) = (&sc_a - &s0, &sc - &sc_a);
            // Exact − structured, per source and kind.
            let fric_a = (&kq - &nq) * a - (&sf_a - &sn_a);
            let fric_b = (&kv - &nv) * b - (&sf_b - &sn_b);
            let norm_a = (&nq - &cq) * a - (&sn_a - &sc_a);
            let norm_b = (&nv - &cv) * b - (&sn_b - &sc_b);
            let rest_a = &cq * a - &sc_a;
            let rest_b = &cv * b - &sc_b;
            full.geometric_in_shifted = true;
            let sg = structured(&mut full, t_end, &q, &qd, a, b);
            full.geometric_in_shifted = false;
            let all_c = &s + &fric_a + &fric_b + &norm_a + &norm_b;
            let all_but_ra = &all_c + &rest_b;
            let rows = [
                rho(&s, &exact),
                rho(&sc, &exact),
                rho(&sg, &exact),
                rho(&(&s + &fric_a), &exact),
                rho(&(&s + &fric_b), &exact),
                rho(&(&s + &norm_a), &exact),
                rho(&(&s + &norm_b), &exact),
                rho(&(&s + &rest_a), &exact),
                rho(&(&s + &rest_b), &exact),
                rho(&all_c, &exact),
                rho(&all_but_ra, &exact),
            ];
            let cells: Vec<String> = rows.iter().map(|r| format!("{r:.3}")).collect();
            println!(
                "| {} | {h:e} | {touching} | {} |",
                t_end * 1e3,
                cells.join(" | ")
            );
        }
    }
}
