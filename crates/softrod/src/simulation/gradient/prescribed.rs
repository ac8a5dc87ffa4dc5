//! The derivatives with respect to the samples of prescribed joints
//! (docs/theory-control.md G17–G20; closed models G28).
//!
//! A prescribed joint's coordinates `p(t)` are not in `q`; the free
//! coordinates' inverse dynamics `ID_f(t, q, q̇, q̈; p, ṗ, p̈)` depends on
//! them nonlinearly. Its derivatives are read off a *companion* model: the
//! same elements with every prescribed joint made an ordinary joint, whose
//! coordinates `q_c = (q, p)` (in the model's element order) are then
//! generalized coordinates. Its inverse dynamics at `(q, p)`, `(q̇, ṗ)`,
//! `(q̈, p̈)` has the free rows `ID_f` (the same tree, the same joint
//! motions: a prescribed joint carries no spring or damper, and nothing
//! else tells the two apart), so the analytic `∂ID/∂q_c`, `∂ID/∂q̇_c` and
//! `M_c` of its prescribed columns, restricted to the free rows, are
//! `∂ID_f/∂p`, `∂ID_f/∂ṗ` and `∂ID_f/∂p̈ = M_fp` (G17). A spline is linear
//! in its samples, `p(t) = Σᵢ xᵢ Bᵢ(t)` with the cardinal splines `Bᵢ`
//! (the spline through the unit samples `eᵢ`, its own rate and
//! acceleration the `Ḃᵢ`, `B̈ᵢ`), which chains them to the samples (G18).
//! Everything is O(N) per stage: one linearization of the companion and
//! its transposed (or forward) products.

use nalgebra::{DMatrix, DVector, Vector3};
use softrod_dynamics::{
    Curve, Data, DynamicsError, Element, ElementKind, Forces, IdDerivatives, Model, Spline,
    inverse_dynamics_jvp, inverse_dynamics_linearization_with, inverse_dynamics_mass_product,
    inverse_dynamics_vjp, section_jacobian,
};

use super::params::{bad, element_index};
use crate::error::Result;

/// The element `element` of `model` whose joint is prescribed by splines
/// of a common sample count: its index and its gradient length
/// (samples × coordinates). Errors name `name`.
pub(crate) fn parse(model: &Model, name: &str, element: &str) -> Result<(usize, usize)> {
    let e = element_index(model, name, element)?;
    let joint = &model.elements()[e].attachment.joint;
    let Some(motion) = &joint.prescribed else {
        return Err(bad(
            name,
            format!(
                "the joint of '{element}' is not prescribed (a {} joint: its coordinates are \
                 degrees of freedom, differentiate q0 and qdot0 instead)",
                joint.kind.name()
            ),
        ));
    };
    let mut samples = None;
    for (c, curve) in motion.curves.iter().enumerate() {
        let Curve::Spline(s) = curve else {
            return Err(bad(
                name,
                format!(
                    "coordinate {c} of the joint of '{element}' follows a sinusoid, which has \
                     no samples to differentiate by"
                ),
            ));
        };
        let n = s.times().len();
        if *samples.get_or_insert(n) != n {
            return Err(bad(
                name,
                format!(
                    "the curves of the joint of '{element}' have different sample counts; \
                     gradients need one table of samples per joint"
                ),
            ));
        }
    }
    Ok((e, samples.unwrap_or(0) * motion.curves.len()))
}

/// The model with every prescribed joint made an ordinary one (G17), and
/// where each coordinate of the original lands in it.
#[derive(Debug)]
struct Companion {
    model: Model,
    /// Free coordinate `i` of the original is `free[i]` of the companion.
    free: Vec<usize>,
    /// Prescribed coordinate `k` of the original
    /// ([`Model::n_prescribed`]'s order) is `pres[k]` of the companion.
    pres: Vec<usize>,
}

