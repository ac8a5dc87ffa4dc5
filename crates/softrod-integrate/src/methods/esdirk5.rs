//! ESDIRK5(4)7L\[2\]SA for second-order systems `q̈ = a(t, q, q̇)`: the
//! tableau of Kennedy & Carpenter's ESDIRK5(4)7L\[2\]SA₁ (C. A. Kennedy,
//! M. H. Carpenter, "Diagonally implicit Runge–Kutta methods for ordinary
//! differential equations. A review", NASA/TM-2016-219173, Table 25): seven
//! stages, the first explicit, six implicit with the same diagonal
//! `γ = 0.184`, order 5 with an embedded order-4 solution, L-stable, stiffly
//! accurate (`b` is the last row of `A`), stage order 2. The order
//! conditions (all 17 trees to order 5 for `b`, the 8 to order 4 for `b̂`),
//! the row sums, the stage order and the stability function are checked by
//! this module's tests, not taken from the transcription.
//!
//! Everything else is [`super::Esdirk`]'s, run on this tableau
//! ([`super::esdirk::Tableau`]): each implicit
//! stage `Vᵢ = v̂ᵢ + hγ Aᵢ`, `Qᵢ = q̂ᵢ + hγ Vᵢ`, `Aᵢ = a(tₙ + cᵢh, Qᵢ, Vᵢ)` is
//! one equation in its acceleration, solved by simplified Newton on the
//! force residual with the structured O(N) matrix `M + h²γ²K + hγD`
//! ([`SecondOrderSystem::factor_shifted_mass`]) and the exact dense Jacobian
//! as fallback; the embedded estimate `h Σ (bᵢ − b̂ᵢ)(Vᵢ, Aᵢ)` filtered by
//! `(I − hγJ)⁻¹` and measured as positions; quintic Hermite dense output
//! (`O(h⁶)` in `q`, `O(h⁵)` in `q̇`: not below the method's order). What
//! differs: the estimate is `O(h⁵)`, so the controller's exponent is `1/5`
//! (Gustafsson's predictive form as before), and a step costs six implicit
//! stages instead of five. The discrete adjoint and the forward
//! sensitivities (`crate::adjoint`, `crate::sensitivity`) run on this
//! tableau as on ESDIRK4(3)6L\[2\]SA's (docs/theory-control.md G27).

// The coefficients are transcribed with all the digits published.
#![allow(clippy::excessive_precision)]
// Negated comparisons are deliberate: a NaN must fail every check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::esdirk::{Esdirk, Tableau};

const S: usize = 7;
/// The diagonal of the implicit stages.
const GAMMA: f64 = 0.184;
/// Nodes `cᵢ = Σⱼ aᵢⱼ` (`c₆ = 1.04` lies beyond the step: the stage is
/// evaluated there all the same, as the method is defined).
const C: [f64; S] = [
    0.0,
    0.368,
    0.10778470452335051,
    0.52,
    0.6531582768582439,
    1.04,
    1.0,
];
/// `aᵢⱼ` (lower triangular, `γ` on the diagonal from the second stage).
const A: [[f64; S]; S] = [
    [0.0; S],
    [GAMMA, GAMMA, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        -0.038107647738324729,
        -0.038107647738324743,
        GAMMA,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        0.021677664958778542,
        0.0216776649587785,
        0.29264467008244299,
        GAMMA,
        0.0,
        0.0,
        0.0,
    ],
    [
        -0.85104626617351575,
        -0.85104626617351564,
        1.7533038157326979,
        0.41794699347257747,
        GAMMA,
        0.0,
        0.0,
    ],
    [
        -5.0356161217492197,
        -5.0356161217492197,
        8.9713052937951279,
        0.31505839963851934,
        1.6408685500647917,
        GAMMA,
        0.0,
    ],
    [
        -0.075998114543861517,
        -0.075998114543861378,
        0.42427748359919076,
        0.27546898147535387,
        0.32051077889797169,
        -0.052261014884793552,
        GAMMA,
    ],
];
/// Weights of the embedded order-4 solution (`b` is the last row of `A`).
const B_HAT: [f64; S] = [
    -0.108049345454303,
    -0.10804934545430295,
    0.48372757888653789,
    0.23595105756244605,
    0.37538336433425512,
    -0.032306662513724778,
    0.15334335263909166,
];
/// The step-size exponent: `1/(q + 1)` for the order-`q = 4` estimate.
const EXPONENT: f64 = 0.2;

/// The ESDIRK5(4)7L\[2\]SA tableau.
pub(crate) struct Esdirk54;

impl Tableau for Esdirk54 {
    const S: usize = S;
    const GAMMA: f64 = GAMMA;
    const C: &'static [f64] = &C;
    const A: &'static [&'static [f64]] = &[&A[0], &A[1], &A[2], &A[3], &A[4], &A[5], &A[6]];
    const B_HAT: &'static [f64] = &B_HAT;
    const EXPONENT: f64 = EXPONENT;
    const START_ORDER: i32 = 4;
}

