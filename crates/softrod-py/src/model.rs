//! Building rods in Python: sections, materials, cables, loads and rods,
//! each validated when it is constructed, and the model they make.
//!
//! Until the facade has builders these wrap the lower crates' constructors
//! (`softrod_kinematics::RodGeometry::with_lengths`, `softrod_mechanics::RodProperties`,
//! `softrod_dynamics::Model::new`) with the defaults of the scene format
//! (docs/scene-format.md): strains in canonical order, straight rest shape,
//! base at the origin, no viscosity, no drag.

use nalgebra::{Matrix3, Vector3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
use softrod::dynamics::{self as dynamics, Model};
use softrod::kinematics::{Basis, RodGeometry, Strain};
use softrod::lie::{Pose, Vec6};
use softrod::mechanics as mech;

use crate::convert::{mat3, vec3, vector};
use crate::errors::input;

/// A cross-section. Construct one of its kinds: [`Circle`], [`Tube`],
/// [`Rectangle`], [`TaperedCircle`].
#[pyclass(subclass, frozen, module = "softrod")]
pub struct Section {
    pub(crate) inner: mech::Section,
}

fn section<T: pyo3::PyClass<BaseType = Section>>(
    name: &str,
    s: mech::Section,
    kind: T,
) -> PyResult<PyClassInitializer<T>> {
    s.validate().map_err(|e| input(format!("{name}: {e}")))?;
    Ok(PyClassInitializer::from(Section { inner: s }).add_subclass(kind))
}

#[pymethods]
impl Section {
    /// The shape: "circle", "tube", "rectangle" or "tapered_circle".
    #[getter]
    fn shape(&self) -> &'static str {
        match self.inner {
            mech::Section::Circle { .. } => "circle",
            mech::Section::Tube { .. } => "tube",
            mech::Section::Rectangle { .. } => "rectangle",
            mech::Section::TaperedCircle { .. } => "tapered_circle",
        }
    }

    /// Area `A` [m²] at the base (`s = 0`).
    #[getter]
    fn area(&self) -> f64 {
        self.inner.properties(0.0).area
    }

    /// Second moments `(Jx, Jy, Jz)` [m⁴] at the base; `Jx = Jy + Jz`.
    #[getter]
    fn second_moments(&self) -> (f64, f64, f64) {
        let p = self.inner.properties(0.0);
        (p.jx, p.jy, p.jz)
    }

    fn __repr__(&self) -> String {
        match self.inner {
            mech::Section::Circle { radius } => format!("Circle(radius={radius:?})"),
            mech::Section::Tube {
                radius,
                inner_radius,
            } => format!("Tube(radius={radius:?}, inner_radius={inner_radius:?})"),
            mech::Section::Rectangle { width, height } => {
                format!("Rectangle(width={width:?}, height={height:?})")
            }
            mech::Section::TaperedCircle {
                radius_base,
                radius_tip,
            } => format!("TaperedCircle(radius_base={radius_base:?}, radius_tip={radius_tip:?})"),
        }
    }
}

/// Solid circle of radius `radius` [m].
#[pyclass(extends = Section, frozen, module = "softrod")]
pub struct Circle;

#[pymethods]
impl Circle {
    #[new]
    fn new(radius: f64) -> PyResult<PyClassInitializer<Self>> {
        section("Circle", mech::Section::Circle { radius }, Circle)
    }
}

/// Hollow circle: outer `radius`, `inner_radius` in [0, radius) [m].
#[pyclass(extends = Section, frozen, module = "softrod")]
pub struct Tube;

#[pymethods]
impl Tube {
    #[new]
    fn new(radius: f64, inner_radius: f64) -> PyResult<PyClassInitializer<Self>> {
        section(
            "Tube",
            mech::Section::Tube {
                radius,
                inner_radius,
            },
            Tube,
        )
    }
}

/// Solid rectangle: `width` along local y, `height` along local z [m].
#[pyclass(extends = Section, frozen, module = "softrod")]
pub struct Rectangle;

#[pymethods]
impl Rectangle {
    #[new]
    fn new(width: f64, height: f64) -> PyResult<PyClassInitializer<Self>> {
        section(
            "Rectangle",
            mech::Section::Rectangle { width, height },
            Rectangle,
        )
    }
}

