//! The parameters a gradient is taken with respect to, and the system the
//! backward pass differentiates: the rod system plus the derivatives
//! `∂q̈/∂p` of its parameters, formed by linearity (docs/theory-control.md
//! G8).
//!
//! The inverse dynamics `ID(q, q̇, q̈; p)` is affine in each parameter the
//! names below allow: Young's and shear modulus (the elastic force
//! `K(q − q̄)`, `K` linear in `E` and `G`), density (inertia, Coriolis and
//! gravity of the rods), viscosity (`D q̇`), a body's mass (its screw
//! inertia and weight, at a fixed inertia about its centre of mass), and a
//! cable's tension values (the cable force is linear in the tension, a
//! table interpolates its values linearly). So for any `Δ ≠ 0`
//! `∂ID/∂p = (ID(p + Δ) − ID(p))/Δ` exactly — no step error, only the
//! round-off of the two evaluations — and `∂q̈/∂p = −M⁻¹ ∂ID/∂p`. The
//! backward pass needs `wᵀ ∂q̈/∂p = −(M⁻¹w)ᵀ ∂ID/∂p` (`M` symmetric): one
//! O(N) solve with `M` per stage, one inverse dynamics per density or mass
//! entry (and one shared by them at `p`), and for the moduli, viscosity and
//! tensions the difference of the strain-space forces alone
//! (`softrod_dynamics::strain_space_force`: `ID = ID_rest − τ_s`, and only
//! `τ_s` depends on them), O(N) with no kinematic sweep.
//!
//! A closed model (G22): `ID` is its open tree's (the closure forces `Jᵀλ`
//! left out; the closure rows do not depend on the parameters), and
//! `∂q̈/∂p = −P M⁻¹ ∂ID/∂p` with the projection of the multiplier system
//! (`softrod_dynamics::closed_force_response`), symmetric as `M⁻¹` is.

use nalgebra::{DMatrix, DVector, Matrix6};
use softrod_dynamics::{
    ClosedDerivatives, Data, DynamicsError, Model, closed_force_response,
    closed_prescribed_derivatives, closed_row_response, closed_row_response_transposed,
    open_tree_inverse_dynamics, strain_space_force,
};
use softrod_integrate::{ParameterSystem, RodSystem, SecondOrderSystem};
use softrod_mechanics::{Material, RodProperties, Tension};

use super::actuator::{self, ActuatorParam};
use super::prescribed::{self, PrescribedParams};
use crate::error::{Error, Result};

/// What a parameter name refers to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    Young(usize),
    Shear(usize),
    Density(usize),
    Viscosity(usize),
    /// A body's mass (index among the model's bodies).
    Mass(usize),
    /// A cable's tension (index in the model's cable order): its constant,
    /// or one entry per table value.
    Tension(usize),
    /// The samples of a prescribed joint (index among the model's
    /// elements): one entry per sample and coordinate (G17–G20).
    Prescribed(usize),
    /// The force values of a joint actuator (index among the model's
    /// elements): one entry per value and coordinate (G29).
    Actuator(usize),
    Q0,
    Qdot0,
}

/// One parameter of a gradient request, with the number of gradient
/// entries it has.
#[derive(Clone, Debug)]
pub(crate) struct Param {
    pub name: String,
    pub kind: Kind,
    pub len: usize,
}

pub(super) fn bad(name: &str, message: impl Into<String>) -> Error {
    Error::Gradient {
        key: name.to_owned(),
        message: message.into(),
    }
}

/// The index of the rod or body named `element` among `model`'s elements;
/// errors name the parameter `name`.
pub(super) fn element_index(model: &Model, name: &str, element: &str) -> Result<usize> {
    model
        .elements()
        .iter()
        .position(|e| e.name == element)
        .ok_or_else(|| bad(name, format!("no rod or body named '{element}'")))
}

/// The cable `c` of `model`: its rod and its index on the rod.
fn locate_cable(model: &Model, c: usize) -> Option<(usize, usize)> {
    model.rods().iter().enumerate().find_map(|(r, rod)| {
        let k = c.checked_sub(rod.cable_offset)?;
        (k < rod.spec.cables.len()).then_some((r, k))
    })
}

