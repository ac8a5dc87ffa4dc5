//! Criterion benches of the `softrod-lie` hot paths, each at a `ψ = xθ` below
//! the series switch (ψ = 1.2, Horner series) and above it (ψ = 4.0, closed
//! forms with one `sin_cos`).
//!
//! Regenerate (numbers in docs/performance.md):
//! `cargo bench -p softrod-benches --bench lie -- --warm-up-time 1 --measurement-time 2`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod_lie::{self as lie, Vec6};
use std::hint::black_box;

/// A fixed, seeded O(1) strain with |k| = 1 and a direction `δ`, so the runs
/// are reproducible; `x = ψ` then sets the regime.
fn inputs() -> (Vec6, Vec6) {
    // SplitMix64, seed 42.
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
    let delta = Vec6::from_fn(|_, _| next());
    (xi, delta)
}

/// (label, ψ): one point on each side of `series::PSI_SWITCH = 2.5`.
const REGIMES: [(&str, f64); 2] = [("series_psi1.2", 1.2), ("closed_psi4.0", 4.0)];

fn bench_lie(c: &mut Criterion) {
    let (xi, delta) = inputs();
    assert!(REGIMES[0].1 < lie::series::PSI_SWITCH && REGIMES[1].1 > lie::series::PSI_SWITCH);

    macro_rules! bench {
        ($name:literal, |$x:ident, $xi:ident, $d:ident| $body:expr) => {{
            let mut g = c.benchmark_group($name);
            for (label, psi) in REGIMES {
                // |k| = 1, so x = ψ.
                g.bench_with_input(BenchmarkId::from_parameter(label), &psi, |b, &psi| {
                    b.iter(|| {
                        let $x = black_box(psi);
                        let $xi = black_box(&xi);
                        let $d = black_box(&delta);
                        let _ = $d;
                        $body
                    })
                });
            }
            g.finish();
        }};
    }

    bench!("exp_twist", |x, xi, d| lie::exp_twist(x, xi));
    bench!("exp_ad", |x, xi, d| lie::exp_ad(x, xi));
    bench!("tangent", |x, xi, d| lie::tangent(x, xi));
    bench!("tangent_minus", |x, xi, d| lie::tangent_minus(x, xi));
    bench!("exp_and_tangent_minus", |x, xi, d| {
        lie::exp_and_tangent_minus(x, xi)
    });
    bench!("d_tangent_minus", |x, xi, d| lie::d_tangent_minus(x, xi, d));
    bench!(
        "d_tangent_minus_self",
        |x, xi, d| lie::d_tangent_minus_self(x, xi, d)
    );
}

criterion_group!(benches, bench_lie);
criterion_main!(benches);
