//! Statics and modes: the static equilibrium and the undamped natural
//! modes about it.

use nalgebra::DVector;
use softrod_dynamics::{Data, Modes, StaticsOptions, modes, statics};
use softrod_mechanics::validity::strain_validity;

use super::Simulation;
use crate::error::Result;
use crate::limits::{MODES_DENSE_MATRICES, STATICS_DENSE_MATRICES};

/// Which equilibrium [`Simulation::modes`] linearized about.
#[derive(Clone, Debug, PartialEq)]
pub enum Equilibrium {
    /// The rest shape `q = 0` (the model has no static loads).
    Rest,
    /// The static equilibrium under the model's static loads.
    Statics(DVector<f64>),
}

/// Natural modes and the equilibrium they are about.
#[derive(Clone, Debug)]
pub struct ModalAnalysis {
    /// Frequencies and shapes (see [`Modes`]; rigid and unstable modes by
    /// [`Modes::kind`]).
    pub modes: Modes,
    /// The equilibrium.
    pub equilibrium: Equilibrium,
    /// What the validity rules (`softrod_mechanics::validity`) say of the
    /// equilibrium, as [`Statics::warnings`]; empty when it is valid.
    pub warnings: Vec<String>,
}

/// A converged static equilibrium ([`Simulation::statics`]) and what the
/// validity rules say of it: Newton converges to equilibria of the model's
/// equations that no rod described by it reaches (a shear of thousands
/// under an absurd load), which are reported, not hidden.
#[derive(Clone, Debug)]
pub struct Statics {
    /// Equilibrium coordinates (n_dof).
    pub q: DVector<f64>,
    /// Newton iterations over all continuation steps.
    pub iterations: usize,
    /// Final residual `‖r‖∞` [N or N·m per coordinate].
    pub residual: f64,
    /// Load increments used (1 when the full load converged directly).
    pub load_steps: usize,
    /// The rules of `softrod_mechanics::validity` the equilibrium breaks,
    /// in the words of a run's watch and of `check` (`"strain beyond the
    /// model's validity at the equilibrium: rod \"arm\" piece 3 has …"`),
    /// at most one per rule and rod; empty when it is valid.
    pub warnings: Vec<String>,
}

impl Simulation {
    /// Whether the rest shape `q = 0` is not an equilibrium at `t = 0`: the
    /// static force there ([`softrod_dynamics::static_force`]: gravity,
    /// loads on rods and bodies, cables, stress-free strains other than the
    /// rest strain, joint springs off their rest) is not zero.
    pub fn has_static_loads(&self) -> bool {
        let m = self.model();
        let mut data = Data::new(m);
        let z = vec![0.0; m.n_dof()];
        softrod_dynamics::static_force(m, &mut data, 0.0, &z)
            .map_or(true, |f| f.iter().any(|v| *v != 0.0))
    }

    /// Static equilibrium under every static term at `t = 0`, from the
    /// initial `q` (Newton with line search and load continuation), with
    /// the validity warnings of the equilibrium ([`Statics::warnings`]).
    pub fn statics(&mut self) -> Result<Statics> {
        self.check_statics()?;
        let s = &mut self.system;
        let r = statics(
            &s.model,
            &mut s.data,
            self.q0.as_slice(),
            &StaticsOptions::default(),
        )?;
        let warnings = self.validity_warnings(r.q.as_slice(), "at the equilibrium");
        Ok(Statics {
            q: r.q,
            iterations: r.iterations,
            residual: r.residual,
            load_steps: r.load_steps,
            warnings,
        })
    }

    /// The rules of `softrod_mechanics::validity` that the rods' strains
    /// at `q` (n_dof) break, one message per rule and rod (the first piece
    /// that breaks it): `"{headline} {when}: rod {name:?} {details}"`, the
    /// words of a run's watch (`when` = `"at t = 1e-2 s"`) and of `check`
    /// (`"at rest"`). A folded piece (stretch not positive) is listed
    /// first: no rod reaches that state.
    ///
    /// # Panics
    /// If `q` is shorter than `n_dof`.
    pub fn validity_warnings(&self, q: &[f64], when: &str) -> Vec<String> {
        let mut out = Vec::new();
        for r in self.model().rods() {
            let v = strain_validity(&r.spec.geometry, r.spec.properties.section(), &q[r.dofs()]);
            for f in v.findings() {
                out.push(format!(
                    "{} {when}: rod {:?} {f}",
                    f.headline(),
                    r.spec.name
                ));
            }
        }
        out
    }

    /// Undamped natural modes about the static equilibrium (the rest shape
    /// when the model has no static loads).
    pub fn modes(&mut self) -> Result<ModalAnalysis> {
        self.check_dense("modes", STATICS_DENSE_MATRICES + MODES_DENSE_MATRICES)?;
        let (equilibrium, warnings) = if self.has_static_loads() {
            let s = self.statics()?;
            (Equilibrium::Statics(s.q), s.warnings)
        } else {
            let z = vec![0.0; self.n_dof()];
            (Equilibrium::Rest, self.validity_warnings(&z, "at rest"))
        };
        let q = match &equilibrium {
            Equilibrium::Rest => DVector::zeros(self.n_dof()),
            Equilibrium::Statics(q) => q.clone(),
        };
        let modes = self.modes_about(q.as_slice())?;
        Ok(ModalAnalysis {
            modes,
            equilibrium,
            warnings,
        })
    }

    /// Undamped natural modes of the model linearized about `q` (which
    /// should be an equilibrium; an unstable one shows negative `ω`, a
    /// rigid mode `ω = 0`, by the tolerance [`Modes::rigid_tolerance`]).
    pub fn modes_about(&mut self, q: &[f64]) -> Result<Modes> {
        self.check("q", q)?;
        self.check_dense("modes", MODES_DENSE_MATRICES)?;
        let s = &mut self.system;
        Ok(modes(&s.model, &mut s.data, q, 0.0)?)
    }
}