/// Parses a parameter name: `q0`, `qdot0`, `ROD.young`,
/// `ROD.shear_modulus`, `ROD.density`, `ROD.viscosity`, `BODY.mass`,
/// `cableN.tension` (or `cable[N].tension`; `N` in the model's cable
/// order, the scene's `[[cable]]` order), `ELEMENT.prescribed` (the samples
/// of the prescribed joint of rod or body `ELEMENT`), `ELEMENT.actuator`
/// (the force values of its joint's actuator).
pub(crate) fn parse(model: &Model, name: &str) -> Result<Param> {
    let n = model.n_dof();
    match name {
        "q0" => {
            return Ok(Param {
                name: name.into(),
                kind: Kind::Q0,
                len: n,
            });
        }
        "qdot0" => {
            return Ok(Param {
                name: name.into(),
                kind: Kind::Qdot0,
                len: n,
            });
        }
        _ => {}
    }
    let Some((element, key)) = name.rsplit_once('.') else {
        return Err(bad(
            name,
            "expected q0, qdot0, ROD.young, ROD.shear_modulus, ROD.density, ROD.viscosity, \
             BODY.mass, cableN.tension, ELEMENT.prescribed or ELEMENT.actuator",
        ));
    };
    let rod = || {
        model
            .rods()
            .iter()
            .position(|r| r.spec.name == element)
            .ok_or_else(|| bad(name, format!("no rod named '{element}'")))
    };
    let kind = match key {
        "young" => Kind::Young(rod()?),
        "shear_modulus" => {
            let r = rod()?;
            if let Some(nu) = model.rods()[r]
                .spec
                .properties
                .material()
                .specified_poisson()
            {
                return Err(bad(
                    name,
                    format!(
                        "rod '{element}' gives its material by poisson = {nu}: its shear \
                         modulus follows young (differentiate '{element}.young', at a fixed \
                         Poisson ratio)"
                    ),
                ));
            }
            Kind::Shear(r)
        }
        "density" => Kind::Density(rod()?),
        "viscosity" => Kind::Viscosity(rod()?),
        "mass" => Kind::Mass(
            model
                .bodies()
                .iter()
                .position(|b| b.spec.name == element)
                .ok_or_else(|| bad(name, format!("no body named '{element}'")))?,
        ),
        "tension" => {
            let index = element
                .strip_prefix("cable")
                .map(|s| s.trim_start_matches('[').trim_end_matches(']'))
                .and_then(|s| s.parse::<usize>().ok())
                .ok_or_else(|| bad(name, "a tension is named cableN.tension (N from 0)"))?;
            if index >= model.n_cables() {
                return Err(bad(
                    name,
                    format!("no cable {index} (the model has {})", model.n_cables()),
                ));
            }
            Kind::Tension(index)
        }
        "prescribed" => {
            let (e, len) = prescribed::parse(model, name, element)?;
            return Ok(Param {
                name: name.into(),
                kind: Kind::Prescribed(e),
                len,
            });
        }
        "actuator" => {
            let (e, len) = actuator::parse(model, name, element)?;
            return Ok(Param {
                name: name.into(),
                kind: Kind::Actuator(e),
                len,
            });
        }
        _ => {
            return Err(bad(
                name,
                format!(
                    "unknown parameter '{key}' (young, shear_modulus, density, viscosity, mass, \
                     tension, prescribed, actuator)"
                ),
            ));
        }
    };
    let len = match kind {
        Kind::Tension(c) => {
            let (r, k) = locate_cable(model, c).expect("index checked");
            match &model.rods()[r].spec.cables[k].tension {
                Tension::Constant(_) => 1,
                Tension::Table { values, .. } => values.len(),
            }
        }
        _ => 1,
    };
    Ok(Param {
        name: name.into(),
        kind,
        len,
    })
}

/// A model with one parameter moved by `delta`, and its buffers.
#[derive(Debug)]
struct Variant {
    model: Model,
    data: Data,
    delta: f64,
    /// Where its derivative goes among the system's parameters.
    slot: usize,
    /// The parameter enters the strain-space forces only (moduli,
    /// viscosity, tensions): `∂ID/∂p = −∂τ_s/∂p`.
    strain_only: bool,
    /// A density or mass: how `∂ID/∂p` follows from the inertia products
    /// of a kept linearization (G13).
    inertia: Option<Inertia>,
}

/// `∂ID/∂p` of a density or mass through the inertia products (D85): rod
/// `r`'s `zᵀ∂ID/∂s_r` times `1/ρ` (`ID` is linear in the density), or body
/// `b`'s `G_b` against `∂𝓜_b/∂m` (affine: the variant's inertia minus the
/// model's, over `Δ`).
#[derive(Clone, Debug)]
enum Inertia {
    Rod { rod: usize, per_density: f64 },
    Body { body: usize, dm: Box<Matrix6<f64>> },
}

