//! Scalar coefficient functions of `ψ = x·θ`, closed form or series.
//!
//! Every analytic function of `x·ad_ξ` is a quartic in `ad_ξ` (docs/theory.md
//! (D1): `ad_ξ⁵ = −2θ²ad_ξ³ − θ⁴ad_ξ`), whose coefficients depend on `ψ` only and
//! are even in `ψ`. The closed forms lose accuracy like `ε/ψ^{2…7}` near 0, so
//! below [`PSI_SWITCH`] they are replaced by their Taylor series in `u = ψ²`
//! ((D5), [`SERIES_TERMS`] terms, Horner). Measured against a 60-digit
//! reference, both sides are accurate to ≤ 6e-16 relative for `τ_i`, `a, b, c`
//! and ≤ 4e-15 for `ρ_i` (docs/theory.md §1, table).

/// Switch point `ψ*`: series below, closed form at and above.
pub const PSI_SWITCH: f64 = 2.5;
/// Number of series terms (`m = 0 … SERIES_TERMS−1`).
pub const SERIES_TERMS: usize = 14;

const N: usize = SERIES_TERMS;

/// `1/n!` for `n = 0 … 2N+6`, computed at compile time.
const fn inv_factorials() -> [f64; 2 * N + 7] {
    let mut out = [0.0; 2 * N + 7];
    let mut f = 1.0;
    let mut n = 0;
    while n < 2 * N + 7 {
        if n > 0 {
            f /= n as f64;
        }
        out[n] = f;
        n += 1;
    }
    out
}

const INV_FACT: [f64; 2 * N + 7] = inv_factorials();

/// `c_{i,m}` of (D5), `i = 1…4`: `(−1)^m (1∓m)/(2m+i)!`.
const fn c_im(i: usize, m: usize) -> f64 {
    let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
    let num = if i <= 2 {
        1.0 - m as f64
    } else {
        1.0 + m as f64
    };
    sign * num * INV_FACT[2 * m + i]
}

/// Series of `τ_i`: `c_{i,m}/(i+2m+1)`, rows `i = 1…4`.
const fn tau_series() -> [[f64; N]; 4] {
    let mut out = [[0.0; N]; 4];
    let mut i = 1;
    while i <= 4 {
        let mut m = 0;
        while m < N {
            out[i - 1][m] = c_im(i, m) / ((i + 2 * m + 1) as f64);
            m += 1;
        }
        i += 1;
    }
    out
}

/// Series of `ρ_i = τ_i′/ψ`: coefficient of `u^{m−1}` is `2m c_{i,m}/(i+2m+1)`,
/// `m = 1…N` (one term more than `τ` because `ρ` is the least accurate family).
const fn rho_series() -> [[f64; N]; 4] {
    let mut out = [[0.0; N]; 4];
    let mut i = 1;
    while i <= 4 {
        let mut m = 1;
        while m <= N {
            out[i - 1][m - 1] = 2.0 * (m as f64) * c_im(i, m) / ((i + 2 * m + 1) as f64);
            m += 1;
        }
        i += 1;
    }
    out
}

/// Series of `a, b, c` of (D4): `(−1)^m/(2m+1+j)!`, `j = 0, 1, 2`.
const fn abc_series() -> [[f64; N]; 3] {
    let mut out = [[0.0; N]; 3];
    let mut j = 0;
    while j < 3 {
        let mut m = 0;
        while m < N {
            let sign = if m % 2 == 0 { 1.0 } else { -1.0 };
            out[j][m] = sign * INV_FACT[2 * m + 1 + j];
            m += 1;
        }
        j += 1;
    }
    out
}

const TAU_SERIES: [[f64; N]; 4] = tau_series();
const RHO_SERIES: [[f64; N]; 4] = rho_series();
const ABC_SERIES: [[f64; N]; 3] = abc_series();