/// Solid circle whose radius varies linearly from `radius_base` (s = 0)
/// to `radius_tip` (s = L) [m].
#[pyclass(extends = Section, frozen, module = "softrod")]
pub struct TaperedCircle;

#[pymethods]
impl TaperedCircle {
    #[new]
    fn new(radius_base: f64, radius_tip: f64) -> PyResult<PyClassInitializer<Self>> {
        section(
            "TaperedCircle",
            mech::Section::TaperedCircle {
                radius_base,
                radius_tip,
            },
            TaperedCircle,
        )
    }
}

/// Linear elastic, Kelvin–Voigt viscous material (SI).
///
/// Give `density` [kg/m³], `young` (Young's modulus E) [Pa] and exactly one
/// of `poisson` (ν in (−1, 0.5], then G = E / (2(1 + ν))) or
/// `shear_modulus` (G) [Pa]; `viscosity` μ [Pa·s] is the Kelvin–Voigt shear
/// viscosity (0: undamped; the damping matrix is D = K with E, G replaced by
/// 3μ, μ, as the scene format's `viscosity`).
#[pyclass(frozen, module = "softrod")]
pub struct Material {
    pub(crate) inner: mech::Material,
}

#[pymethods]
impl Material {
    #[new]
    #[pyo3(signature = (density, young, poisson = None, shear_modulus = None, viscosity = 0.0))]
    fn new(
        density: f64,
        young: f64,
        poisson: Option<f64>,
        shear_modulus: Option<f64>,
        viscosity: f64,
    ) -> PyResult<Self> {
        let bad = |e: mech::MechanicsError| input(format!("Material: {e}"));
        let b = mech::Material::builder()
            .density(density)
            .young(young)
            .viscosity(viscosity);
        let inner = match (poisson, shear_modulus) {
            (Some(nu), None) => b.poisson(nu),
            (None, Some(g)) => b.shear_modulus(g),
            _ => {
                return Err(input(
                    "Material: give exactly one of poisson or shear_modulus",
                ));
            }
        }
        .build()
        .map_err(bad)?;
        Ok(Self { inner })
    }

    /// Density ρ [kg/m³].
    #[getter]
    fn density(&self) -> f64 {
        self.inner.density()
    }

    /// Young's modulus E [Pa].
    #[getter]
    fn young(&self) -> f64 {
        self.inner.young()
    }

    /// Shear modulus G [Pa].
    #[getter]
    fn shear_modulus(&self) -> f64 {
        self.inner.shear_modulus()
    }

    /// Poisson's ratio implied by E and G, ν = E/(2G) − 1.
    #[getter]
    fn poisson(&self) -> f64 {
        self.inner.poisson()
    }

    /// Kelvin–Voigt shear viscosity μ [Pa·s].
    #[getter]
    fn viscosity(&self) -> f64 {
        self.inner.viscosity()
    }

    fn __repr__(&self) -> String {
        let m = &self.inner;
        format!(
            "Material(density={:?}, young={:?}, shear_modulus={:?}, viscosity={:?})",
            m.density(),
            m.young(),
            m.shear_modulus(),
            m.viscosity()
        )
    }
}

/// A cable (tendon) routed through the cross-section and anchored at `to`.
///
/// `offset=(y, z)` [m]: constant position in the section; or
/// `path=[(s, y, z), ...]`: piecewise linear along s. `tension` [N] ≥ 0:
/// a constant, or `(times, values)` piecewise linear in time (held beyond
/// the ends). `from_`, `to` [m]: the span along the rod (default: the whole
/// rod). `friction`: Coulomb coefficient along the cable's channel (a
/// pulled cable's tension decays as `T e^{−μφ}`, docs/theory.md D15f).
/// Cable-tension inputs `u` of `Simulation.forward_dynamics`,
/// `simulate(controller=…)` and `step` replace the tension given here.
#[pyclass(frozen, module = "softrod")]
pub struct Cable {
    pub(crate) routing: mech::Routing,
    pub(crate) from: f64,
    pub(crate) to: Option<f64>,
    pub(crate) tension: mech::Tension,
    pub(crate) friction: f64,
}

