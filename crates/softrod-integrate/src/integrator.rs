//! The one list of integrators: the methods of this crate, under the names
//! the scene format (`run.integrator`), the facade, Python and its stubs use.

use std::fmt;
use std::str::FromStr;

/// A time integrator. Its [`name`](Self::name) is the scene format's
/// `run.integrator` and Python's `integrator=`; the scene, the facade's
/// settings and Python (`softrod.INTEGRATORS`) take their lists from
/// [`Integrator::ALL`].
///
/// Method parameters are [`Options`](crate::Options): tolerances or the
/// fixed step, the implicit iteration, and generalized-α's
/// [`rho_inf`](crate::Options::rho_inf).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Integrator {
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
    /// release excites, which makes it much slower than
    /// [`Integrator::Esdirk`] at equal tip error (docs/performance.md).
    Rosenbrock,
    /// Generalized-α for second-order systems (Chung & Hulbert, J. Appl.
    /// Mech. 60 (1993) 371–375) in the form of Arnold & Brüls (Multibody Syst.
    /// Dyn. 18 (2007) 185–202): second-order accurate, unconditionally stable
    /// for linear problems, with high-frequency spectral radius
    /// [`Options::rho_inf`](crate::Options::rho_inf) `∈ [0, 1]` (1: no
    /// dissipation, trapezoidal-like; 0: asymptotic annihilation). With
    /// [`StepControl::Fixed`](crate::StepControl::Fixed) the step is `dt` (halved
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
    /// Both terms are needed: positions alone leave a global error that
    /// grows like `tol^(−1/3)` relative to the tolerance (local error `O(h³)`
    /// per step, global `O(h²)`); with the velocity term it is
    /// tolerance-proportional (measurements in docs/performance.md).
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
    GeneralizedAlpha,
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
    Esdirk,
    /// ESDIRK5(4)7L\[2\]SA (Kennedy & Carpenter, NASA/TM-2016-219173,
    /// Table 25): [`Integrator::Esdirk`]'s machinery — the structured O(N)
    /// Newton matrix `M(q) + h²γ²K + hγD`, the exact-Jacobian fallback, the
    /// filtered error estimate measured as positions, quintic Hermite dense
    /// output — on a tableau of order 5 with an embedded order 4, L-stable,
    /// stiffly accurate, seven stages of which six implicit with `γ = 0.184`.
    /// One more implicit stage per step than ESDIRK4(3)6L\[2\]SA, for fewer
    /// steps at tight tolerances. It has no discrete adjoint (gradients
    /// refuse it). Only for [`SecondOrderSystem`](crate::SecondOrderSystem).
    Esdirk5,
    /// Radau IIA of order 5 (Ehle; three-stage collocation, L-stable,
    /// stiffly accurate), in the design of Hairer & Wanner's RADAU5
    /// (*Solving ODEs II*, §IV.8): simplified Newton on the exact dense
    /// Jacobian in the variables that split the stage system into one real
    /// and one complex `n×n` system, Jacobian and factorization reuse,
    /// filtered error estimate, predictive step control, collocation dense
    /// output. For first- and second-order systems (the latter through `n×n`
    /// Schur complements, the error measured in positions as for
    /// [`Integrator::Esdirk`]). Its complex shift has no real-shifted
    /// structured counterpart, so it always works on dense `n×n` matrices:
    /// for small stiff systems and tight tolerances.
    Radau5,
}

impl Integrator {
    /// Every integrator, in the order lists and error messages show them.
    pub const ALL: [Integrator; 7] = [
        Integrator::Rk4,
        Integrator::Dopri5,
        Integrator::Rosenbrock,
        Integrator::GeneralizedAlpha,
        Integrator::Esdirk,
        Integrator::Esdirk5,
        Integrator::Radau5,
    ];

    /// The recommended integrator, the default of a scene that names none:
    /// the stiff, error-controlled ESDIRK with Newton on the exact Jacobian
    /// (see [`Recommended::tolerance`](crate::Recommended::tolerance) for
    /// why).
    pub const DEFAULT: Integrator = Integrator::Esdirk;