/// Coefficient tables laid out term by term (`rows[m][j]` = coefficient `m`
/// of family `j`), 16-byte aligned, so the Horner steps of neighbouring
/// families run side by side in the two lanes of one SIMD register. Padding
/// lanes hold zeros and are never read by the callers.
#[repr(C, align(16))]
struct Packed<const F: usize> {
    rows: [[f64; F]; N],
}

const fn pack<const F: usize>(fams: &[&[f64; N]]) -> Packed<F> {
    let mut rows = [[0.0; F]; N];
    let mut j = 0;
    while j < fams.len() {
        let mut m = 0;
        while m < N {
            rows[m][j] = fams[j][m];
            m += 1;
        }
        j += 1;
    }
    Packed { rows }
}

/// `[a, b, c, ·]`.
static ABC_P: Packed<4> = pack(&[&ABC_SERIES[0], &ABC_SERIES[1], &ABC_SERIES[2]]);
/// `[a, b, c, τ₃, τ₄, ·]`.
static ABC_T34_P: Packed<6> = pack(&[
    &ABC_SERIES[0],
    &ABC_SERIES[1],
    &ABC_SERIES[2],
    &TAU_SERIES[2],
    &TAU_SERIES[3],
]);
/// `[a, b, c, τ₂, τ₃, τ₄, ρ₁, …, ρ₄]`: what a point of a moving piece needs
/// ([`abc_tau234_rho`]), five lane pairs where the three tables of
/// [`abc_tau_rho`] take six.
static ABC_T234_RHO_P: Packed<10> = pack(&[
    &ABC_SERIES[0],
    &ABC_SERIES[1],
    &ABC_SERIES[2],
    &TAU_SERIES[1],
    &TAU_SERIES[2],
    &TAU_SERIES[3],
    &RHO_SERIES[0],
    &RHO_SERIES[1],
    &RHO_SERIES[2],
    &RHO_SERIES[3],
]);
/// `[τ₁, …, τ₄]`.
static TAU_P: Packed<4> = pack(&[
    &TAU_SERIES[0],
    &TAU_SERIES[1],
    &TAU_SERIES[2],
    &TAU_SERIES[3],
]);
/// `[ρ₁, …, ρ₄]`.
static RHO_P: Packed<4> = pack(&[
    &RHO_SERIES[0],
    &RHO_SERIES[1],
    &RHO_SERIES[2],
    &RHO_SERIES[3],
]);

/// Horner in `u` on every family of a packed table at once. Plain
/// `acc * u + c` on purpose, not `f64::mul_add`: on the default `x86_64`
/// target (no `fma` feature) `mul_add` is an out-of-line libm call per step,
/// which made the series branch ~3× slower than the closed forms; the
/// separate rounding costs nothing measurable in accuracy
/// (tests/accuracy.rs) and gives the same bits on every target. Each lane
/// performs exactly the operations of a one-family Horner loop, so packing
/// changes no bit of the results.
///
/// Only the first `n ≤ N` terms are summed ([`terms`]); a constant term
/// count per arm lets the compiler unroll each loop (a runtime bound would
/// cost more in loop overhead than the terms saved).
#[inline(always)]
fn horner_packed<const F: usize>(t: &Packed<F>, u: f64, n: usize) -> [f64; F] {
    match n {
        7 => horner_packed_k::<F, 7>(t, u),
        8 => horner_packed_k::<F, 8>(t, u),
        10 => horner_packed_k::<F, 10>(t, u),
        11 => horner_packed_k::<F, 11>(t, u),
        12 => horner_packed_k::<F, 12>(t, u),
        _ => horner_packed_k::<F, N>(t, u),
    }
}

#[inline(always)]
fn horner_packed_k<const F: usize, const K: usize>(t: &Packed<F>, u: f64) -> [f64; F] {
    let mut acc = t.rows[K - 1];
    let mut m = K - 1;
    while m > 0 {
        m -= 1;
        let row = &t.rows[m];
        for j in 0..F {
            acc[j] = acc[j] * u + row[j];
        }
    }
    acc
}