#[pymethods]
impl Cable {
    #[new]
    #[pyo3(signature = (offset = None, *, path = None, tension = None, from_ = 0.0, to = None, friction = 0.0))]
    fn new(
        offset: Option<&Bound<'_, PyAny>>,
        path: Option<&Bound<'_, PyAny>>,
        tension: Option<&Bound<'_, PyAny>>,
        from_: f64,
        to: Option<f64>,
        friction: f64,
    ) -> PyResult<Self> {
        let routing = match (offset, path) {
            (Some(o), None) => {
                let a = vector(o, "Cable(offset)", 2)?;
                let s = a.slice();
                mech::Routing::Offset { y: s[0], z: s[1] }
            }
            (None, Some(p)) => {
                let a = crate::convert::array(p, "Cable(path)")?;
                let shape = a.shape().to_vec();
                if shape.len() != 2 || shape[1] != 3 || shape[0] == 0 {
                    return Err(input(format!(
                        "Cable(path) must have shape (n, 3) with n >= 1 (rows s, y, z), got {shape:?}"
                    )));
                }
                mech::Routing::Path(a.slice().chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
            }
            _ => return Err(input("Cable: give exactly one of offset or path")),
        };
        let tension = match tension {
            None => mech::Tension::Constant(0.0),
            Some(t) => {
                if let Ok(v) = t.extract::<f64>() {
                    mech::Tension::Constant(v)
                } else {
                    let (times, values): (Bound<'_, PyAny>, Bound<'_, PyAny>) =
                        t.extract().map_err(|_| {
                            input("Cable(tension) must be a number or a pair (times, values)")
                        })?;
                    let times = crate::convert::array(&times, "Cable(tension) times")?;
                    let n = times.slice().len();
                    let values = vector(&values, "Cable(tension) values", n)?;
                    mech::Tension::Table {
                        times: times.slice().to_vec(),
                        values: values.slice().to_vec(),
                    }
                }
            }
        };
        // Checked against an unbounded rod here, against the rod's length
        // when the Rod is built; a path without `to` spans to its last point
        // until the rod's length is known.
        let end = to.unwrap_or(match &routing {
            mech::Routing::Path(p) => p.last().map_or(f64::MAX, |r| r[0]),
            _ => f64::MAX,
        });
        let cable = Self {
            routing,
            from: from_,
            to,
            tension,
            friction,
        };
        cable
            .mech(end)
            .validate(f64::MAX)
            .map_err(|e| input(format!("Cable: {e}")))?;
        Ok(cable)
    }

    fn __repr__(&self) -> String {
        let routing = match &self.routing {
            mech::Routing::Offset { y, z } => format!("offset=({y:?}, {z:?})"),
            mech::Routing::Path(p) => format!("path=<{} points>", p.len()),
        };
        let tension = match &self.tension {
            mech::Tension::Constant(v) => format!("{v:?}"),
            mech::Tension::Table { times, .. } => format!("<table of {} points>", times.len()),
        };
        let to = self.to.map_or("None".into(), |v| format!("{v:?}"));
        format!(
            "Cable({routing}, tension={tension}, from_={:?}, to={to}, friction={:?})",
            self.from, self.friction
        )
    }
}

impl Cable {
    /// The mechanics cable on a rod of length `length` (span end defaulted).
    pub(crate) fn mech(&self, length: f64) -> mech::Cable {
        mech::Cable::new(self.routing.clone(), self.tension.clone())
            .between(self.from, self.to.unwrap_or(length))
            .with_friction(self.friction)
    }
}

/// A point load at abscissa `s` [m]: `force` [N] and `moment` [N·m], with
/// components in `frame`: "world" (a dead load, fixed direction) or "body"
/// (a follower load, turning with the section).
#[pyclass(frozen, module = "softrod")]
pub struct PointLoad {
    pub(crate) inner: mech::PointLoad,
}

#[pymethods]
impl PointLoad {
    #[new]
    #[pyo3(signature = (s, force, moment = None, frame = "world"))]
    fn new(
        s: f64,
        force: &Bound<'_, PyAny>,
        moment: Option<&Bound<'_, PyAny>>,
        frame: &str,
    ) -> PyResult<Self> {
        let force = Vector3::from(vec3(force, "PointLoad(force)")?);
        let moment = match moment {
            Some(m) => Vector3::from(vec3(m, "PointLoad(moment)")?),
            None => Vector3::zeros(),
        };
        let frame = match frame {
            "world" => mech::LoadFrame::World,
            "body" => mech::LoadFrame::Body,
            other => {
                return Err(input(format!(
                    "PointLoad(frame) must be \"world\" or \"body\", got {other:?}"
                )));
            }
        };
        let inner = mech::PointLoad {
            s,
            force,
            moment,
            frame,
        };
        inner
            .validate(f64::MAX)
            .map_err(|e| input(format!("PointLoad: {e}")))?;
        Ok(Self { inner })
    }

