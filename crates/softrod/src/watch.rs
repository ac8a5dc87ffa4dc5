//! What physics guarantees, watched along a run: the energy balance, a
//! positive stretch, and strains inside the model's range of validity.
//!
//! **Energy balance.** With `E = T + V_e + V_g` (kinetic, elastic,
//! gravitational; [`Energies`]) and `M q̈ + b(t, q, q̇) = 0`,
//! `b = C q̇ + G + τ_e + D q̇ − τ_c − Q_ext` (D21–D22), the skew symmetry of
//! `Ṁ − 2C` gives
//!
//! `dE/dt = P_nc = q̇ᵀ(τ_c + Q_ext − D q̇)`,
//!
//! the power of the cables (tensions × the rates of their lengths), of the
//! point, distributed and follower loads, of drag, and of the viscous
//! forces. It is computed as `P_nc = q̇ᵀ(b_c − b)` where `b_c` is the bias of
//! the *conservative* model — the same rods, inertia, stiffness and gravity,
//! with no viscosity, drag, cables or loads — so every non-conservative term
//! of the model is covered, whatever it is, and nothing is assumed about
//! its form. `W(t) = ∫ P_nc dt` is integrated by Simpson's rule over each
//! accepted step, the power at the step's midpoint taken at the state of
//! the cubic Hermite interpolant through the step's ends `(q, q̇)` (`q` to
//! O(h⁴), `q̇` to O(h³); fourth order in the step, `P_nc ≡ 0` and `W = 0`
//! exactly for a model without such terms). The trapezoidal rule alone
//! (second order) mistook its own error for a drift on the long steps an
//! implicit integrator takes through a smooth, driven motion (a base
//! shaken at 2 Hz, 28 ms steps: 1.1 % of the energy in play). The balance
//! error is `|E(t) − E(0) − W(t)|`.
//!
//! **Energy scale.** The error is compared with the energy in play:
//! `scale(t) = max_{τ ≤ t} [T(τ) + V_e(τ) + |V_g(τ) − V_g(0)|] + ∫₀ᵗ |P_nc| dτ`
//! (the gravitational energy counts by its change: its zero is arbitrary).
//! A run fails when `error(t) − U(t) > energy_tolerance · scale(t)` at an
//! accepted step, `U = Σ |S − T|` the work's uncertainty, the distance of
//! each step's Simpson work `S` from its trapezoidal one `T` (an estimate
//! of the trapezoid's error, far above Simpson's; zero for a model without
//! non-conservative terms; a drift below it goes unseen); it warns when
//! the largest error exceeds a tenth of the bound
//! relative to the final scale (early in a run the scale is tiny and the
//! ratio to it says little: measured up to 2e-2 in the first microseconds
//! of correct runs).
//!
//! **Closures.** The closure forces `Jᵀλ` do no work while a closure holds
//! exactly (`J q̇ = 0`), but the Baumgarte stabilization (D68) lets `J q̇`
//! follow the residual's noise, and against large forces (a weight, a
//! load carried by a locked structure) that noise times `λ` is work the
//! energies see. With closures the power therefore includes
//! `P_c = q̇ᵀJᵀλ = q̇ᵀ(M q̈ + b)` at the constrained `q̈` (the open tree's
//! inverse dynamics, plus the closures' share of the drives' forces, D60),
//! reported as [`EnergyBalance::closure_work`] and part of `W`.
//!
//! **Round-off floor.** No energy is computed better than the round-off of
//! the forces that act times the distances they act over: positions carry
//! `ε L` of round-off, so the potential of a force `F` is known to `ε F L`.
//! Errors below
//!
//! `floor = 10³ ε (T + V_e + |V_g| + |E(0)| + ∫|P| dτ + F L)`
//!
//! count as zero, where `F L` is the model's work scale: the sum over rods
//! and bodies of the weight, point and distributed loads and largest cable
//! tensions \[N\], times the sum of the rods' lengths \[m\], plus the loads'
//! moments \[N m\] (one radian). A rod welded at both ends that cannot move
//! has every energy at round-off (1.7e-23 J under its 0.4 N weight): far
//! below its floor, 1.8e-14 J.
//!
//! **Advice.** The message of a failure says what can help: a drive
//! (prescribed joint) that starts or stops with a nonzero rate before `t`
//! is an impulse, which no step size resolves (give it a zero rate at its
//! ends); otherwise a smaller step or tolerance, or a stiff integrator.