/// Number of series terms that reach 1e-17 relative on every family for
/// `u = ψ²` (measured with 40-digit arithmetic over each band: 7 terms up
/// to ψ = 0.25, 8 to 0.5, 10 to 1, 11 to 1.5, 12 to 2; the full
/// [`SERIES_TERMS`] = 14 keep a margin over the 13 needed at ψ* = 2.5).
/// Short pieces of gently curved rods — the common case — thus cost half
/// the multiplications.
#[inline(always)]
fn terms(u: f64) -> usize {
    if u < 0.0625 {
        7
    } else if u < 0.25 {
        8
    } else if u < 1.0 {
        10
    } else if u < 2.25 {
        11
    } else if u < 4.0 {
        12
    } else {
        N
    }
}

/// Taylor coefficients of `sin r = r + r·u·Σ_{m≥1} (−1)^m u^{m−1}/(2m+1)!` and
/// `cos r = 1 − u/2 + u²·Σ_{m≥2} (−1)^m u^{m−2}/(2m)!`, `u = r²`, side by side
/// (`[sin, cos]` per term) for one packed Horner. Eight terms each: on
/// `|r| ≤ π/4` the first neglected terms are below 1e-19 relative.
#[repr(C, align(16))]
struct SinCosTable([[f64; 2]; 8]);

const fn sin_cos_table() -> SinCosTable {
    let mut rows = [[0.0; 2]; 8];
    let mut j = 0;
    while j < 8 {
        let sign = if j % 2 == 0 { -1.0 } else { 1.0 };
        rows[j] = [sign * INV_FACT[2 * j + 3], -sign * INV_FACT[2 * j + 4]];
        j += 1;
    }
    SinCosTable(rows)
}

static SIN_COS: SinCosTable = sin_cos_table();

/// Above this `|ψ|` the reduction below is not exact enough; `f64::sin_cos`.
const SIN_COS_FAST_MAX: f64 = 1_048_576.0; // 2^20