/// A rod material with one constant moved.
fn material_with(m: &Material, kind: Kind, delta: f64) -> Result<Material> {
    let (mut rho, mut e, mut g, mut mu) =
        (m.density(), m.young(), m.shear_modulus(), m.viscosity());
    match kind {
        Kind::Young(_) => e += delta,
        Kind::Shear(_) => g += delta,
        Kind::Density(_) => rho += delta,
        Kind::Viscosity(_) => mu += delta,
        _ => unreachable!("not a material constant"),
    }
    let b = Material::builder().density(rho).young(e).viscosity(mu);
    // A material given by its Poisson ratio keeps it: G follows E.
    Ok(match m.specified_poisson() {
        Some(nu) => b.poisson(nu),
        None => b.shear_modulus(g),
    }
    .build()?)
}

/// The model with entry `entry` of parameter `kind` moved by `Δ` (chosen
/// here: the value itself when positive, else a scale of the model), and
/// `Δ`.
fn variant(model: &Model, kind: Kind, entry: usize) -> Result<(Model, f64)> {
    let scaled = |v: f64, fallback: f64| if v > 0.0 { v } else { fallback };
    match kind {
        Kind::Young(r) | Kind::Shear(r) | Kind::Density(r) | Kind::Viscosity(r) => {
            let spec = &model.rods()[r].spec;
            let m = spec.properties.material();
            let delta = match kind {
                Kind::Young(_) => m.young(),
                Kind::Shear(_) => m.shear_modulus(),
                Kind::Density(_) => m.density(),
                // A zero viscosity: the one that damps in a millisecond.
                _ => scaled(m.viscosity(), 1e-3 * m.shear_modulus()),
            };
            let mut spec = spec.clone();
            spec.properties = RodProperties::new(
                *spec.properties.section(),
                material_with(m, kind, delta)?,
                spec.properties.length(),
            )?;
            Ok((model.clone().with_rod_spec(r, spec)?, delta))
        }
        Kind::Mass(b) => {
            let mut spec = model.bodies()[b].spec.clone();
            let delta = spec.mass;
            spec.mass += delta;
            Ok((model.clone().with_body_spec(b, spec)?, delta))
        }
        Kind::Tension(c) => {
            let (r, k) = locate_cable(model, c).expect("index checked");
            let mut spec = model.rods()[r].spec.clone();
            let tension = &mut spec.cables[k].tension;
            let delta = match tension {
                Tension::Constant(v) => {
                    let d = scaled(*v, 1.0);
                    *v += d;
                    d
                }
                Tension::Table { values, .. } => {
                    let d = scaled(values[entry], 1.0);
                    values[entry] += d;
                    d
                }
            };
            Ok((model.clone().with_rod_spec(r, spec)?, delta))
        }
        Kind::Q0 | Kind::Qdot0 | Kind::Prescribed(_) | Kind::Actuator(_) => {
            unreachable!("initial states, prescribed samples and actuators have no model variant")
        }
    }
}

/// The closure terms' derivatives by the prescribed coordinates at
/// `(t, q, q̇)` into `work` (G28), with the run's actuation.
fn closure_terms(
    sys: &mut RodSystem,
    work: &mut ClosedDerivatives,
    t: f64,
    q: &DVector<f64>,
    qd: &DVector<f64>,
) -> Result<(), DynamicsError> {
    closed_prescribed_derivatives(
        &sys.model,
        &mut sys.data,
        work,
        t,
        q.as_slice(),
        qd.as_slice(),
        sys.tau.as_ref().map(|v| v.as_slice()),
    )
}