use nalgebra::DVector;
use softrod_dynamics::{
    Curve, Data, DynamicsError, Element, ElementKind, Energies, Model, Rod, bias_force, energies,
    forward_dynamics, inverse_dynamics,
};
use softrod_mechanics::validity::{StrainProblem, strain_validity};
use softrod_mechanics::{Material, RodProperties};

use crate::error::Error;

/// The energy balance of a run (see the module documentation for the
/// definitions). Energies in joules, times in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyBalance {
    /// `E(0) = T + V_e + V_g` at the start \[J\].
    pub initial: f64,
    /// The measured change `E(t_end) − E(0)` \[J\].
    pub change: f64,
    /// The work of the non-conservative forces `W(t_end) = ∫ P_nc dt` \[J\].
    pub work: f64,
    /// The largest balance error `|E(t) − E(0) − W(t)|` over the accepted
    /// steps \[J\].
    pub error: f64,
    /// `error / scale`: the largest error relative to the energy scale at
    /// the end (what the summary reports and warns on).
    pub relative: f64,
    /// The energy scale at the end \[J\].
    pub scale: f64,
    /// Time of the largest error \[s\].
    pub t_worst: f64,
    /// Whether the model has non-conservative terms (else `W ≡ 0`).
    pub non_conservative: bool,
    /// The uncertainty of the work, `U = Σ |S_k − T_k|` over the accepted
    /// steps: the distance of each step's Simpson work from its trapezoidal
    /// one (an estimate of the trapezoid's error, far above Simpson's; zero
    /// without non-conservative terms) \[J\].
    pub quadrature: f64,
    /// The part of `work` done by the closure forces through the
    /// stabilization, `∫ q̇ᵀJᵀλ dt` (zero without closures) \[J\].
    pub closure_work: f64,
    /// The round-off floor at the end: errors below it count as zero (see
    /// the module documentation) \[J\].
    pub floor: f64,
}

pub(crate) struct Watch {
    tolerance: f64,
    /// The full model's buffers (inputs synchronized before each use).
    full: Data,
    /// The conservative model and its buffers (`None`: no non-conservative term).
    conservative: Option<(Model, Data)>,
    /// The model without its closures and its buffers, for the closure
    /// forces' power (`None`: no closures).
    open: Option<(Model, Data)>,
    /// The model's work scale `F L` of the round-off floor \[J\].
    work_scale: f64,
    closure_work: f64,
    /// The closure part of the power at the last accepted step \[W\].
    pc_prev: f64,
    e0: f64,
    vg0: f64,
    /// The last accepted step whose balance was within a tenth of the
    /// bound: a drive's jump after it may be what broke the balance.
    t_fine: f64,
    t_start: f64,
    t_prev: f64,
    p_prev: f64,
    work: f64,
    abs_work: f64,
    quadrature: f64,
    peak: f64,
    balance: EnergyBalance,
    warnings: Vec<String>,
    warned_strain: bool,
    warned_curvature: bool,
    /// The state at the last accepted step, and the midpoint of the step
    /// that follows (buffers reused every step: no allocation per step).
    q_prev: Vec<f64>,
    qd_prev: Vec<f64>,
    q_mid: Vec<f64>,
    qd_mid: Vec<f64>,
}

fn dot(a: &[f64], b: &DVector<f64>) -> f64 {
    a.iter().zip(b.iter()).map(|(x, y)| x * y).sum()
}