/// `(sin ψ, cos ψ)` in one go for the closed forms.
///
/// `f64::sin_cos` is two libm calls (`sin` and `cos`, each reducing the
/// argument again): 210 of the 373 instructions of `exp_twist` on the closed
/// branch. Here the argument is reduced once, `ψ = k·π/2 + r`, `|r| ≤ π/4`,
/// with π/2 split in three parts (33 + 33 + 53 bits: `k·P₁`, `k·P₂` are exact
/// for `|k| < 2^20`, `ψ − k·P₁` is exact by Sterbenz) and the reduced
/// argument kept as an unnormalized double-double `r₁ + lo` (the rounded
/// difference and its exact error); both Taylor polynomials then run on `r₁`
/// in the two lanes of one register, `lo` enters to first order, and the
/// quadrant `k mod 4` picks signs and order. Error ≤ 1 ulp against a correctly rounded sine and
/// cosine (tested against `f64::sin_cos`); beyond `|ψ| = 2^20` it defers to
/// `f64::sin_cos`.
#[inline(always)]
pub(crate) fn sin_cos(psi: f64) -> (f64, f64) {
    // π/2 = P1 + P2 + P3 + O(1e-37).
    const P1: f64 = f64::from_bits(0x3ff9_21fb_5440_0000);
    const P2: f64 = f64::from_bits(0x3dd0_b461_1a60_0000);
    const P3: f64 = f64::from_bits(0x3ba3_198a_2e03_7073);
    // Adding and subtracting 1.5·2^52 rounds to the nearest integer (ties to
    // even) for |x| < 2^51 without a libm call (`round` is one on x86_64
    // without SSE4.1).
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    // NaN takes the fast path and comes out NaN.
    if psi.abs() >= SIN_COS_FAST_MAX {
        return psi.sin_cos();
    }
    let kf = (psi * std::f64::consts::FRAC_2_PI + SHIFT) - SHIFT;
    let t = psi - kf * P1;
    let w = kf * P2;
    // Two-sum t − w: the rounding error is kept, whatever the magnitudes.
    let r1 = t - w;
    let bv = r1 - t;
    let e1 = (t - (r1 - bv)) + (-w - bv);
    let lo = e1 - kf * P3;
    // The polynomials run on the rounded head `r1` alone and the tail `lo`
    // (|lo| ≲ ulp(r1)) enters only through the first-order terms below:
    // sin(r1 + lo) = sin r1 + lo·cos r1 + O(lo²), and likewise for cos.
    // Renormalizing `r1 + lo` first would put three more dependent
    // additions in front of the polynomial for no digit.
    let (r, r_lo) = (r1, lo);
    let u = r * r;
    // Estrin, not Horner: the whole function is one dependency chain
    // (reduction, polynomial, reconstruction), and pairing the terms halves
    // the polynomial's depth (4 instead of 8 multiply-add steps) for two
    // extra multiplications. The terms fall off by ≥ 1/30 each, so the
    // evaluation order changes nothing at the ulp level (tested below).
    let t = &SIN_COS.0;
    let u2 = u * u;
    let u4 = u2 * u2;
    let pair = |i: usize| [t[i][0] + t[i + 1][0] * u, t[i][1] + t[i + 1][1] * u];
    let (p01, p23, p45, p67) = (pair(0), pair(2), pair(4), pair(6));
    let q0 = [p01[0] + p23[0] * u2, p01[1] + p23[1] * u2];
    let q1 = [p45[0] + p67[0] * u2, p45[1] + p67[1] * u2];
    let acc = [q0[0] + q1[0] * u4, q0[1] + q1[1] * u4];
    let h = 0.5 * u;
    // sin(r + r_lo) ≈ sin r + r_lo·cos r, cos(r + r_lo) ≈ cos r − r_lo·r;
    // 1 − h is split into its rounded value and its exact error.
    let s = r + (r_lo * (1.0 - h) + r * u * acc[0]);
    let hw = 1.0 - h;
    let c = hw + (((1.0 - hw) - h) + (u2 * acc[1] - r * r_lo));
    match (kf as i64) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// The coefficients `(a, b, c)` of the group exponential (D4):
/// `a = sinψ/ψ`, `b = (1 − cosψ)/ψ²`, `c = (ψ − sinψ)/ψ³`.
#[inline(always)]
pub fn abc(psi: f64) -> [f64; 3] {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        abc_below_switch(psi)
    } else {
        let (s, c) = sin_cos(psi);
        abc_closed(psi, s, c)
    }
}

/// The series branch of [`abc`] (`|ψ| <` [`PSI_SWITCH`]).
#[inline(always)]
pub(crate) fn abc_below_switch(psi: f64) -> [f64; 3] {
    let u = psi * psi;
    let [a, b, c, _] = horner_packed(&ABC_P, u, terms(u));
    [a, b, c]
}

#[inline(always)]
fn abc_closed(psi: f64, s: f64, c: f64) -> [f64; 3] {
    let p2 = psi * psi;
    [s / psi, (1.0 - c) / p2, (psi - s) / (p2 * psi)]
}

/// The coefficients `[τ₁, τ₂, τ₃, τ₄]` of the tangent operator (D3)
/// (`τ₀ = 1`): `τ_i = N_i(ψ)/(2ψ^{i+1})` with
/// `N₁ = 4 − 4cosψ − ψ sinψ`, `N₂ = 4ψ − 5 sinψ + ψ cosψ`,
/// `N₃ = 2 − 2cosψ − ψ sinψ`, `N₄ = 2ψ − 3 sinψ + ψ cosψ` (D3).
#[inline]
pub fn tau(psi: f64) -> [f64; 4] {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        let u = psi * psi;
        horner_packed(&TAU_P, u, terms(u))
    } else {
        let (s, c) = sin_cos(psi);
        tau_closed(psi, s, c)
    }
}

