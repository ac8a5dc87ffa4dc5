//! Runs the group exponential of the `exp_twist` criterion bench
//! (`benches/benches/lie.rs`: |k| = 1, so `x = ψ`) for
//! `valgrind --tool=callgrind`; one call of `one_exp` (never inlined) is one
//! bench iteration:
//! `PSI=4.0 N_ITER=100000 cargo run --release -p softrod-lie --example exp_timing`
//! (`PSI=1.2` for the series branch).
use softrod_lie::{self as lie, Pose, Vec6};
use std::hint::black_box;

/// The bench's strain (`inputs` in benches/benches/lie.rs: SplitMix64, seed 42).
fn strain() -> Vec6 {
    let mut state: u64 = 42;
    let mut next = || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    };
    let mut xi = Vec6::from_fn(|_, _| next());
    let theta = lie::angular(&xi).norm();
    for i in 0..3 {
        xi[i] /= theta;
    }
    xi
}

#[inline(never)]
fn one_exp(x: f64, xi: &Vec6) -> Pose {
    lie::exp_twist(black_box(x), black_box(xi))
}

fn main() {
    let psi: f64 = std::env::var("PSI")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4.0);
    let iters: usize = std::env::var("N_ITER")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let xi = strain();
    let t0 = std::time::Instant::now();
    let mut acc = 0.0;
    for _ in 0..iters {
        acc += black_box(one_exp(psi, &xi)).translation[0];
    }
    println!(
        "psi = {psi}: {:.2} ns per exp_twist (checksum {acc:.6e})",
        t0.elapsed().as_secs_f64() / iters as f64 * 1e9
    );
}
