//! Statics and modes: the static equilibrium and the undamped natural
//! modes about it.

use nalgebra::DVector;
use softrod_dynamics::{
    Data, DynamicsError, Modes, StaticsOptions, StaticsSolver, lowest_modes, modes, statics,
};
use softrod_mechanics::validity::strain_validity;

use super::Simulation;
use crate::error::Result;
use crate::limits::{LANCZOS_MIN_DOF, MODES_DENSE_MATRICES, STATICS_DENSE_MATRICES};

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
    /// From a fresh contact state (docs/theory-contact.md CT15: the base
    /// stiffness, no friction anchors), whatever a run before it committed;
    /// the stiffness it raises stays for [`Simulation::contacts`].
    pub fn statics(&mut self) -> Result<Statics> {
        self.check_statics()?;
        let s = &mut self.system;
        s.data.reset_contact();
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
    /// when the model has no static loads): all `n_dof` of them, by the
    /// dense eigensolver. [`Simulation::lowest_modes`] gives the lowest few
    /// of a large model without `n × n` matrices.
    pub fn modes(&mut self) -> Result<ModalAnalysis> {
        self.check_dense("modes", STATICS_DENSE_MATRICES + MODES_DENSE_MATRICES)?;
        let (equilibrium, q, warnings) = self.modal_equilibrium()?;
        let modes = self.modes_about(q.as_slice())?;
        Ok(ModalAnalysis {
            modes,
            equilibrium,
            warnings,
        })
    }

    /// The `count` lowest undamped modes about the static equilibrium (the
    /// rest shape when the model has no static loads), lowest first; fewer
    /// when the model has fewer coordinates. The same modes as
    /// [`Simulation::modes`] to the eigensolvers' tolerances, by the
    /// cheaper method ([`Simulation::lowest_modes_about`]): the
    /// matrix-free statics and Lanczos (docs/theory.md E8–E11, O(N) memory
    /// and time per iteration) on large open models, the dense ones
    /// otherwise.
    pub fn lowest_modes(&mut self, count: usize) -> Result<ModalAnalysis> {
        if self.lanczos_applies() {
            self.check_statics()?;
        } else {
            self.check_dense("modes", STATICS_DENSE_MATRICES + MODES_DENSE_MATRICES)?;
        }
        let (equilibrium, q, warnings) = self.modal_equilibrium()?;
        let modes = self.lowest_modes_about(q.as_slice(), count)?;
        Ok(ModalAnalysis {
            modes,
            equilibrium,
            warnings,
        })
    }

    /// The equilibrium [`Simulation::modes`] linearizes about, its
    /// coordinates and its validity warnings.
    fn modal_equilibrium(&mut self) -> Result<(Equilibrium, DVector<f64>, Vec<String>)> {
        if self.has_static_loads() {
            let s = self.statics()?;
            Ok((Equilibrium::Statics(s.q.clone()), s.q, s.warnings))
        } else {
            let z = vec![0.0; self.n_dof()];
            let warnings = self.validity_warnings(&z, "at rest");
            Ok((Equilibrium::Rest, DVector::zeros(self.n_dof()), warnings))
        }
    }

    /// Whether [`Simulation::lowest_modes_about`] starts with Lanczos: an
    /// open model of at least [`LANCZOS_MIN_DOF`] coordinates whose
    /// generalized stiffness is positive definite (the conditions of
    /// `softrod_dynamics::lowest_modes` that are known before it runs).
    fn lanczos_applies(&self) -> bool {
        self.n_dof() >= LANCZOS_MIN_DOF && StaticsSolver::Auto.is_structured(self.model())
    }

    /// The `count` lowest undamped modes of the model linearized about `q`
    /// (an equilibrium), lowest first. From [`LANCZOS_MIN_DOF`]
    /// coordinates on an open model whose generalized stiffness is
    /// positive definite: shift-invert Lanczos
    /// (`softrod_dynamics::lowest_modes`, docs/theory.md E11), no `n × n`
    /// matrix. Otherwise — closures, free joints or joints without springs,
    /// small models, or a tangent stiffness that is not symmetric
    /// (follower loads, world-frame moments, cables), which Lanczos
    /// refuses — the dense eigensolver of [`Simulation::modes_about`]
    /// (the symmetric part, as there), whose matrices must fit the memory
    /// limit ([`crate::Error::TooLarge`]); a large non-symmetric model
    /// whose matrices do not fit gets Lanczos' refusal.
    pub fn lowest_modes_about(&mut self, q: &[f64], count: usize) -> Result<Modes> {
        self.check("q", q)?;
        if self.lanczos_applies() {
            let s = &mut self.system;
            match lowest_modes(&s.model, &mut s.data, q, 0.0, count) {
                Ok(m) => return Ok(m),
                Err(e @ DynamicsError::NotSymmetric { .. }) => {
                    if self.check_dense("modes", MODES_DENSE_MATRICES).is_err() {
                        return Err(e.into());
                    }
                }
                Err(e) => return Err(e.into()),
            }
        }
        let mut m = self.modes_about(q)?;
        let k = count.min(m.omega.len());
        m.omega = m.omega.rows(0, k).into_owned();
        m.shapes = m.shapes.columns(0, k).into_owned();
        Ok(m)
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
