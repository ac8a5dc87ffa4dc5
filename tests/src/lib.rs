//! Shared helpers of the validation suite; the cases live in `tests/*.rs`
//! and the document generators in `examples/`.

pub mod extreme;

/// Composite Simpson rule of `f` on `[a, b]` with `m` (even) intervals:
/// the independent quadrature the tapered-rod references are built with.
pub fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, m: usize) -> f64 {
    assert!(
        m >= 2 && m % 2 == 0,
        "Simpson needs an even number of intervals"
    );
    let h = (b - a) / m as f64;
    (0..=m)
        .map(|k| {
            let w = if k == 0 || k == m {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            w * f(a + k as f64 * h)
        })
        .sum::<f64>()
        * h
        / 3.0
}

/// The repository README's code: its Rust program compiled and run as a
/// doctest exactly as pasted (`tests/tests/readme_blocks.rs` checks its
/// TOML blocks, `crates/softrod-py/tests/test_readme.py` its Python).
#[doc = include_str!("../../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
