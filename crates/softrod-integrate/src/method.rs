//! The integration method.

/// The integration method.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Method {
    /// Classical 4th-order Runge–Kutta with a fixed step
    /// ([`StepControl::Fixed`](crate::StepControl::Fixed); the last step is shortened to land on `t1`).
    /// Dense output: cubic Hermite (order 3 interpolant, uses the step's end
    /// derivative which the next step reuses as its first stage).
    Rk4,
    /// Dormand–Prince 5(4) (Dormand & Prince 1980; Hairer, Nørsett & Wanner,
    /// *Solving ODEs I*, §II.5, Table 5.2), FSAL, local extrapolation, the PI
    /// step-size controller of Hairer's DOPRI5 (β = 0.04) and its 4th-order
    /// continuous extension (dense output, *ODEs I* §II.6).
    Dopri5,
    /// ROS34PW2 (Rang & Angermann, BIT 45 (2005) 761–787): a 4-stage
    /// Rosenbrock–W method of order 3 with an embedded order-2 solution,
    /// L-stable and stiffly accurate. Linearly implicit: no Newton iteration;
    /// 4 solves with one LU of `I/(hγ) − J` per step.
    ///
    /// Why it is kept beside the Newton methods: (1) as a *W*-method it
    /// keeps order 3 with any approximation of the Jacobian, so the Jacobian
    /// is reused across many steps and the LU across steps of equal size —
    /// with [`RodJacobian::ElasticOnly`](crate::RodJacobian::ElasticOnly) it
    /// is a linearly implicit IMEX scheme; (2) no Newton iteration, hence no
    /// convergence failure mode and bit-reproducible cost; (3) L-stability
    /// and stiff accuracy. A cheap Jacobian is kept only while it works: when
    /// rejections cluster, the step collapses or drifts down, or it is about
    /// to underflow, ROS34PW2 switches to the exact Jacobian
    /// ([`SecondOrderSystem::jacobians`](crate::SecondOrderSystem::jacobians))
    /// for a window of steps, kept while it takes clearly larger steps.
    /// Its embedded estimate is first-order-norm (positions and
    /// velocities), so on undamped rods it resolves the high modes the
    /// release excites: 10–100× slower than [`Method::Esdirk46`] at equal
    /// tip error (docs/performance.md).
    Rosw34,
    /// Generalized-α for second-order systems (Chung & Hulbert, J. Appl.
    /// Mech. 60 (1993) 371–375) in the form of Arnold & Brüls (Multibody Syst.
    /// Dyn. 18 (2007) 185–202): second-order accurate, unconditionally stable
    /// for linear problems, with high-frequency spectral radius `rho_inf ∈
    /// [0, 1]` (1: no dissipation, trapezoidal-like; 0: asymptotic
    /// annihilation). With [`StepControl::Fixed`](crate::StepControl::Fixed) the step is `dt` (halved
    /// and regrown when Newton fails); simplified Newton with Jacobian and LU
    /// reuse, or one iteration per step ([`Iteration::LinearlyImplicit`](crate::Iteration::LinearlyImplicit)).
    /// Only for [`SecondOrderSystem`](crate::SecondOrderSystem).
    ///
    /// With [`StepControl::Adaptive`](crate::StepControl::Adaptive) the step adapts to `rtol`, `atol`
    /// (error per step, weights `atol + rtol·max(|yₙ|, |yₙ₊₁|)`, RMS norm,
    /// accepted if ≤ 1). The estimate is free — no extra evaluation or
    /// solve — and built from the two auxiliary accelerations of the step,
    /// `Δa = aₙ₊₁ − aₙ`, with `aₙ = q̈(tₙ + δh) + O(h²)`, `δ = α_m − α_f`
    /// (Arnold & Brüls 2007):
    /// * positions: `e_q = (β + δ/2 − 1/6) h² Δa`, the leading local error
    ///   `(β + δ/2 − 1/6) h³ q⃛` of the position update (Taylor expansion;
    ///   for `δ = 0` Zienkiewicz & Xie's Newmark estimator, Earthquake Eng.
    ///   Struct. Dyn. 20 (1991) 871–887);
    /// * velocities: `e_v = ½ h Δa ≈ ½ h² q⃛`, the local error of a first-order
    ///   velocity (`vₙ + h·aₙ` against the trapezoidal `vₙ + ½h(aₙ + aₙ₊₁)`):
    ///   an embedded lower-order estimate, as ROS34PW2's, since the method's
    ///   own velocity has no `h²` term to estimate (`γ = ½ − δ`).
    ///
    /// Why both: measured on the linear oscillators of the tests (t = 4,
    /// ρ∞ 0…1, rtol = atol = 1e-3…1e-7), positions alone give global errors
    /// of 15–600× the tolerance, growing like `tol^(−1/3)` (local error
    /// `O(h³)` per step, global `O(h²)`); with the velocity term the global
    /// error is tolerance-proportional: 0.4–2.2× tol in `q` and 1.6–6.3× in
    /// `(q, q̇)` for ρ∞ ≥ 0.5 (up to 8× and 23× for ρ∞ = 0), like ROS34PW2
    /// (3–9×) and DOPRI5 (0.4–4.5×) there. Step doubling would cost 50 %
    /// more work per step; filtering `Δa` by the iteration matrix
    /// (Hairer–Wanner's `(I − hγJ)⁻¹` for RADAU5) saved 2–10 % of the steps
    /// on the rod for one more solve per step, and moving `aₙ` to the new
    /// offset `δh` when `h` changes made no measurable difference on the
    /// oscillators — neither is kept.
    /// Step: the PI controller of DOPRI5 (Gustafsson; Hairer's form) for an
    /// `O(h²)` estimate, `h·0.9·err^(−0.35)·err_prev^(0.2)` within
    /// `[0.2, 5]·h`; after a rejection `h·max(0.2, 0.9·err^(−1/2))`, after a
    /// Newton failure or a non-finite trial a fresh Jacobian if it was old,
    /// else `h/2`; `h` is kept for factors in `[0.9, 1.2]` so the
    /// factorization is reused.
    ///
    /// On the undamped soft rod it resolves the physical high-frequency
    /// ringing (as the other error-controlled methods do; see the crate
    /// documentation): there the fixed-step linearly implicit scheme is the
    /// fast one, and error control is for runs whose accuracy must be
    /// guaranteed rather than checked.
    GeneralizedAlpha {
        /// Spectral radius at infinite frequency, in `[0, 1]`.
        rho_inf: f64,
    },
    /// ESDIRK4(3)6L\[2\]SA (Kennedy & Carpenter, Appl. Numer. Math. 44 (2003)
    /// 139–181): an adaptive implicit Runge–Kutta method of order 4 with an
    /// embedded order 3, L-stable and stiffly accurate, six stages of which
    /// five implicit with one diagonal `γ = 1/4`. Each implicit stage is one
    /// equation in its acceleration, solved by simplified Newton on the
    /// force residual with the iteration matrix `M(q) + h²γ²K + hγD` — the
    /// structured O(N) solve of
    /// [`SecondOrderSystem::factor_shifted_mass`](crate::SecondOrderSystem::factor_shifted_mass)
    /// when the system has it — and on the exact dense Jacobian when that
    /// converges badly. Jacobian and factorization are kept while the
    /// iteration contracts fast and `h` changes by less than 20 %. Dense
    /// output: quintic Hermite in `(q, q̇, q̈)`. Only for
    /// [`SecondOrderSystem`](crate::SecondOrderSystem). With
    /// [`StepControl::Fixed`](crate::StepControl::Fixed) every step is
    /// accepted (for convergence studies).
    Esdirk46,
    /// Radau IIA of order 5 (Ehle; three-stage collocation, L-stable,
    /// stiffly accurate), in the design of Hairer & Wanner's RADAU5
    /// (*Solving ODEs II*, §IV.8): simplified Newton on the exact dense
    /// Jacobian in the variables that split the stage system into one real
    /// and one complex `n×n` system, Jacobian and factorization reuse,
    /// filtered error estimate, predictive step control, collocation dense
    /// output. For first- and second-order systems (the latter through `n×n`
    /// Schur complements, the error measured in positions as for
    /// [`Method::Esdirk46`]). Its complex shift has no real-shifted
    /// structured counterpart, so it always works on dense `n×n` matrices:
    /// for small stiff systems and tight tolerances.
    Radau5,
}