impl Companion {
    fn new(model: &Model) -> Result<Self> {
        let elements = model
            .elements()
            .iter()
            .map(|info| {
                let mut attachment = info.attachment.clone();
                attachment.joint.prescribed = None;
                match info.kind {
                    ElementKind::Rod(r) => Element::Rod(model.rods()[r].spec.clone(), attachment),
                    ElementKind::Body(b) => {
                        Element::Body(model.bodies()[b].spec.clone(), attachment)
                    }
                }
            })
            .collect();
        let companion = Model::with_elements(elements, model.gravity(), model.quadrature().len())?;
        let mut free = vec![0; model.n_dof()];
        let mut pres = vec![0; model.n_prescribed()];
        for (info, cinfo) in model.elements().iter().zip(companion.elements()) {
            for (i, c) in info.joint_dofs.clone().zip(cinfo.joint_dofs.clone()) {
                free[i] = c;
            }
            for (k, c) in info.prescribed_dofs.clone().zip(cinfo.joint_dofs.clone()) {
                pres[k] = c;
            }
        }
        for (rod, crod) in model.rods().iter().zip(companion.rods()) {
            for (i, c) in rod.dofs().zip(crod.dofs()) {
                free[i] = c;
            }
        }
        Ok(Self {
            model: companion,
            free,
            pres,
        })
    }
}

/// One `ELEMENT.prescribed` parameter: its slots and its cardinal splines.
#[derive(Debug)]
struct Entry {
    /// The first slot among the system's parameters; entry `(i, c)`
    /// (sample `i`, coordinate `c`) is `slot + i·dof + c`, the order of the
    /// scene's `values` rows.
    slot: usize,
    /// The joint's coordinates in the companion.
    comp: Vec<usize>,
    /// The joint's coordinates among the original's prescribed ones
    /// ([`Model::n_prescribed`]'s order).
    pres: Vec<usize>,
    /// `basis[c][i]`: coordinate `c`'s cardinal spline of sample `i`.
    basis: Vec<Vec<Spline>>,
}

impl Entry {
    fn dof(&self) -> usize {
        self.comp.len()
    }
}

/// The prescribed-sample parameters of a gradient and their workspace.
#[derive(Debug)]
pub(crate) struct PrescribedParams {
    companion: Companion,
    work: IdDerivatives,
    entries: Vec<Entry>,
    /// The companion's `q_c, q̇_c, q̈_c` at the last point, and scratch.
    qc: DVector<f64>,
    qdc: DVector<f64>,
    qddc: DVector<f64>,
    u: DVector<f64>,
    oq: DVector<f64>,
    oqd: DVector<f64>,
    om: DVector<f64>,
    /// The prescribed values, rates and accelerations at `t`.
    p: Vec<f64>,
    pd: Vec<f64>,
    pdd: Vec<f64>,
    /// The companion's buffers for the loss's section Jacobians.
    data: Option<Data>,
}

impl PrescribedParams {
    pub(crate) fn new(model: &Model) -> Result<Self> {
        let companion = Companion::new(model)?;
        let nc = companion.model.n_dof();
        let np = model.n_prescribed();
        Ok(Self {
            work: IdDerivatives::for_products(&companion.model),
            companion,
            entries: Vec::new(),
            qc: DVector::zeros(nc),
            qdc: DVector::zeros(nc),
            qddc: DVector::zeros(nc),
            u: DVector::zeros(nc),
            oq: DVector::zeros(nc),
            oqd: DVector::zeros(nc),
            om: DVector::zeros(nc),
            p: vec![0.0; np],
            pd: vec![0.0; np],
            pdd: vec![0.0; np],
            data: None,
        })
    }

    /// Adds element `element`'s samples (checked by [`parse`]) at `slot`.
    pub(crate) fn add(&mut self, model: &Model, element: usize, slot: usize) -> Result<()> {
        let info = &model.elements()[element];
        let motion = info
            .attachment
            .joint
            .prescribed
            .as_ref()
            .expect("checked by parse");
        let mut basis = Vec::with_capacity(motion.curves.len());
        for curve in &motion.curves {
            let Curve::Spline(s) = curve else {
                unreachable!("checked by parse")
            };
            let times = s.times();
            let mut unit = vec![0.0; times.len()];
            let mut splines = Vec::with_capacity(times.len());
            for i in 0..times.len() {
                unit[i] = 1.0;
                splines.push(Spline::new(times, &unit).map_err(|m| bad(&info.name, m))?);
                unit[i] = 0.0;
            }
            basis.push(splines);
        }
        let comp = info
            .prescribed_dofs
            .clone()
            .map(|k| self.companion.pres[k])
            .collect();
        let pres = info.prescribed_dofs.clone().collect();
        self.entries.push(Entry {
            slot,
            comp,
            pres,
            basis,
        });
        Ok(())
    }