/// The rod system with the parameter derivatives of the backward pass
/// (a [`ParameterSystem`]); its parameters are the model parameters of
/// `params` in order, one per gradient entry (`q0`, `qdot0` are the
/// adjoint's own).
pub(crate) struct ParamSystem<'a> {
    sys: &'a mut RodSystem,
    variants: Vec<Variant>,
    n_params: usize,
    z: DVector<f64>,
    id0: DVector<f64>,
    sf0: DVector<f64>,
    /// The inertia products' outputs (G13, D85), per rod and per body.
    rods: Vec<f64>,
    bodies: Vec<Matrix6<f64>>,
    /// The point `(t, q, q̇, q̈)` of the last dense
    /// [`force_jacobians`](ParameterSystem::force_jacobians) (stage 0 of a
    /// step, or a switched stage), whose derivatives' workspace the inertia
    /// products can use (G16); `None` before one.
    dense_at: Option<Point>,
    /// A closed model: the workspace of the constrained projection
    /// `P M⁻¹` (G22) and one column for its products.
    closed: Option<(Box<ClosedDerivatives>, DMatrix<f64>)>,
    /// The samples of prescribed joints (G17–G20), if any are asked for.
    prescribed: Option<Box<PrescribedParams>>,
    /// The joint actuators' force values asked for (G29).
    actuators: Vec<ActuatorParam>,
    /// A closed model with prescribed samples (G28): `ν` and `h` (m), a
    /// column (n), and per prescribed coordinate the cotangent's products
    /// with the closure terms' derivatives by `p`, `ṗ`, `p̈`.
    nu: DVector<f64>,
    hrow: DVector<f64>,
    col: DVector<f64>,
    by_coordinate: Vec<[f64; 3]>,
}

/// An evaluation point `(t, q, q̇, q̈)`.
struct Point(f64, DVector<f64>, DVector<f64>, DVector<f64>);

impl<'a> ParamSystem<'a> {
    pub(crate) fn new(sys: &'a mut RodSystem, params: &[Param]) -> Result<Self> {
        let mut variants = Vec::new();
        let mut slot = 0;
        let inputs = sys.data.cable_tensions().map(<[f64]>::to_vec);
        let mut prescribed: Option<Box<PrescribedParams>> = None;
        let mut actuators = Vec::new();
        for p in params {
            if matches!(p.kind, Kind::Q0 | Kind::Qdot0) {
                continue;
            }
            if let Kind::Actuator(element) = p.kind {
                if sys.data.joint_forces().is_some() {
                    return Err(bad(
                        &p.name,
                        "the joint forces are set as inputs, not by the actuators' schedules",
                    ));
                }
                actuators.push(ActuatorParam::new(&sys.model, element, slot));
                slot += p.len;
                continue;
            }
            if let Kind::Prescribed(element) = p.kind {
                let pp = match &mut prescribed {
                    Some(pp) => pp,
                    None => prescribed.insert(Box::new(PrescribedParams::new(&sys.model)?)),
                };
                pp.add(&sys.model, element, slot)?;
                slot += p.len;
                continue;
            }
            if matches!(p.kind, Kind::Tension(_)) && inputs.is_some() {
                return Err(bad(
                    &p.name,
                    "the cable tensions are set as inputs, not by the model's tension",
                ));
            }
            for entry in 0..p.len {
                let (model, delta) = variant(&sys.model, p.kind, entry)?;
                let inertia = match p.kind {
                    Kind::Density(rod) => Some(Inertia::Rod {
                        rod,
                        per_density: 1.0
                            / sys.model.rods()[rod].spec.properties.material().density(),
                    }),
                    Kind::Mass(body) => Some(Inertia::Body {
                        body,
                        dm: Box::new(
                            (model.bodies()[body].inertia - sys.model.bodies()[body].inertia)
                                / delta,
                        ),
                    }),
                    _ => None,
                };
                let mut data = Data::new(&model);
                data.set_cable_tensions(&model, inputs.as_deref())?;
                variants.push(Variant {
                    model,
                    data,
                    delta,
                    slot,
                    strain_only: matches!(
                        p.kind,
                        Kind::Young(_) | Kind::Shear(_) | Kind::Viscosity(_) | Kind::Tension(_)
                    ),
                    inertia,
                });
                slot += 1;
            }
        }
        let n = sys.model.n_dof();
        let (rods, bodies) = (sys.model.rods().len(), sys.model.bodies().len());
        let (m, np) = (sys.model.n_constraints(), sys.model.n_prescribed());
        let closed = sys.model.has_closures().then(|| {
            (
                Box::new(ClosedDerivatives::new(&sys.model)),
                DMatrix::zeros(n, 1),
            )
        });
        Ok(Self {
            sys,
            variants,
            n_params: slot,
            z: DVector::zeros(n),
            id0: DVector::zeros(n),
            sf0: DVector::zeros(n),
            rods: vec![0.0; rods],
            bodies: vec![Matrix6::zeros(); bodies],
            dense_at: None,
            closed,
            prescribed,
            actuators,
            nu: DVector::zeros(m),
            hrow: DVector::zeros(m),
            col: DVector::zeros(n),
            by_coordinate: vec![[0.0; 3]; np],
        })
    }
}