#[inline(always)]
fn numerators(psi: f64, s: f64, c: f64) -> [f64; 4] {
    [
        4.0 - 4.0 * c - psi * s,
        4.0 * psi - 5.0 * s + psi * c,
        2.0 - 2.0 * c - psi * s,
        2.0 * psi - 3.0 * s + psi * c,
    ]
}

#[inline(always)]
fn tau_closed(psi: f64, s: f64, c: f64) -> [f64; 4] {
    let n = numerators(psi, s, c);
    let p2 = psi * psi;
    let p3 = p2 * psi;
    let p4 = p2 * p2;
    let p5 = p4 * psi;
    [
        n[0] / (2.0 * p2),
        n[1] / (2.0 * p3),
        n[2] / (2.0 * p4),
        n[3] / (2.0 * p5),
    ]
}

/// The coefficients `[ρ₁, …, ρ₄]`, `ρ_i = τ_i′(ψ)/ψ`, used by the strain
/// derivative (D6): `ρ_i = [ψ N_i′ − (i+1) N_i]/(2ψ^{i+3})` with
/// `N₁′ = 3 sinψ − ψ cosψ`, `N₂′ = N₁`, `N₃′ = sinψ − ψ cosψ`, `N₄′ = N₃`.
#[inline]
pub fn rho(psi: f64) -> [f64; 4] {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        let u = psi * psi;
        horner_packed(&RHO_P, u, terms(u))
    } else {
        let (s, c) = sin_cos(psi);
        rho_closed(psi, s, c)
    }
}

#[inline(always)]
fn rho_closed(psi: f64, s: f64, c: f64) -> [f64; 4] {
    let n = numerators(psi, s, c);
    let dn = [3.0 * s - psi * c, n[0], s - psi * c, n[2]];
    let p2 = psi * psi;
    let p4 = p2 * p2;
    let p5 = p4 * psi;
    let p6 = p4 * p2;
    let p7 = p6 * psi;
    [
        (psi * dn[0] - 2.0 * n[0]) / (2.0 * p4),
        (psi * dn[1] - 3.0 * n[1]) / (2.0 * p5),
        (psi * dn[2] - 4.0 * n[2]) / (2.0 * p6),
        (psi * dn[3] - 5.0 * n[3]) / (2.0 * p7),
    ]
}

/// `abc(ψ)` and `tau(ψ)` together, sharing one `sin_cos` above the switch.
#[inline]
pub fn abc_tau(psi: f64) -> ([f64; 3], [f64; 4]) {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        (abc(psi), tau(psi))
    } else {
        let (s, c) = sin_cos(psi);
        (abc_closed(psi, s, c), tau_closed(psi, s, c))
    }
}

/// `abc(ψ)` and `[τ₃, τ₄]` together: all that `T(x)`, `T₋(x)` and the group
/// exponential need once `τ₁, τ₂` are folded into `b, c`
/// (`τ₁ − ψ²τ₃ = b`, `τ₂ − ψ²τ₄ = c`).
#[inline(always)]
pub fn abc_tau34(psi: f64) -> ([f64; 3], [f64; 2]) {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        let u = psi * psi;
        let [a, b, c, t3, t4, _] = horner_packed(&ABC_T34_P, u, terms(u));
        ([a, b, c], [t3, t4])
    } else {
        let (s, c) = sin_cos(psi);
        let t = tau_closed(psi, s, c);
        (abc_closed(psi, s, c), [t[2], t[3]])
    }
}

/// `abc(ψ)`, `tau(ψ)` and `rho(ψ)` together: the eleven coefficients of the
/// pose, `T₋` and its strain derivative at one abscissa.
#[inline(always)]
pub fn abc_tau_rho(psi: f64) -> ([f64; 3], [f64; 4], [f64; 4]) {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        (abc(psi), tau(psi), rho(psi))
    } else {
        let (s, c) = sin_cos(psi);
        (
            abc_closed(psi, s, c),
            tau_closed(psi, s, c),
            rho_closed(psi, s, c),
        )
    }
}