    fn __repr__(&self) -> String {
        let l = &self.inner;
        let frame = match l.frame {
            mech::LoadFrame::World => "world",
            mech::LoadFrame::Body => "body",
        };
        format!(
            "PointLoad(s={:?}, force={:?}, moment={:?}, frame={frame:?})",
            l.s,
            l.force.as_slice(),
            l.moment.as_slice()
        )
    }
}

/// One rod: geometry, strain basis, section, material, and what acts on it.
///
/// `pieces`: the number of equal pieces, or the list of piece lengths [m]
/// (summing to `length`). `strains`: "all" or a list of the names "kx",
/// "ky", "kz" (torsion, bendings), "qx", "qy", "qz" (stretch, shears); the
/// coordinates of each piece are the selected strains in that canonical
/// order, whatever order the list gives. `base`: the clamped base pose as a
/// 4×4 homogeneous transform (default identity: the rod along world x).
/// `rest_strain`: the stress-free strain (kx, ky, kz, qx, qy, qz), default
/// straight (0, 0, 0, 1, 0, 0). `drag`: (translational [N·s/m²],
/// rotational [N·m·s]) linear drag per unit length. `contact_radius` [m]:
/// the radius of the rod's contact surface (default: from the section,
/// scene key `contact_radius`).
///
/// On a robot (scene keys of the same names, docs/scene-format.md):
/// `parent` the name of a rod or body it hangs from ("world" default),
/// `at` [m] the arc length on a parent rod (default its tip), `joint` the
/// scene's joint table (`softrod.Joint(...)` or a dict, default fixed);
/// `base` is then relative to the attachment frame.
#[pyclass(frozen, module = "softrod")]
pub struct Rod {
    pub(crate) spec: dynamics::Rod,
    pub(crate) named: bool,
    /// The scene tables this rod stands for (`Simulation(…, bodies=, …)`
    /// builds through the scene).
    pub(crate) tables: crate::scene_dict::RodTables,
}

fn piece_lengths(length: f64, pieces: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(n) = pieces.extract::<i64>() {
        if n < 1 {
            return Err(input(format!("Rod(pieces) must be at least 1, got {n}")));
        }
        return Ok(vec![length / n as f64; n as usize]);
    }
    let a = crate::convert::array(pieces, "Rod(pieces)")?;
    if a.shape().len() != 1 || a.shape()[0] == 0 {
        return Err(input(format!(
            "Rod(pieces) must be a count or a non-empty list of lengths, got shape {:?}",
            a.shape()
        )));
    }
    let sum: f64 = a.slice().iter().sum();
    if (sum - length).abs() > 1e-9 * length {
        return Err(input(format!(
            "Rod(pieces): the piece lengths sum to {sum}, not the rod length {length}"
        )));
    }
    Ok(a.slice().to_vec())
}

fn strain_indices(strains: &Bound<'_, PyAny>) -> PyResult<Vec<usize>> {
    if let Ok(s) = strains.cast::<PyString>() {
        let s = s.to_str()?;
        if s == "all" {
            return Ok((0..6).collect());
        }
        return Err(input(format!(
            "Rod(strains) must be \"all\" or a list of strain names, got {s:?}"
        )));
    }
    let names: Vec<String> = strains
        .extract()
        .map_err(|_| input("Rod(strains) must be \"all\" or a list of strain names"))?;
    let mut mask = [false; 6];
    for n in &names {
        let s: Strain = n.parse().map_err(|_| {
            input(format!(
                "Rod(strains): unknown strain {n:?} (valid: kx, ky, kz, qx, qy, qz)"
            ))
        })?;
        if mask[s as usize] {
            return Err(input(format!("Rod(strains): {n:?} is listed twice")));
        }
        mask[s as usize] = true;
    }
    if names.is_empty() {
        return Err(input("Rod(strains) must select at least one strain"));
    }
    Ok((0..6).filter(|&i| mask[i]).collect())
}

#[pymethods]
impl Rod {
    #[new]
    #[pyo3(signature = (length, pieces, strains = None, *, section, material, name = None,
                        base = None, rest_strain = None, drag = None, cables = None, loads = None,
                        contact_radius = None, parent = None, at = None, joint = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        length: f64,
        pieces: &Bound<'_, PyAny>,
        strains: Option<&Bound<'_, PyAny>>,
        section: PyRef<'_, Section>,
        material: PyRef<'_, Material>,
        name: Option<String>,
        base: Option<&Bound<'_, PyAny>>,
        rest_strain: Option<&Bound<'_, PyAny>>,
        drag: Option<(f64, f64)>,
        cables: Option<&Bound<'_, PyList>>,
        loads: Option<&Bound<'_, PyList>>,
        contact_radius: Option<f64>,
        parent: Option<String>,
        at: Option<f64>,
        joint: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        if !(length.is_finite() && length > 0.0) {
            return Err(input(format!(
                "Rod(length) must be positive and finite, got {length}"
            )));
        }
        let lengths = piece_lengths(length, pieces)?;
        let idx = match strains {
            Some(s) => strain_indices(s)?,
            None => (0..6).collect(),
        };
        let basis = Basis::from_indices(&idx).map_err(|e| input(format!("Rod(strains): {e}")))?;
        let rest = match rest_strain {
            Some(r) => Vec6::from_row_slice(vector(r, "Rod(rest_strain)", 6)?.slice()),
            None => softrod::kinematics::straight(),
        };
        let base = match base {
            Some(b) => pose_checked(b)?,
            None => Pose::identity(),
        };
        let rod = RodGeometry::with_lengths(&lengths, basis, rest, base)
            .map_err(|e| input(format!("Rod: {e}")))?;
        let body = mech::RodProperties::new(section.inner, material.inner, rod.length())
            .map_err(|e| input(format!("Rod: {e}")))?;
        let mut spec = dynamics::Rod::new(name.clone().unwrap_or_default(), rod, body);
        if let Some((translational, rotational)) = drag {
            let d = mech::Drag {
                translational,
                rotational,
            };
            d.validate().map_err(|e| input(format!("Rod(drag): {e}")))?;
            if translational != 0.0 || rotational != 0.0 {
                spec.drag = Some(d);
            }
        }
        if let Some(list) = cables {
            for (i, c) in list.iter().enumerate() {
                let c = c
                    .cast::<Cable>()
                    .map_err(|_| input(format!("Rod(cables[{i}]) is not a softrod.Cable")))?;
                let cable = c.get().mech(length);
                cable
                    .validate(length)
                    .map_err(|e| input(format!("Rod(cables[{i}]): {e}")))?;
                spec.cables.push(cable);
            }
        }
        if let Some(list) = loads {
            for (i, l) in list.iter().enumerate() {
                let l = l
                    .cast::<PointLoad>()
                    .map_err(|_| input(format!("Rod(loads[{i}]) is not a softrod.PointLoad")))?;
                let load = l.get().inner;
                load.validate(length)
                    .map_err(|e| input(format!("Rod(loads[{i}]): {e}")))?;
                spec.point_loads.push(load);
            }
        }
        if let Some(r) = contact_radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(input(format!(
                    "Rod(contact_radius) must be positive and finite, got {r}"
                )));
            }
            spec.contact_radius = Some(r);
        }
        let tables = crate::scene_dict::rod_tables(
            length,
            &spec,
            pieces.extract::<i64>().ok(),
            strains.is_some().then(|| idx.clone()),
            rest_strain.is_some(),
            cables,
            (parent, at, joint),
        )?;
        Ok(Self {
            spec,
            named: name.is_some(),
            tables,
        })
    }

    /// The rod's name ("" until a Simulation names it rod0, rod1, … by position).
    #[getter]
    fn name(&self) -> &str {
        &self.spec.name
    }

    /// Unstretched length L [m].
    #[getter]
    fn length(&self) -> f64 {
        self.spec.geometry.length()
    }

    /// Number of pieces N.
    #[getter]
    fn n_pieces(&self) -> usize {
        self.spec.geometry.n_pieces()
    }

    /// Number of coordinates of this rod (pieces × selected strains).
    #[getter]
    fn n_dof(&self) -> usize {
        self.spec.geometry.n_dof()
    }

    /// Number of cables.
    #[getter]
    fn n_cables(&self) -> usize {
        self.spec.cables.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Rod(name={:?}, length={:?}, pieces={}, n_dof={}, cables={}, loads={})",
            self.spec.name,
            self.spec.geometry.length(),
            self.spec.geometry.n_pieces(),
            self.spec.geometry.n_dof(),
            self.spec.cables.len(),
            self.spec.point_loads.len()
        )
    }
}