impl ParamSystem<'_> {
    /// The moduli, viscosity and tensions: adds `+zᵀ (τ_s(pⱼ + Δⱼ) −
    /// τ_s(pⱼ))/Δⱼ` of the strain-space forces alone (G8).
    fn strain_products(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        if !self.variants.iter().any(|v| v.strain_only) {
            return Ok(());
        }
        let (q, qd) = (q.as_slice(), qd.as_slice());
        self.sf0.copy_from(strain_space_force(
            &self.sys.model,
            &mut self.sys.data,
            t,
            q,
            qd,
        )?);
        for v in self.variants.iter_mut().filter(|v| v.strain_only) {
            let sf = strain_space_force(&v.model, &mut v.data, t, q, qd)?;
            let mut s = 0.0;
            for r in 0..sf.len() {
                s += z[r] * (sf[r] - self.sf0[r]);
            }
            out[v.slot] += s / v.delta;
        }
        Ok(())
    }

    /// Subtracts the inertia products in `rods`, `bodies` (`zᵀ∂ID/∂s_r`,
    /// `G_b`, D85) from the density and mass entries of `out` (G13).
    fn apply_inertia(&self, out: &mut [f64]) {
        for v in &self.variants {
            out[v.slot] -= match &v.inertia {
                Some(Inertia::Rod { rod, per_density }) => self.rods[*rod] * per_density,
                Some(Inertia::Body { body, dm }) => self.bodies[*body].component_mul(dm).sum(),
                None => continue,
            };
        }
    }

    /// A closed model: `x ← P M⁻¹ x` at `(t, q, q̇)` (G22), the
    /// constrained acceleration's response to the generalized forces in the
    /// columns of `x` (`x = None`: the one column of the workspace). False
    /// for an open model (nothing done).
    fn closed_response(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        x: Option<&mut DMatrix<f64>>,
    ) -> Result<bool, DynamicsError> {
        let Some((work, column)) = self.closed.as_mut() else {
            return Ok(false);
        };
        let sys = &mut *self.sys;
        closed_force_response(
            &sys.model,
            &mut sys.data,
            work,
            t,
            q.as_slice(),
            qd.as_slice(),
            sys.tau.as_ref().map(|v| v.as_slice()),
            x.unwrap_or(column),
        )?;
        Ok(true)
    }

    /// Adds the actuators' `−zᵀ ∂ID/∂xᵢ = z_j wᵢ(t)` (G29).
    fn actuator_products(&self, t: f64, z: &DVector<f64>, out: &mut [f64]) {
        for a in &self.actuators {
            for (slot, j, w) in a.weights(t) {
                out[slot] += z[j] * w;
            }
        }
    }

    /// Adds the prescribed samples' `−zᵀ ∂ID/∂xᵢ` (G19); nothing without
    /// them.
    fn prescribed_products(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let Some(pp) = self.prescribed.as_mut() else {
            return Ok(());
        };
        let sys = &*self.sys;
        pp.force_vjp(&sys.model, sys.data.cable_tensions(), t, q, qd, qdd, z, out)
    }

    /// A closed model with prescribed samples: adds the closure terms'
    /// part of `wᵀ ∂q̈/∂xᵢ` (G28), `zᵀ ∂(Jᵀλ)/∂xᵢ − νᵀ ∂R/∂xᵢ` with
    /// `z = P M⁻¹ w` and `ν = A⁻¹ Yᵀ w`; nothing otherwise.
    fn closed_prescribed_vjp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        w: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        let (Some(pp), Some((work, _))) = (self.prescribed.as_ref(), self.closed.as_mut()) else {
            return Ok(());
        };
        let sys = &mut *self.sys;
        closure_terms(sys, work, t, q, qd)?;
        closed_row_response_transposed(&sys.data, work, w, &mut self.nu)?;
        for (k, c) in self.by_coordinate.iter_mut().enumerate() {
            *c = [
                z.dot(&work.force_dp.column(k)) - self.nu.dot(&work.rows_dp.column(k)),
                -self.nu.dot(&work.rows_dpd.column(k)),
                -self.nu.dot(&work.rows_dpdd.column(k)),
            ];
        }
        for (slot, k, (b0, b1, b2)) in pp.samples_at(t) {
            let [a, b, c] = self.by_coordinate[k];
            out[slot] += a * b0 + b * b1 + c * b2;
        }
        Ok(())
    }

    /// The directly dependent part of a position-tracking loss term on the
    /// prescribed samples (G19): see [`PrescribedParams::position_term`].
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn prescribed_position_term(
        &mut self,
        t: f64,
        q: &[f64],
        rod: usize,
        s: f64,
        target: [f64; 3],
        weight: f64,
        out: &mut [f64],
    ) -> Result<()> {
        match self.prescribed.as_mut() {
            Some(pp) => pp.position_term(&self.sys.model, t, q, rod, s, target, weight, out),
            None => Ok(()),
        }
    }

    /// Whether prescribed samples are among the parameters.
    pub(crate) fn has_prescribed(&self) -> bool {
        self.prescribed.is_some()
    }

    /// `(t, q, q̇, q̈)` is the point of the last dense linearization.
    fn at_dense(&self, t: f64, q: &DVector<f64>, qd: &DVector<f64>, qdd: &DVector<f64>) -> bool {
        matches!(&self.dense_at, Some(Point(t0, q0, qd0, qdd0))
            if *t0 == t && q0 == q && qd0 == qd && qdd0 == qdd)
    }
}

