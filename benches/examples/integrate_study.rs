//! Exploration harness (issue 13): one scene, one method, one setting.
//!
//! `SCENE=planar|3d|wire PIECES=32 T1=1 METHOD=dopri5|rosw|ga|li RTOL=1e-6 DT=1e-3 RHO=0.8`

use softrod_benches::rod_scenes::*;
use softrod_integrate::{Method, Options, RodJacobian};

fn env<T: std::str::FromStr>(k: &str, d: T) -> T {
    std::env::var(k)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(d)
}

fn main() {
    let scene: String = env("SCENE", "planar".to_string());
    let pieces: usize = env("PIECES", 32);
    let t1: f64 = env("T1", 1.0);
    let nout: usize = env("NOUT", 1000);
    let model = match scene.as_str() {
        "planar" => planar_release(),
        "3d" => release_3d(pieces),
        "wire" => steel_wire(pieces),
        s => panic!("scene {s}"),
    };
    let ts = times(t1, nout);
    let refname = format!("{scene}_{}_{t1}_{nout}_dopri5_1e-10", model.n_dof());
    let (rf, info) = reference(
        &refname,
        &model,
        Method::Dopri5,
        &Options::tol(1e-10, 1e-12),
        &ts,
    );
    if let Some(m) = info {
        println!("reference {refname}: {:?} wall {:.1} s", m.stats, m.wall);
    }
    let method: String = env("METHOD", "dopri5".to_string());
    let rtol: f64 = env("RTOL", 1e-6);
    let atol: f64 = env("ATOL", rtol * 1e-3);
    let dt: f64 = env("DT", 1e-3);
    let rho: f64 = env("RHO", 0.8);
    let elastic = env("ELASTIC", 0) == 1;
    let (m, o) = match method.as_str() {
        "dopri5" => (Method::Dopri5, Options::tol(rtol, atol)),
        "rosw" => (Method::Rosw34, Options::tol(rtol, atol)),
        "ga" => (
            Method::GeneralizedAlpha { rho_inf: rho },
            Options::fixed(dt),
        ),
        "gatol" => (
            Method::GeneralizedAlpha { rho_inf: rho },
            Options::tol(rtol, atol),
        ),
        "li" => (
            Method::GeneralizedAlpha { rho_inf: rho },
            Options::linearly_implicit(dt),
        ),
        "esdirk" => (
            Method::Esdirk46,
            if env("H0", 0.0) > 0.0 {
                Options::tol(rtol, atol).with_h0(env("H0", 0.0))
            } else {
                Options::tol(rtol, atol)
            },
        ),
        "radau" => (Method::Radau5, Options::tol(rtol, atol)),
        "radaufix" => (Method::Radau5, Options::fixed(dt)),
        "esdirkfix" => (Method::Esdirk46, Options::fixed(dt)),
        s => panic!("method {s}"),
    };
    let o = match env("NTOL", 0.0) {
        t if t > 0.0 => softrod_integrate::Options {
            iteration: softrod_integrate::Iteration::Newton {
                tol: t,
                max_iter: env("NIT", 8),
            },
            ..o
        },
        _ => o,
    };
    let r = measure(
        &model,
        |s| {
            if elastic {
                s.jacobian = RodJacobian::ElasticOnly
            }
        },
        m,
        &o,
        &ts,
        env("BUDGET", 600.0),
    );
    match r {
        Ok(r) => println!(
            "{scene} n_dof {} {method} rtol {rtol:e} dt {dt:e}: max tip error {:.3e} m, wall {:.3} s, {:?}",
            model.n_dof(),
            max_error(&r.tips, &rf),
            r.wall,
            r.stats
        ),
        Err(e) => println!("{scene} {method}: failed: {e}"),
    }
}