/// The model without viscosity, drag, cables and loads (on rods and bodies)
/// and without joint damping and actuators, if it has any of them; joints, bodies and
/// joint springs stay (they are conservative).
fn conservative_model(model: &Model) -> Result<Option<Model>, Error> {
    let has = model.rods().iter().any(|r| {
        let s = &r.spec;
        !s.cables.is_empty()
            || !s.point_loads.is_empty()
            || !s.distributed_loads.is_empty()
            || s.drag
                .is_some_and(|d| d.translational != 0.0 || d.rotational != 0.0)
            || s.properties.material().viscosity() != 0.0
    }) || model.bodies().iter().any(|b| !b.spec.loads.is_empty())
        // Contact forces do work (the penalty stores it, damping and
        // friction dissipate it): the conservative model leaves them out.
        || model.has_contact()
        || model.elements().iter().any(|e| {
            e.attachment.joint.damping.iter().any(|d| *d != 0.0)
                || e.attachment.joint.actuator.is_some()
        });
    if !has {
        return Ok(None);
    }
    let conservative_rod = |spec: &Rod| -> Result<Rod, Error> {
        let mut s = spec.clone();
        s.cables.clear();
        s.point_loads.clear();
        s.distributed_loads.clear();
        s.drag = None;
        let m = s.properties.material();
        let elastic = Material::builder()
            .density(m.density())
            .young(m.young())
            .shear_modulus(m.shear_modulus())
            .viscosity(0.0)
            .build()?;
        s.properties = RodProperties::new(*s.properties.section(), elastic, s.properties.length())?;
        Ok(s)
    };
    if !model.is_articulated() {
        let specs: Vec<Rod> = model
            .rods()
            .iter()
            .map(|r| conservative_rod(&r.spec))
            .collect::<Result<_, Error>>()?;
        return Ok(Some(Model::new(
            specs,
            model.gravity(),
            model.quadrature().len(),
        )?));
    }
    let elements = model
        .elements()
        .iter()
        .map(|e| {
            let mut at = e.attachment.clone();
            at.joint.damping.iter_mut().for_each(|d| *d = 0.0);
            // A joint actuator's force is an input: its work is the
            // non-conservative power's (IS14).
            at.joint.actuator = None;
            Ok(match e.kind {
                ElementKind::Rod(i) => Element::Rod(conservative_rod(&model.rods()[i].spec)?, at),
                ElementKind::Body(i) => {
                    let mut b = model.bodies()[i].spec.clone();
                    b.loads.clear();
                    Element::Body(b, at)
                }
            })
        })
        .collect::<Result<Vec<_>, Error>>()?;
    Ok(Some(
        Model::with_elements(elements, model.gravity(), model.quadrature().len())?
            .with_closures(model.closures().cloned().collect())?,
    ))
}

/// The model with the same elements and contact and no closures (`None`
/// without closures): its inverse dynamics at the constrained `q̈` is
/// `Jᵀλ` — with the contact force on both sides (`M q̈ + b = τ_c + Jᵀλ`),
/// so that the contact's power is counted once, in the non-conservative
/// power, and not again as the closures'.
fn open_model(model: &Model) -> Result<Option<Model>, Error> {
    if !model.has_closures() {
        return Ok(None);
    }
    let elements = model
        .elements()
        .iter()
        .map(|e| match e.kind {
            ElementKind::Rod(i) => Element::Rod(model.rods()[i].spec.clone(), e.attachment.clone()),
            ElementKind::Body(i) => {
                Element::Body(model.bodies()[i].spec.clone(), e.attachment.clone())
            }
        })
        .collect();
    let open = Model::with_elements(elements, model.gravity(), model.quadrature().len())?;
    Ok(Some(if model.has_contact() {
        open.with_contact(model.obstacles().to_vec(), model.contact_settings())?
    } else {
        open
    }))
}

