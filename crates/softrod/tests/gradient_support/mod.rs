//! What the gradient test files share: central differences of whole runs
//! and the comparison of an adjoint entry with them.

/// Central difference of `f` at `x` with relative step 1e-6 (absolute
/// `floor` for a zero `x`).
pub fn central(x: f64, floor: f64, f: impl Fn(f64) -> f64) -> f64 {
    let d = (1e-6 * x.abs()).max(floor);
    (f(x + d) - f(x - d)) / (2.0 * d)
}

/// Asserts that the gradient entry `adjoint` equals the central difference
/// `differences` to 1e-6, relative to the larger of `|differences|` and
/// `scale` (for entries near zero).
pub fn agree(name: &str, adjoint: f64, differences: f64, scale: f64) {
    let err = (adjoint - differences).abs() / differences.abs().max(scale);
    eprintln!("{name}: adjoint {adjoint:e}, differences {differences:e}, relative {err:e}");
    assert!(
        err < 1e-6,
        "{name}: adjoint {adjoint:e}, differences {differences:e}, relative {err:e}"
    );
}