impl SecondOrderSystem for ParamSystem<'_> {
    type Error = DynamicsError;

    fn dim(&self) -> usize {
        self.sys.dim()
    }

    fn accel(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &mut DVector<f64>,
    ) -> Result<(), DynamicsError> {
        self.sys.accel(t, q, qd, qdd)
    }

    fn jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        dqdd_dq: &mut DMatrix<f64>,
        dqdd_dqd: &mut DMatrix<f64>,
    ) -> Result<(), DynamicsError> {
        self.sys.jacobians(t, q, qd, dqdd_dq, dqdd_dqd)
    }

    // The rod system's structured solves, forwarded: the backward pass
    // preconditions its transposed stage solves with the O(N)
    // `M + aK + bD` (docs/theory-control.md G11).
    fn mass_form_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        constant: Option<(&mut DMatrix<f64>, &mut DMatrix<f64>)>,
    ) -> Result<bool, DynamicsError> {
        self.sys.mass_form_jacobians(t, q, qd, mass, constant)
    }

    fn has_mass_form(&self) -> bool {
        self.sys.has_mass_form()
    }

    fn force_residual(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        r: &mut DVector<f64>,
    ) -> Result<bool, DynamicsError> {
        self.sys.force_residual(t, q, qd, qdd, r)
    }

    fn factor_shifted_mass(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        a: f64,
        b: f64,
    ) -> Result<bool, DynamicsError> {
        self.sys.factor_shifted_mass(t, q, a, b)
    }

    fn solve_shifted_mass(&mut self, x: &mut DVector<f64>) -> Result<(), DynamicsError> {
        self.sys.solve_shifted_mass(x)
    }

    fn is_autonomous(&self) -> bool {
        self.sys.is_autonomous()
    }
}