/// [`abc_tau_rho`] without `τ₁` (which `T₋` and its strain derivative
/// fold into `b`): `([a, b, c], [τ₂, τ₃, τ₄], [ρ₁, …, ρ₄])`, the same bits,
/// one packed Horner below the switch.
#[inline(always)]
pub fn abc_tau234_rho(psi: f64) -> ([f64; 3], [f64; 3], [f64; 4]) {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        let u = psi * psi;
        let [a, b, c, t2, t3, t4, r1, r2, r3, r4] = horner_packed(&ABC_T234_RHO_P, u, terms(u));
        ([a, b, c], [t2, t3, t4], [r1, r2, r3, r4])
    } else {
        let (s, c) = sin_cos(psi);
        let t = tau_closed(psi, s, c);
        (
            abc_closed(psi, s, c),
            [t[1], t[2], t[3]],
            rho_closed(psi, s, c),
        )
    }
}

/// `tau(ψ)` and `rho(ψ)` together, sharing one `sin_cos` above the switch.
#[inline]
pub fn tau_rho(psi: f64) -> ([f64; 4], [f64; 4]) {
    let psi = psi.abs();
    if psi < PSI_SWITCH {
        (tau(psi), rho(psi))
    } else {
        let (s, c) = sin_cos(psi);
        (tau_closed(psi, s, c), rho_closed(psi, s, c))
    }
}

