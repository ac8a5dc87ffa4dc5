//! Statics and modes: the static equilibrium and the undamped natural
//! modes about it.

use nalgebra::DVector;
use softrod_dynamics::{Data, Modes, StaticsOptions, StaticsResult, modes, statics};

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
    /// Frequencies and shapes (see [`Modes`]).
    pub modes: Modes,
    /// The equilibrium.
    pub equilibrium: Equilibrium,
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
    /// initial `q` (Newton with line search and load continuation).
    pub fn statics(&mut self) -> Result<StaticsResult> {
        self.check_statics()?;
        let s = &mut self.system;
        Ok(statics(
            &s.model,
            &mut s.data,
            self.q0.as_slice(),
            &StaticsOptions::default(),
        )?)
    }

    /// Undamped natural modes about the static equilibrium (the rest shape
    /// when the model has no static loads).
    pub fn modes(&mut self) -> Result<ModalAnalysis> {
        self.check_dense("modes", STATICS_DENSE_MATRICES + MODES_DENSE_MATRICES)?;
        let equilibrium = if self.has_static_loads() {
            Equilibrium::Statics(self.statics()?.q)
        } else {
            Equilibrium::Rest
        };
        let q = match &equilibrium {
            Equilibrium::Rest => DVector::zeros(self.n_dof()),
            Equilibrium::Statics(q) => q.clone(),
        };
        let modes = self.modes_about(q.as_slice())?;
        Ok(ModalAnalysis { modes, equilibrium })
    }

    /// Undamped natural modes of the model linearized about `q` (which
    /// should be an equilibrium; an unstable one shows negative `ω`).
    pub fn modes_about(&mut self, q: &[f64]) -> Result<Modes> {
        self.check("q", q)?;
        self.check_dense("modes", MODES_DENSE_MATRICES)?;
        let s = &mut self.system;
        Ok(modes(&s.model, &mut s.data, q, 0.0)?)
    }
}