    /// Its name: the scene format's `run.integrator` and Python's
    /// `integrator=`.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Rk4 => "rk4",
            Integrator::Dopri5 => "dopri5",
            Integrator::Rosenbrock => "rosenbrock",
            Integrator::GeneralizedAlpha => "generalized-alpha",
            Integrator::Esdirk => "esdirk",
            Integrator::Esdirk5 => "esdirk5",
            Integrator::Radau5 => "radau5",
        }
    }

    /// One line on what it is and what it is for (help texts, docs).
    pub fn description(self) -> &'static str {
        match self {
            Integrator::Rk4 => {
                "classical Runge-Kutta of order 4, fixed step dt: non-stiff reference runs"
            }
            Integrator::Dopri5 => {
                "Dormand-Prince 5(4), adaptive explicit: non-stiff problems, references"
            }
            Integrator::Rosenbrock => {
                "Rosenbrock-W ROS34PW2, adaptive, linearly implicit (no Newton): \
                 stiff problems at loose tolerances"
            }
            Integrator::GeneralizedAlpha => {
                "generalized-alpha (Chung-Hulbert), implicit, order 2, fixed step dt \
                 (or error control): large fixed steps"
            }
            Integrator::Esdirk => {
                "ESDIRK4(3)6L[2]SA, adaptive, L-stable, Newton with the O(N) structured \
                 solve: stiff rods of any size (the default)"
            }
            Integrator::Esdirk5 => {
                "ESDIRK5(4)7L[2]SA, adaptive, L-stable, order 5, Newton with the O(N) \
                 structured solve: stiff rods at tight tolerances"
            }
            Integrator::Radau5 => {
                "Radau IIA of order 5, adaptive, Newton on the dense exact Jacobian: \
                 small stiff models at tight tolerances"
            }
        }
    }

    /// The order of the method (of its propagated solution).
    pub fn order(self) -> u32 {
        match self {
            Integrator::Rk4 | Integrator::Esdirk => 4,
            Integrator::Dopri5 | Integrator::Esdirk5 | Integrator::Radau5 => 5,
            Integrator::Rosenbrock => 3,
            Integrator::GeneralizedAlpha => 2,
        }
    }

    /// Whether it adapts its step to `rtol`/`atol` by default (otherwise it
    /// steps with a fixed `dt`; generalized-α adapts only when asked,
    /// [`StepControl::Adaptive`](crate::StepControl::Adaptive)).
    pub fn is_adaptive(self) -> bool {
        !matches!(self, Integrator::Rk4 | Integrator::GeneralizedAlpha)
    }

    /// Whether it supports [`Options::project_state`](crate::Options::project_state)
    /// (the projection of the state onto a system's constraints after each
    /// accepted step): ESDIRK and ESDIRK5.
    pub fn projects_state(self) -> bool {
        matches!(self, Integrator::Esdirk | Integrator::Esdirk5)
    }

    /// Whether it has an error estimate, so that it can run with
    /// [`StepControl::Adaptive`](crate::StepControl::Adaptive) (all but
    /// RK4).
    pub fn has_error_estimate(self) -> bool {
        self != Integrator::Rk4
    }

    /// Whether it is implicit or linearly implicit (suited to stiff
    /// problems).
    pub fn is_implicit(self) -> bool {
        !matches!(self, Integrator::Rk4 | Integrator::Dopri5)
    }

    /// Whether it needs a [`SecondOrderSystem`](crate::SecondOrderSystem)
    /// ([`integrate_second_order`](crate::integrate_second_order)); the
    /// others run on first-order systems too.
    pub fn needs_second_order(self) -> bool {
        matches!(
            self,
            Integrator::GeneralizedAlpha | Integrator::Esdirk | Integrator::Esdirk5
        )
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Error of [`Integrator::from_str`]: the name is not one of
/// [`Integrator::ALL`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown integrator {name:?} (valid: {})", valid_names())]
pub struct UnknownIntegrator {
    /// The name given.
    pub name: String,
}

/// The valid names, comma-separated.
fn valid_names() -> String {
    Integrator::ALL.map(Integrator::name).join(", ")
}

impl FromStr for Integrator {
    type Err = UnknownIntegrator;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Integrator::ALL
            .into_iter()
            .find(|i| i.name() == s)
            .ok_or_else(|| UnknownIntegrator { name: s.to_owned() })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names are distinct, parse back, and the error lists them all.
    #[test]
    fn names_round_trip() {
        for i in Integrator::ALL {
            assert_eq!(i.name().parse::<Integrator>(), Ok(i));
            assert_eq!(
                Integrator::ALL
                    .iter()
                    .filter(|j| j.name() == i.name())
                    .count(),
                1
            );
        }
        let e = "euler".parse::<Integrator>().unwrap_err().to_string();
        assert_eq!(
            e,
            "unknown integrator \"euler\" (valid: rk4, dopri5, rosenbrock, generalized-alpha, esdirk, esdirk5, radau5)"
        );
    }
}