/// Closed forms evaluated at any `ψ ≠ 0`, whatever the switch says: for
/// tests that measure the series against them, and for users who want to
/// see why the series exist. Returns `(abc, tau, rho)`.
pub fn closed_forms(psi: f64) -> ([f64; 3], [f64; 4], [f64; 4]) {
    let (s, c) = sin_cos(psi);
    (
        abc_closed(psi, s, c),
        tau_closed(psi, s, c),
        rho_closed(psi, s, c),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One family, the first `n` terms: the reference for the packed tables.
    fn horner(c: &[f64; N], u: f64, n: usize) -> f64 {
        let mut acc = c[n - 1];
        for m in (0..n - 1).rev() {
            acc = acc * u + c[m];
        }
        acc
    }

    #[test]
    fn packed_tables_give_the_one_family_bits() {
        for psi in [0.0, 1e-9, 0.1, 0.2499, 0.3, 0.7, 1.2, 1.7, 2.2, 2.4999] {
            let u: f64 = psi * psi;
            let n = terms(u);
            let one = |f: &[f64; N]| horner(f, u, n);
            let [a, b, c] = abc(psi);
            assert_eq!([a, b, c], [0, 1, 2].map(|j| one(&ABC_SERIES[j])));
            let (abc3, t234, r4) = abc_tau234_rho(psi);
            let (abc4, t4, r5) = abc_tau_rho(psi);
            assert_eq!((abc3, r4), (abc4, r5));
            assert_eq!(t234, [t4[1], t4[2], t4[3]]);
            let (abc2, t34) = abc_tau34(psi);
            assert_eq!(abc2, [a, b, c]);
            assert_eq!(t34, [one(&TAU_SERIES[2]), one(&TAU_SERIES[3])]);
            assert_eq!(tau(psi), [0, 1, 2, 3].map(|i| one(&TAU_SERIES[i])));
            assert_eq!(rho(psi), [0, 1, 2, 3].map(|i| one(&RHO_SERIES[i])));
        }
    }

    #[test]
    fn truncated_series_match_full_series() {
        // The band rule of `terms` against all 14 terms, at each band's upper
        // edge (the worst point of the band).
        for psi in [0.2499, 0.4999, 0.9999, 1.4999, 1.9999, 2.4999] {
            let u: f64 = psi * psi;
            let n = terms(u);
            let fams = TAU_SERIES
                .iter()
                .chain(RHO_SERIES.iter())
                .chain(ABC_SERIES.iter());
            for c in fams {
                let full = horner(c, u, N);
                let cut = horner(c, u, n);
                assert!(
                    (full - cut).abs() <= 4e-16 * full.abs(),
                    "psi {psi}: {cut} vs {full}"
                );
            }
        }
    }

    #[test]
    fn sin_cos_within_an_ulp_of_libm() {
        // Dense sweeps over the closed-form range and beyond, plus points
        // next to multiples of π/2 (where the reduction must be exact).
        let ulp = |v: f64| f64::from_bits(v.abs().to_bits() + 1) - v.abs();
        let mut psis: Vec<f64> = (0..200_000).map(|i| 2.5 + i as f64 * 1.3e-3).collect();
        psis.extend((0..20_000).map(|i| 0.1 + i as f64 * 52.4287));
        for k in 1..2000 {
            let m = k as f64 * std::f64::consts::FRAC_PI_2;
            psis.extend([
                m,
                f64::from_bits(m.to_bits() + 1),
                f64::from_bits(m.to_bits() - 1),
            ]);
        }
        psis.extend([-3.0, -1e3, 1e-300, 0.0, 1048575.9, 1048576.0, 3e7]);
        let (s, c) = sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
        for psi in psis {
            let (s, c) = sin_cos(psi);
            let (s0, c0) = psi.sin_cos();
            assert!((s - s0).abs() <= ulp(s0), "sin({psi:e}): {s:e} vs {s0:e}");
            assert!((c - c0).abs() <= ulp(c0), "cos({psi:e}): {c:e} vs {c0:e}");
        }
    }

    #[test]
    fn limits_at_zero() {
        // τ_i(0) = c_{i,0}/(i+1) = 1/((i+1)·i!); ρ_i(0) = 2c_{i,1}/(i+3).
        let t = tau(0.0);
        assert_eq!(t, [0.5, 1.0 / 6.0, 1.0 / 24.0, 1.0 / 120.0]);
        let r = rho(0.0);
        assert_eq!(r[0], 0.0); // c_{1,1} = 0
        assert_eq!(r[1], 0.0); // c_{2,1} = 0
        assert!((r[2] - 2.0 * (-2.0 / 120.0) / 6.0).abs() < 1e-18);
        assert_eq!(abc(0.0), [1.0, 0.5, 1.0 / 6.0]);
    }

    #[test]
    fn series_and_closed_agree_at_switch() {
        for psi in [PSI_SWITCH * (1.0 - 1e-9), PSI_SWITCH, 2.0, 3.0] {
            let (a1, t1, r1) = closed_forms(psi);
            let u = psi * psi;
            // ψ = 3 lies beyond the switch, where the series is never used:
            // there a = sin3/3 ≈ 0.047 is what is left of O(1) alternating
            // terms (Σ|terms| = sinh3/3 ≈ 3.3), so the series itself is only
            // good to ~ε·3.3/0.047 ≈ 8e-15 (measured 3.3e-15 vs 60 digits).
            let tol_abc = if psi > PSI_SWITCH { 1e-14 } else { 2e-15 };
            for j in 0..3 {
                let s = horner(&ABC_SERIES[j], u, N);
                assert!(
                    (s - a1[j]).abs() <= tol_abc * a1[j].abs(),
                    "abc[{j}] at {psi}"
                );
            }
            for i in 0..4 {
                let s = horner(&TAU_SERIES[i], u, N);
                assert!(
                    (s - t1[i]).abs() <= 2e-15 * t1[i].abs(),
                    "tau[{i}] at {psi}"
                );
                let s = horner(&RHO_SERIES[i], u, N);
                assert!(
                    (s - r1[i]).abs() <= 1e-14 * r1[i].abs(),
                    "rho[{i}] at {psi}"
                );
            }
        }
    }
}