impl ParameterSystem for ParamSystem<'_> {
    fn n_params(&self) -> usize {
        self.n_params
    }

    /// `wᵀ ∂q̈/∂pⱼ = −(M⁻¹w)ᵀ (ID(pⱼ + Δⱼ) − ID(pⱼ))/Δⱼ` (G8): one O(N)
    /// solve with `M`, then [`force_param_vjp`](Self::force_param_vjp). A
    /// closed model: `P M⁻¹` for `M⁻¹` (G22), `ID` the open tree's.
    fn accel_param_vjp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        w: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        if self.variants.is_empty() && self.prescribed.is_none() && self.actuators.is_empty() {
            return Ok(());
        }
        let mut z = std::mem::take(&mut self.z);
        z.copy_from(w);
        let solved = if let Some((_, column)) = self.closed.as_mut() {
            // A closed model: `P M⁻¹` (symmetric) for `M⁻¹` (G22).
            column.set_column(0, w);
            self.closed_response(t, q, qd, None).map(|_| {
                if let Some((_, column)) = &self.closed {
                    z.copy_from(&column.column(0));
                }
            })
        } else {
            // M(q) by the O(N) shifted solver with no shift.
            self.sys
                .factor_shifted_mass(t, q, 0.0, 0.0)
                .and_then(|_| self.sys.solve_shifted_mass(&mut z))
        }
        .and_then(|()| self.force_param_vjp(t, q, qd, qdd, &z, out))
        .and_then(|()| self.closed_prescribed_vjp(t, q, qd, w, &z, out));
        self.z = z;
        solved
    }

    /// `∂a/∂pⱼ = −M⁻¹ (ID(pⱼ + Δⱼ) − ID(pⱼ))/Δⱼ` column by column (G8,
    /// G21; `ID` is affine in each parameter): one inverse dynamics per
    /// entry and one at `p`, one O(N) solve with `M` each (a closed model:
    /// `P M⁻¹` for `M⁻¹`, G22).
    fn accel_param_jvp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), DynamicsError> {
        if self.variants.is_empty() && self.prescribed.is_none() && self.actuators.is_empty() {
            return Ok(());
        }
        let closed = self.closed.is_some();
        if !closed {
            self.sys.factor_shifted_mass(t, q, 0.0, 0.0)?;
        }
        let (qs, qds, qdds) = (q.as_slice(), qd.as_slice(), qdd.as_slice());
        self.id0.copy_from(open_tree_inverse_dynamics(
            &self.sys.model,
            &mut self.sys.data,
            t,
            qs,
            qds,
            qdds,
        )?);
        let mut z = std::mem::take(&mut self.z);
        for v in &mut self.variants {
            let id = open_tree_inverse_dynamics(&v.model, &mut v.data, t, qs, qds, qdds)?;
            for r in 0..z.len() {
                z[r] = -(id[r] - self.id0[r]) / v.delta;
            }
            if !closed {
                self.sys.solve_shifted_mass(&mut z)?;
            }
            out.set_column(v.slot, &z);
        }
        self.z = z;
        if let Some(pp) = self.prescribed.as_mut() {
            // `−∂ID/∂xᵢ` into the samples' columns, then `M⁻¹` on each
            // (a closed model: `+∂(Jᵀλ)/∂xᵢ`, then `P M⁻¹` below, G28).
            let sys = &mut *self.sys;
            pp.force_columns(&sys.model, sys.data.cable_tensions(), t, q, qd, qdd, out)?;
            if let Some((work, _)) = self.closed.as_mut() {
                closure_terms(sys, work, t, q, qd)?;
                for (slot, k, (b0, _, _)) in pp.samples_at(t) {
                    out.column_mut(slot).axpy(b0, &work.force_dp.column(k), 1.0);
                }
            } else {
                let mut z = std::mem::take(&mut self.z);
                for col in pp.slots() {
                    z.copy_from(&out.column(col));
                    sys.solve_shifted_mass(&mut z)?;
                    out.set_column(col, &z);
                }
                self.z = z;
            }
        }
        // The actuators' columns `e_j wᵢ(t)`, then `M⁻¹` (G29; a closed
        // model: `P M⁻¹` below).
        if !self.actuators.is_empty() {
            let mut z = std::mem::take(&mut self.z);
            for a in &self.actuators {
                for slot in a.slots() {
                    out.column_mut(slot).fill(0.0);
                }
                for (slot, j, w) in a.weights(t) {
                    out[(j, slot)] = w;
                }
                if !closed {
                    for slot in a.slots() {
                        z.copy_from(&out.column(slot));
                        self.sys.solve_shifted_mass(&mut z)?;
                        out.set_column(slot, &z);
                    }
                }
            }
            self.z = z;
        }
        if closed {
            // `−P M⁻¹ ∂ID/∂p` on all columns at once (G22).
            self.closed_response(t, q, qd, Some(out))?;
            if let (Some(pp), Some((work, _))) = (self.prescribed.as_ref(), self.closed.as_mut()) {
                // The rows' own dependence on the samples: `+Y A⁻¹ hᵢ`,
                // `hᵢ = −∂R/∂xᵢ` (G28), with the factorizations the
                // projection just used.
                for (slot, k, (b0, b1, b2)) in pp.samples_at(t) {
                    for r in 0..self.hrow.len() {
                        self.hrow[r] = -(b0 * work.rows_dp[(r, k)]
                            + b1 * work.rows_dpd[(r, k)]
                            + b2 * work.rows_dpdd[(r, k)]);
                    }
                    self.col.copy_from(&out.column(slot));
                    closed_row_response(&self.sys.data, work, &self.hrow, &mut self.col)?;
                    out.set_column(slot, &self.col);
                }
            }
        }
        Ok(())
    }

    /// `M(q)`, `∂ID/∂q`, `∂ID/∂q̇` of the rod system
    /// ([`RodSystem::force_jacobians`]).
    fn force_jacobians(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
        dr_dq: &mut DMatrix<f64>,
        dr_dqd: &mut DMatrix<f64>,
    ) -> Result<bool, DynamicsError> {
        let done = self
            .sys
            .force_jacobians(t, q, qd, qdd, mass, dr_dq, dr_dqd)?;
        match (&mut self.dense_at, done) {
            (_, false) => self.dense_at = None,
            (Some(Point(t0, q0, qd0, qdd0)), true) => {
                *t0 = t;
                q0.copy_from(q);
                qd0.copy_from(qd);
                qdd0.copy_from(qdd);
            }
            (None, true) => self.dense_at = Some(Point(t, q.clone(), qd.clone(), qdd.clone())),
        }
        Ok(done)
    }

    /// `M(q)` and `∂ID/∂q`, `∂ID/∂q̇` kept as an O(N) operator
    /// ([`RodSystem::force_linearization`]).
    fn force_linearization(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        mass: &mut DMatrix<f64>,
    ) -> Result<bool, DynamicsError> {
        self.sys.force_linearization(slot, t, q, qd, qdd, mass)
    }

    /// The same operator with `M(q)` kept as products
    /// ([`RodSystem::force_operators`], G15).
    fn force_operators(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
    ) -> Result<bool, DynamicsError> {
        self.sys.force_operators(slot, t, q, qd, qdd)
    }

    /// Its `M v` ([`RodSystem::force_mass_product`]).
    fn force_mass_product(
        &mut self,
        slot: usize,
        v: &DVector<f64>,
        out: &mut DVector<f64>,
    ) -> Result<(), DynamicsError> {
        self.sys.force_mass_product(slot, v, out)
    }

    /// Its transposed products ([`RodSystem::force_vjp`]).
    fn force_vjp(
        &mut self,
        slot: usize,
        u: &DVector<f64>,
        out_q: &mut DVector<f64>,
        out_qd: &mut DVector<f64>,
    ) -> Result<(), DynamicsError> {
        self.sys.force_vjp(slot, u, out_q, out_qd)
    }

    /// [`force_param_vjp`](Self::force_param_vjp) on the linearization
    /// kept in `slot` (G13): the densities and masses by the inertia
    /// products of that linearization (one O(N) pass for all of them,
    /// [`RodSystem::force_inertia_vjp`], D85) instead of an inverse
    /// dynamics each and one at `p`; the moduli, viscosity and tensions as
    /// there.
    fn force_param_vjp_kept(
        &mut self,
        slot: usize,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        if self.variants.iter().any(|v| v.inertia.is_some()) {
            self.sys
                .force_inertia_vjp(slot, z, &mut self.rods, &mut self.bodies)?;
        }
        self.strain_products(t, q, qd, z, out)?;
        self.apply_inertia(out);
        self.prescribed_products(t, q, qd, qdd, z, out)?;
        self.actuator_products(t, z, out);
        Ok(true)
    }

    /// `−zᵀ (ID(pⱼ + Δⱼ) − ID(pⱼ))/Δⱼ` (G8; `ID` is affine in each
    /// parameter): one inverse dynamics per density or mass entry plus one
    /// at `p`; for the moduli, viscosity and tensions `+zᵀ (τ_s(pⱼ + Δⱼ) −
    /// τ_s(pⱼ))/Δⱼ` of the strain-space forces alone (`ID = ID_rest − τ_s`,
    /// `ID_rest` independent of them), O(N) without a kinematic sweep.
    fn force_param_vjp(
        &mut self,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.strain_products(t, q, qd, z, out)?;
        self.prescribed_products(t, q, qd, qdd, z, out)?;
        self.actuator_products(t, z, out);
        if !self.variants.iter().any(|v| !v.strain_only) {
            return Ok(());
        }
        // At the point of the last dense linearization (stage 0): the
        // inertia products of its kept sums (G16), as G13 on stages 1–5.
        if self.at_dense(t, q, qd, qdd) {
            self.sys
                .force_jacobians_inertia_vjp(z, &mut self.rods, &mut self.bodies)?;
            self.apply_inertia(out);
            return Ok(());
        }
        let (q, qd, qdd) = (q.as_slice(), qd.as_slice(), qdd.as_slice());
        self.id0.copy_from(open_tree_inverse_dynamics(
            &self.sys.model,
            &mut self.sys.data,
            t,
            q,
            qd,
            qdd,
        )?);
        for v in self.variants.iter_mut().filter(|v| !v.strain_only) {
            let id = open_tree_inverse_dynamics(&v.model, &mut v.data, t, q, qd, qdd)?;
            let mut s = 0.0;
            for r in 0..id.len() {
                s += z[r] * (id[r] - self.id0[r]);
            }
            out[v.slot] -= s / v.delta;
        }
        Ok(())
    }
}