/// ESDIRK5(4)7L\[2\]SA: [`Esdirk`] on [`Esdirk54`].
pub(crate) type Esdirk5 = Esdirk<Esdirk54>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The row sums `cᵢ = Σⱼ aᵢⱼ`, stage order 2 (`Σⱼ aᵢⱼ cⱼ = cᵢ²/2`), and
    /// the order conditions of every rooted tree up to order 5 for `b` (the
    /// last row of `A`) and up to order 4 for `b̂`, with the order-5 ones
    /// violated by `b̂` (Butcher's conditions `Φ(t) = 1/t!`: Hairer–Nørsett–
    /// Wanner, *ODEs I*, Table II.2.2, the nine trees of order 5 from §II.2).
    #[test]
    fn tableau_satisfies_the_order_conditions() {
        let b = A[S - 1];
        let tol = 2e-14;
        for i in 0..S {
            let c: f64 = A[i].iter().sum();
            assert!((c - C[i]).abs() < tol, "row {i}: {c} vs {}", C[i]);
            let ac: f64 = (0..S).map(|j| A[i][j] * C[j]).sum();
            if i >= 1 {
                assert!((ac - C[i] * C[i] / 2.0).abs() < tol, "stage order, row {i}");
            }
        }
        // Vectors over the stages and the products that build the trees.
        type V = [f64; S];
        let mul = |x: &V, y: &V| -> V { std::array::from_fn(|i| x[i] * y[i]) };
        let am = |x: &V| -> V { std::array::from_fn(|i| (0..S).map(|j| A[i][j] * x[j]).sum()) };
        let dot = |w: &V, x: &V| (0..S).map(|i| w[i] * x[i]).sum::<f64>();
        let one: V = [1.0; S];
        let c = C;
        let c2 = mul(&c, &c);
        let c3 = mul(&c2, &c);
        let c4 = mul(&c3, &c);
        let ac = am(&c);
        let ac2 = am(&c2);
        let aac = am(&ac);
        // (tree's elementary weight argument, 1/γ(t)), by order.
        let trees: [(usize, V, f64); 17] = [
            (1, one, 1.0),
            (2, c, 1.0 / 2.0),
            (3, c2, 1.0 / 3.0),
            (3, ac, 1.0 / 6.0),
            (4, c3, 1.0 / 4.0),
            (4, mul(&c, &ac), 1.0 / 8.0),
            (4, ac2, 1.0 / 12.0),
            (4, aac, 1.0 / 24.0),
            (5, c4, 1.0 / 5.0),
            (5, mul(&c2, &ac), 1.0 / 10.0),
            (5, mul(&c, &ac2), 1.0 / 15.0),
            (5, mul(&c, &aac), 1.0 / 30.0),
            (5, mul(&ac, &ac), 1.0 / 20.0),
            (5, am(&c3), 1.0 / 20.0),
            (5, am(&mul(&c, &ac)), 1.0 / 40.0),
            (5, am(&ac2), 1.0 / 60.0),
            (5, am(&aac), 1.0 / 120.0),
        ];
        for (k, (order, x, want)) in trees.iter().enumerate() {
            let got = dot(&b, x);
            assert!(
                (got - want).abs() < tol,
                "b, tree {k} (order {order}): {got} vs {want}"
            );
            let got = dot(&B_HAT, x);
            if *order <= 4 {
                assert!(
                    (got - want).abs() < tol,
                    "b̂, tree {k} (order {order}): {got} vs {want}"
                );
            }
        }
        // The embedded solution is of order 4 only: some order-5 tree fails.
        let worst = trees
            .iter()
            .filter(|t| t.0 == 5)
            .map(|(_, x, want)| (dot(&B_HAT, x) - want).abs())
            .fold(0.0, f64::max);
        assert!(worst > 1e-6, "b̂ satisfies order 5: {worst}");
    }

    /// The stability function `R(z) = 1 + z bᵀ(I − zA)⁻¹𝟙` of `b` and of
    /// `b̂` at complex `z` by forward substitution.
    fn stability(w: &[f64; S], z: nalgebra::Complex<f64>) -> f64 {
        let one = nalgebra::Complex::new(1.0, 0.0);
        let mut k = [nalgebra::Complex::new(0.0, 0.0); S];
        for i in 0..S {
            let mut s = one;
            for j in 0..i {
                s += z * A[i][j] * k[j];
            }
            k[i] = s / (one - z * A[i][i]);
        }
        (one + z * (0..S).map(|i| k[i] * w[i]).sum::<nalgebra::Complex<f64>>()).norm()
    }

    /// L-stability: `R(z) → 0` as `z → −∞`; `|R| ≤ 1` on the imaginary axis
    /// (where the undamped modes of a rod live) and in the left half-plane
    /// on a grid (A-stability, by the maximum principle the axis suffices
    /// for a function analytic there: the poles are at `1/γ > 0`).
    #[test]
    fn stability_function_is_l_stable() {
        let z = |re: f64, im: f64| nalgebra::Complex::new(re, im);
        let b = A[S - 1];
        assert!(stability(&b, z(-1e8, 0.0)) < 1e-6);
        for k in -40..=60 {
            let w = 10f64.powf(k as f64 / 10.0);
            let r = stability(&b, z(0.0, w));
            assert!(r <= 1.0 + 1e-14, "|R({w}i)| = {r}");
        }
        for re in [-0.1, -1.0, -10.0, -100.0] {
            for im in [0.0, 0.5, 3.0, 30.0] {
                assert!(stability(&b, z(re, im)) <= 1.0 + 1e-14);
            }
        }
    }
}
