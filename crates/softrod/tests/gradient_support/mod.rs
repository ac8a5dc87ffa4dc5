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

/// `base` for the runs of `s`: Radau IIA measures its Newton iteration
/// against its internal tolerance `0.1·rtol^(2/3)` (RADAU5's), 46× the
/// `rtol = 1e-8` of the test scenes; `newton_tol` scaled by
/// `rtol / (0.1·rtol^(2/3))` solves its stage equations to the same
/// absolute accuracy as the ESDIRK runs, so the differences carry the
/// same Newton noise (error / step) — with `base`'s 1e-3 as is, it is
/// 4e-7 relative on a q0 entry with a 1e-6 step (measured).
#[allow(dead_code)]
pub fn options_for(
    s: &softrod::Simulation,
    base: softrod::GradientOptions,
) -> softrod::GradientOptions {
    let settings = s.settings();
    if settings.integrator.name() != "radau5" {
        return base;
    }
    let internal = 0.1 * settings.rtol.powf(2.0 / 3.0);
    softrod::GradientOptions {
        newton_tol: base.newton_tol.map(|t| t * settings.rtol / internal),
        ..base
    }
}