/// A base pose from a 4×4 transform, or a dict {"position", "rotation"};
/// the rotation must be orthonormal with determinant +1 (to 1e-6, as the
/// scene format checks).
fn pose_checked(b: &Bound<'_, PyAny>) -> PyResult<Pose> {
    let g = if let Ok(d) = b.cast::<PyDict>() {
        let p = match d.get_item("position")? {
            Some(p) => Vector3::from(vec3(&p, "Rod(base) position")?),
            None => Vector3::zeros(),
        };
        let r = match d.get_item("rotation")? {
            Some(r) => mat3(&r, "Rod(base) rotation")?,
            None => Matrix3::identity(),
        };
        Pose::new(r, p)
    } else {
        crate::convert::pose_from(b, "Rod(base)")?
    };
    let r = g.rotation;
    let err = (r.transpose() * r - Matrix3::identity()).abs().max();
    if !(err <= 1e-6 && (r.determinant() - 1.0).abs() <= 1e-6) {
        return Err(input(format!(
            "Rod(base): the rotation must be orthonormal with determinant +1 \
             (|RᵀR − I| = {err:.3e}, det = {:.6})",
            r.determinant()
        )));
    }
    Ok(g)
}

/// The model of `rods` (named rod0, rod1, … where no name was given) under
/// `gravity` with `quadrature` Gauss points per piece.
pub fn build_model(
    rods: &[PyRef<'_, Rod>],
    gravity: Option<[f64; 3]>,
    quadrature: usize,
) -> PyResult<Model> {
    let mut specs = Vec::with_capacity(rods.len());
    for (i, r) in rods.iter().enumerate() {
        let mut spec = r.spec.clone();
        if !r.named {
            spec.name = format!("rod{i}");
        }
        if specs.iter().any(|s: &dynamics::Rod| s.name == spec.name) {
            return Err(input(format!(
                "Simulation(rods): two rods are named {:?}",
                spec.name
            )));
        }
        specs.push(spec);
    }
    if specs.is_empty() {
        return Err(input("Simulation(rods) needs at least one rod"));
    }
    Model::new(specs, gravity.map(Vector3::from), quadrature)
        .map_err(|e| input(format!("Simulation: {e}")))
}

/// The facade's simulation of Python-built `rods` (see
/// `softrod.Simulation(rods, gravity, quadrature=)`), sampling every
/// thousandth of a run.
pub fn simulation_of(
    rods: &Bound<'_, PyList>,
    gravity: Option<&Bound<'_, PyAny>>,
    quadrature: usize,
) -> PyResult<softrod::Simulation> {
    let mut refs = Vec::with_capacity(rods.len());
    for (i, r) in rods.iter().enumerate() {
        let r = r
            .cast_into::<Rod>()
            .map_err(|_| input(format!("Simulation(rods[{i}]) is not a softrod.Rod")))?;
        refs.push(r.borrow());
    }
    let g = match gravity {
        Some(g) => Some(crate::convert::vec3(g, "gravity")?),
        None => None,
    };
    if quadrature == 0 {
        return Err(input("quadrature must be at least 1 Gauss point per piece"));
    }
    let model = build_model(&refs, g, quadrature)?;
    let mut sim = softrod::Simulation::new(model);
    // Samples every thousandth of the run, whatever its length (a scene's
    // [run] default is a fixed spacing).
    sim.set_settings(softrod::Settings {
        output_every: None,
        ..sim.settings().clone()
    })
    .map_err(crate::errors::to_py)?;
    Ok(sim)
}