/// The model's work scale `F L` \[J\] (module documentation, "Round-off
/// floor"): weights, loads and the largest cable tensions (`tensions`, the
/// inputs set by a controller, when larger) times the rods' total length,
/// plus the loads' moments.
fn work_scale(model: &Model, tensions: Option<&[f64]>) -> f64 {
    let length: f64 = model.rods().iter().map(|r| r.spec.geometry.length()).sum();
    let g = model.gravity().map_or(0.0, |g| g.norm());
    let (mut force, mut moment) = (0.0, 0.0);
    let mut k = 0;
    for r in model.rods() {
        let s = &r.spec;
        let l = s.geometry.length();
        force += g * s.properties.mass_per_length(0.5 * l) * l;
        for p in &s.point_loads {
            force += p.force.norm();
            moment += p.moment.norm();
        }
        for d in &s.distributed_loads {
            force += d.force.norm() * l;
            moment += d.moment.norm() * l;
        }
        for c in &s.cables {
            let set = tensions.and_then(|t| t.get(k)).copied().unwrap_or(0.0);
            force += c.tension.max().max(set.abs());
            k += 1;
        }
    }
    // A joint actuator's largest force or torque, over the rods' length
    // (a torque's work scale is its moment times a rotation of order 1).
    for e in model.elements() {
        if let Some(a) = &e.attachment.joint.actuator {
            let largest = match &a.force {
                softrod_dynamics::JointForce::Constant(v) => {
                    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
                }
                softrod_dynamics::JointForce::Table { values, .. } => {
                    values.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()))
                }
            };
            moment += largest;
        }
    }
    for b in model.bodies() {
        force += g * b.spec.mass;
        for l in &b.spec.loads {
            force += l.force.norm();
            moment += l.moment.norm();
        }
    }
    force * length + moment
}

/// What can help a run whose balance failed at `t`, having held within a
/// tenth of the bound until `t_fine`: a drive that starts or stops moving
/// abruptly in `[t_fine, t]` is an impulse no step size resolves; otherwise
/// the step, the tolerances or the method. A drive moving at the run's
/// start `t_start` does not jump there: the state starts with its rate.
fn advice(model: &Model, t_start: f64, t_fine: f64, t: f64) -> String {
    for e in model.elements() {
        let Some(p) = &e.attachment.joint.prescribed else {
            continue;
        };
        for (c, curve) in p.curves.iter().enumerate() {
            let Curve::Spline(sp) = curve else {
                continue;
            };
            let (start, end) = sp.span();
            for (at, what) in [(start, "starts"), (end, "stops")] {
                let (_, rate, _) = sp.eval(at);
                if at > t_start && (t_fine..=t).contains(&at) && rate.abs() > 1e-12 {
                    return format!(
                        "the drive of {:?} (coordinate {c}) {what} abruptly at t = {at:e} s \
                         (rate {rate:e}): an impulse, which no step size resolves; give the \
                         drive a zero rate at its ends",
                        e.name
                    );
                }
            }
        }
    }
    "reduce dt or the tolerances, or use a stiff integrator".to_owned()
}

impl Watch {
    /// A watch of runs of `model` (whose inputs are in `data`) with
    /// `tolerance` on the relative balance error.
    pub(crate) fn new(model: &Model, data: &Data, tolerance: f64) -> Result<Self, Error> {
        let conservative = conservative_model(model)?.map(|m| {
            let d = Data::new(&m);
            (m, d)
        });
        let open = open_model(model)?.map(|m| {
            let d = Data::new(&m);
            (m, d)
        });
        Ok(Self {
            tolerance,
            full: data.clone(),
            conservative,
            open,
            work_scale: work_scale(model, data.cable_tensions()),
            closure_work: 0.0,
            pc_prev: 0.0,
            e0: 0.0,
            vg0: 0.0,
            t_fine: 0.0,
            t_start: 0.0,
            t_prev: 0.0,
            p_prev: 0.0,
            work: 0.0,
            abs_work: 0.0,
            quadrature: 0.0,
            peak: 0.0,
            balance: EnergyBalance::default(),
            warnings: Vec::new(),
            warned_strain: false,
            warned_curvature: false,
            q_prev: vec![0.0; model.n_dof()],
            qd_prev: vec![0.0; model.n_dof()],
            q_mid: vec![0.0; model.n_dof()],
            qd_mid: vec![0.0; model.n_dof()],
        })
    }