    /// Every sample entry at `t`: its slot, its coordinate among the
    /// original's prescribed ones, and its cardinal spline's value, rate
    /// and acceleration `(Bᵢ, Ḃᵢ, B̈ᵢ)(t)` (G18).
    pub(crate) fn samples_at(
        &self,
        t: f64,
    ) -> impl Iterator<Item = (usize, usize, (f64, f64, f64))> + '_ {
        self.entries.iter().flat_map(move |e| {
            let dof = e.dof();
            e.pres.iter().enumerate().flat_map(move |(c, &k)| {
                e.basis[c]
                    .iter()
                    .enumerate()
                    .map(move |(i, b)| (e.slot + i * dof + c, k, b.eval(t)))
            })
        })
    }

    /// The slots of every sample entry.
    pub(crate) fn slots(&self) -> impl Iterator<Item = usize> + '_ {
        self.entries
            .iter()
            .flat_map(|e| e.slot..e.slot + e.dof() * e.basis.first().map_or(0, Vec::len))
    }

    /// `q_c, q̇_c, q̈_c` from the original's `(q, q̇, q̈)` and the prescribed
    /// motion at `t`.
    fn fill(&mut self, model: &Model, t: f64, q: &[f64], qd: &[f64], qdd: &[f64]) {
        for info in model.elements() {
            if let Some(m) = &info.attachment.joint.prescribed {
                for (c, k) in info.prescribed_dofs.clone().enumerate() {
                    (self.p[k], self.pd[k], self.pdd[k]) = m.curves[c].eval(t);
                }
            }
        }
        for (i, &c) in self.companion.free.iter().enumerate() {
            self.qc[c] = q[i];
            self.qdc[c] = qd[i];
            self.qddc[c] = qdd[i];
        }
        for (k, &c) in self.companion.pres.iter().enumerate() {
            self.qc[c] = self.p[k];
            self.qdc[c] = self.pd[k];
            self.qddc[c] = self.pdd[k];
        }
    }

    /// The companion's linearization at the original's `(t, q, q̇, q̈)`
    /// (G17), with the run's cable tensions when they are inputs.
    fn linearize(
        &mut self,
        model: &Model,
        tensions: Option<&[f64]>,
        t: f64,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
    ) -> Result<(), DynamicsError> {
        self.fill(model, t, q, qd, qdd);
        match (tensions, &mut self.work.tensions) {
            (None, w) => *w = None,
            (Some(u), Some(w)) => w.as_mut_slice().copy_from_slice(u),
            (Some(u), w) => *w = Some(DVector::from_column_slice(u)),
        }
        inverse_dynamics_linearization_with(
            &self.companion.model,
            &mut self.work,
            Forces::ALL,
            t,
            self.qc.as_slice(),
            self.qdc.as_slice(),
            self.qddc.as_slice(),
        )?;
        Ok(())
    }

    /// Adds `−zᵀ ∂ID_f/∂xᵢ` to `out` for every sample `xᵢ` (G19): one
    /// transposed product and one mass product of the companion with `z`
    /// on its free rows, chained with the cardinal splines at `t`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn force_vjp(
        &mut self,
        model: &Model,
        tensions: Option<&[f64]>,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        z: &DVector<f64>,
        out: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.linearize(
            model,
            tensions,
            t,
            q.as_slice(),
            qd.as_slice(),
            qdd.as_slice(),
        )?;
        self.u.fill(0.0);
        for (i, &c) in self.companion.free.iter().enumerate() {
            self.u[c] = z[i];
        }
        let cm = &self.companion.model;
        inverse_dynamics_vjp(
            cm,
            &mut self.work,
            self.u.as_slice(),
            self.oq.as_mut_slice(),
            self.oqd.as_mut_slice(),
        )?;
        // `(M_c u)_p = Σ_f M_pf z_f = zᵀ M_fp`: M is symmetric.
        inverse_dynamics_mass_product(
            cm,
            &mut self.work,
            self.u.as_slice(),
            self.om.as_mut_slice(),
        )?;
        for e in &self.entries {
            let dof = e.dof();
            for (c, &j) in e.comp.iter().enumerate() {
                let (gq, gv, ga) = (self.oq[j], self.oqd[j], self.om[j]);
                for (i, b) in e.basis[c].iter().enumerate() {
                    let (b0, b1, b2) = b.eval(t);
                    out[e.slot + i * dof + c] -= gq * b0 + gv * b1 + ga * b2;
                }
            }
        }
        Ok(())
    }

    /// Writes `−∂ID_f/∂xᵢ` into column `slot(i)` of `out` for every sample
    /// (G20; the caller applies `M⁻¹`): per coordinate, the companion's
    /// forward products with its unit vector, chained with the cardinal
    /// splines at `t`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn force_columns(
        &mut self,
        model: &Model,
        tensions: Option<&[f64]>,
        t: f64,
        q: &DVector<f64>,
        qd: &DVector<f64>,
        qdd: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), DynamicsError> {
        self.linearize(
            model,
            tensions,
            t,
            q.as_slice(),
            qd.as_slice(),
            qdd.as_slice(),
        )?;
        let cm = &self.companion.model;
        for e in &self.entries {
            let dof = e.dof();
            for (c, &j) in e.comp.iter().enumerate() {
                // ∂ID/∂q_j, ∂ID/∂q̇_j and M e_j of the companion.
                self.u.fill(0.0);
                self.u[j] = 1.0;
                self.om.fill(0.0);
                inverse_dynamics_jvp(
                    cm,
                    &mut self.work,
                    self.u.as_slice(),
                    self.om.as_slice(),
                    self.oq.as_mut_slice(),
                )?;
                inverse_dynamics_jvp(
                    cm,
                    &mut self.work,
                    self.om.as_slice(),
                    self.u.as_slice(),
                    self.oqd.as_mut_slice(),
                )?;
                inverse_dynamics_mass_product(
                    cm,
                    &mut self.work,
                    self.u.as_slice(),
                    self.om.as_mut_slice(),
                )?;
                for (i, b) in e.basis[c].iter().enumerate() {
                    let (b0, b1, b2) = b.eval(t);
                    let col = e.slot + i * dof + c;
                    for (r, &fc) in self.companion.free.iter().enumerate() {
                        out[(r, col)] = -(self.oq[fc] * b0 + self.oqd[fc] * b1 + self.om[fc] * b2);
                    }
                }
            }
        }
        Ok(())
    }

    /// The direct dependence of a position-tracking term on the samples
    /// (G19): adds `w eᵀ ∂x/∂p · Bᵢ(t)` to `out` for the section of rod
    /// `rod` at `s`, with `e = x − x*` its position error. The section's
    /// world velocity from the companion's spatial Jacobian:
    /// `ẋ = v + ω × x` of its columns `(ω, v)`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn position_term(
        &mut self,
        model: &Model,
        t: f64,
        q: &[f64],
        rod: usize,
        s: f64,
        target: [f64; 3],
        weight: f64,
        out: &mut [f64],
    ) -> Result<()> {
        self.fill(model, t, q, q, q);
        let cm = &self.companion.model;
        let data = self.data.get_or_insert_with(|| Data::new(cm));
        let (g, jac) = section_jacobian(cm, data, self.qc.as_slice(), rod, s)?;
        let x = g.translation;
        let e = Vector3::new(x[0] - target[0], x[1] - target[1], x[2] - target[2]);
        for en in &self.entries {
            let dof = en.dof();
            for (c, &j) in en.comp.iter().enumerate() {
                let w = Vector3::new(jac[(0, j)], jac[(1, j)], jac[(2, j)]);
                let v = Vector3::new(jac[(3, j)], jac[(4, j)], jac[(5, j)]);
                let dx = v + w.cross(&Vector3::new(x[0], x[1], x[2]));
                let gp = weight * e.dot(&dx);
                for (i, b) in en.basis[c].iter().enumerate() {
                    out[en.slot + i * dof + c] += gp * b.eval(t).0;
                }
            }
        }
        Ok(())
    }
}