    /// Remembers `(q, q̇)` as the start of the next step.
    fn keep_state(&mut self, q: &[f64], qd: &[f64]) {
        self.q_prev.copy_from_slice(q);
        self.qd_prev.copy_from_slice(qd);
    }

    /// The power (with the closures' part) at the middle of the step from
    /// the last accepted state to `(t, q, q̇)` of length `h`, at the state
    /// of the cubic Hermite interpolant through the step's ends:
    /// `q_m = (q₀ + q₁)/2 + h (q̇₀ − q̇₁)/8`,
    /// `q̇_m = 3 (q₁ − q₀)/(2h) − (q̇₀ + q̇₁)/4`. Returns `(P_m, P_c,m)`.
    fn midpoint_power(
        &mut self,
        model: &Model,
        t: f64,
        h: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<(f64, f64), Error> {
        let (mut qm, mut qdm) = (
            std::mem::take(&mut self.q_mid),
            std::mem::take(&mut self.qd_mid),
        );
        let ends = self.q_prev.iter().zip(&self.qd_prev).zip(q.iter().zip(qd));
        for ((m, dm), ((&q0, &v0), (&q1, &v1))) in qm.iter_mut().zip(qdm.iter_mut()).zip(ends) {
            *m = 0.5 * (q0 + q1) + 0.125 * h * (v0 - v1);
            *dm = 1.5 * (q1 - q0) / h - 0.25 * (v0 + v1);
        }
        let tm = t - 0.5 * h;
        let result = self.closure_power(model, tm, &qm, &qdm).and_then(|pc| {
            let p = self.power(model, tm, &qm, &qdm)?;
            Ok((p + pc, pc))
        });
        (self.q_mid, self.qd_mid) = (qm, qdm);
        result
    }

    fn sync_inputs(&mut self, model: &Model, data: &Data) -> Result<(), DynamicsError> {
        // The friction forces whose power is counted are the run's: with
        // its anchors, not a fresh workspace's (which would see every
        // sticking contact as new and leave its dissipation out).
        self.full.copy_friction_state_from(data);
        if let Some((_, od)) = &mut self.open {
            od.copy_friction_state_from(data);
        }
        if self.full.joint_forces() != data.joint_forces() {
            self.full.set_joint_forces(model, data.joint_forces())?;
            if let Some((om, od)) = &mut self.open {
                od.set_joint_forces(om, data.joint_forces())?;
            }
        }
        if self.full.cable_tensions() != data.cable_tensions() {
            self.full.set_cable_tensions(model, data.cable_tensions())?;
            if let Some((om, od)) = &mut self.open {
                od.set_cable_tensions(om, data.cable_tensions())?;
            }
            self.work_scale = self
                .work_scale
                .max(work_scale(model, data.cable_tensions()));
        }
        Ok(())
    }

    /// The power of the closure forces `P_c = q̇ᵀJᵀλ` \[W\] (zero without
    /// closures): the open tree's inverse dynamics at the constrained `q̈`
    /// is `Jᵀλ` on the free coordinates, and the drives' open forces less
    /// their constrained ones are the closures' share `J_pᵀλ` (D60).
    fn closure_power(
        &mut self,
        model: &Model,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<f64, Error> {
        let Some((om, od)) = &mut self.open else {
            return Ok(0.0);
        };
        forward_dynamics(model, &mut self.full, t, q, qd, None)?;
        let tau = inverse_dynamics(om, od, t, q, qd, self.full.qdd.as_slice())?;
        let mut p = dot(qd, tau);
        if model.n_prescribed() > 0 {
            p += od.prescribed_qd.dot(&od.prescribed_force)
                - self.full.prescribed_qd.dot(&self.full.prescribed_force);
        }
        Ok(p)
    }

    /// `P_nc = q̇ᵀ(b_c − b)` at `(t, q, q̇)` \[W\], plus, with prescribed
    /// joints (D59), the power `F_p·q̇_p` of the forces that drive them and
    /// the power the non-conservative terms exert through them,
    /// `q̇_pᵀ(F_p,c − F_p)` at `q̈ = 0` (the inertial parts cancel as in `b`).
    fn power(&mut self, model: &Model, t: f64, q: &[f64], qd: &[f64]) -> Result<f64, Error> {
        let driven = model.n_prescribed() > 0;
        let mut p = 0.0;
        if driven {
            forward_dynamics(model, &mut self.full, t, q, qd, None)?;
            p += self.full.prescribed_force.dot(&self.full.prescribed_qd);
        }
        let Some((cm, cd)) = &mut self.conservative else {
            return Ok(p);
        };
        let full = dot(qd, bias_force(model, &mut self.full, t, q, qd)?);
        let cons = dot(qd, bias_force(cm, cd, t, q, qd)?);
        if driven {
            p += cd.prescribed_force.dot(&cd.prescribed_qd)
                - self.full.prescribed_force.dot(&self.full.prescribed_qd);
        }
        Ok(p + cons - full)
    }

    fn energies(
        &mut self,
        model: &Model,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<Energies, Error> {
        model.set_time(&mut self.full, t);
        Ok(energies(model, &mut self.full, q, qd)?)
    }

    /// The initial state.
    pub(crate) fn start(
        &mut self,
        model: &Model,
        data: &Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<(), Error> {
        self.sync_inputs(model, data)?;
        let e = self.energies(model, t, q, qd)?;
        self.e0 = e.total();
        self.vg0 = e.gravitational;
        self.peak = e.kinetic + e.elastic;
        self.t_fine = t;
        self.t_start = t;
        self.t_prev = t;
        self.pc_prev = self.closure_power(model, t, q, qd)?;
        self.p_prev = self.power(model, t, q, qd)? + self.pc_prev;
        self.keep_state(q, qd);
        self.balance = EnergyBalance {
            initial: self.e0,
            scale: self.peak,
            t_worst: t,
            non_conservative: self.conservative.is_some()
                || model.n_prescribed() > 0
                || self.open.is_some(),
            ..EnergyBalance::default()
        };
        self.check_strains(model, t, q)
    }

    /// The inputs changed at `t` (zero-order hold): the power from `t` on
    /// is the new one.
    pub(crate) fn inputs_changed(
        &mut self,
        model: &Model,
        data: &Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<(), Error> {
        self.sync_inputs(model, data)?;
        self.pc_prev = self.closure_power(model, t, q, qd)?;
        self.p_prev = self.power(model, t, q, qd)? + self.pc_prev;
        self.keep_state(q, qd);
        Ok(())
    }

    /// An accepted step ending at `(t, q, q̇)`: the balance and the strains
    /// there; an error when the balance is violated or a stretch is not
    /// positive.
    pub(crate) fn step(
        &mut self,
        model: &Model,
        data: &Data,
        t: f64,
        q: &[f64],
        qd: &[f64],
    ) -> Result<(), Error> {
        // The balance first: after an unstable step it names the cause
        // better than the folded piece that follows from it.
        self.sync_inputs(model, data)?;
        let pc = self.closure_power(model, t, q, qd)?;
        let p = self.power(model, t, q, qd)? + pc;
        let h = t - self.t_prev;
        // Simpson's rule on the step (the trapezoid where it has no length).
        let (pm, pcm) = if h > 0.0 {
            self.midpoint_power(model, t, h, q, qd)?
        } else {
            (0.5 * (self.p_prev + p), 0.5 * (self.pc_prev + pc))
        };
        let simpson = h / 6.0 * (self.p_prev + 4.0 * pm + p);
        let trapezoid = 0.5 * h * (self.p_prev + p);
        self.work += simpson;
        self.closure_work += h / 6.0 * (self.pc_prev + 4.0 * pcm + pc);
        self.pc_prev = pc;
        self.abs_work += h / 6.0 * (self.p_prev.abs() + 4.0 * pm.abs() + p.abs());
        self.quadrature += (simpson - trapezoid).abs();
        self.t_prev = t;
        self.p_prev = p;
        self.keep_state(q, qd);
        let e = self.energies(model, t, q, qd)?;
        self.peak = self
            .peak
            .max(e.kinetic + e.elastic + (e.gravitational - self.vg0).abs());
        let scale = self.peak + self.abs_work;
        let change = e.total() - self.e0;
        let error = (change - self.work).abs();
        let roundoff = 1e3
            * f64::EPSILON
            * (e.kinetic
                + e.elastic
                + e.gravitational.abs()
                + self.e0.abs()
                + self.abs_work
                + self.work_scale);
        // The failure test compares with the scale so far: a run that blows
        // up is stopped where it does.
        let error = if error <= roundoff { 0.0 } else { error };
        // What the trapezoidal work cannot resolve is not held against the
        // run (a tension ramp from zero: P ∝ t³ is overestimated 2× on the
        // first step, when the scale is 1e-15 J).
        let beyond = (error - self.quadrature).max(0.0);
        let relative = if !error.is_finite() || !scale.is_finite() {
            f64::INFINITY
        } else if beyond == 0.0 {
            0.0
        } else {
            beyond / scale
        };
        let b = &mut self.balance;
        b.change = change;
        b.work = self.work;
        b.scale = scale;
        b.quadrature = self.quadrature;
        b.closure_work = self.closure_work;
        b.floor = roundoff;
        if error > b.error || !error.is_finite() {
            b.error = error;
            b.t_worst = t;
        }
        b.relative = if b.error == 0.0 { 0.0 } else { b.error / scale };
        if relative > self.tolerance {
            b.relative = relative;
            return Err(Error::EnergyBalance {
                t,
                relative,
                tolerance: self.tolerance,
                balance: Box::new(*b),
                advice: advice(model, self.t_start, self.t_fine, t),
            });
        }
        if relative <= 0.1 * self.tolerance {
            self.t_fine = t;
        }
        self.check_strains(model, t, q)
    }

    /// The rules of `softrod_mechanics::validity` at `(t, q)`, the ones a
    /// scene check applies to the initial state: a folded piece (stretch
    /// not positive) is an error; strains beyond the model's validity and
    /// curvature radii below the section's half size warn once each.
    fn check_strains(&mut self, model: &Model, t: f64, q: &[f64]) -> Result<(), Error> {
        for r in model.rods() {
            let v = strain_validity(&r.spec.geometry, r.spec.properties.section(), &q[r.dofs()]);
            if let Some(f) = v.folded {
                let StrainProblem::Folded { stretch } = f.problem else {
                    unreachable!("a folded finding")
                };
                return Err(Error::Stretch {
                    t,
                    rod: r.spec.name.clone(),
                    piece: f.piece,
                    stretch,
                });
            }
            for (found, warned) in [
                (v.strain, &mut self.warned_strain),
                (v.curvature, &mut self.warned_curvature),
            ] {
                if let Some(f) = found
                    && !*warned
                {
                    *warned = true;
                    self.warnings.push(format!(
                        "{} at t = {t:e} s: rod {:?} {f}",
                        f.headline(),
                        r.spec.name
                    ));
                }
            }
        }
        Ok(())
    }

    /// The balance and the warnings of the run.
    pub(crate) fn finish(mut self) -> (EnergyBalance, Vec<String>) {
        let b = self.balance;
        if b.relative > 0.1 * self.tolerance {
            self.warnings.insert(
                0,
                format!(
                    "energy balance drifts: relative error {:.3e} at t = {:e} s (error {:.3e} J, \
                     scale {:.3e} J); the run fails beyond energy_tolerance = {}",
                    b.relative, b.t_worst, b.error, b.scale, self.tolerance
                ),
            );
        }
        (b, self.warnings)
    }
}
