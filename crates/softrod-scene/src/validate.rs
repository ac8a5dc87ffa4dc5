//! From raw TOML structs to a validated [`Scene`]: ranges, consistency,
//! defaults, warnings. Every check names its key path.

use std::f64::consts::PI;
use std::fmt::Display;

use crate::actuation::{Cable, Load, LoadFrame, Routing, Tension};
use crate::error::{Location, SceneError, Warning};
use crate::locate::{SpanMap, join, map_toml_error};
use crate::raw::{
    RawCable, RawDrag, RawInitial, RawLoad, RawMaterial, RawReference, RawRod, RawRun, RawScene,
    RawSection,
};
use crate::rod::{Drag, Material, Pose, Rod, STRAIN_NAMES, Section, StrainSelection};
use crate::scene::{Initial, Integrator, Mode, Reference, Run, Scene, World};

type Result<T> = std::result::Result<T, SceneError>;

/// Tolerance on `Σ piece_lengths = length`, relative to `length`.
const PIECE_SUM_RTOL: f64 = 1e-9;
/// Tolerance on `R Rᵀ = I` and `det R = 1` of a base rotation.
const ROTATION_TOL: f64 = 1e-6;
/// Upper bound on `pieces`: far beyond any useful discretization, low enough
/// that a typo (`pieces = 10000000000`) cannot exhaust memory.
const MAX_PIECES: i64 = 1_000_000;

/// Parses and validates a scene; `file` names it in messages.
pub(crate) fn parse(text: &str, file: &str) -> Result<(Scene, Vec<Warning>)> {
    let spans = SpanMap::build(text).map_err(|e| map_toml_error(&e, text, file, None))?;
    let raw: RawScene =
        toml::from_str(text).map_err(|e| map_toml_error(&e, text, file, Some(&spans)))?;
    let mut cx = Ctx {
        file,
        text,
        spans: &spans,
        warnings: Vec::new(),
    };
    if let Some((path, literal, span)) = &spans.non_finite {
        return Err(SceneError::NotFinite {
            file: file.to_owned(),
            path: path.clone(),
            at: Some(Location::of_offset(text, span.start)),
            value: literal.clone(),
        });
    }
    let scene = cx.scene(raw)?;
    Ok((scene, cx.warnings))
}

/// Validation context: the file name, the text and its key spans, and the
/// warnings collected so far.
struct Ctx<'a> {
    file: &'a str,
    text: &'a str,
    spans: &'a SpanMap,
    warnings: Vec<Warning>,
}

impl Ctx<'_> {
    fn at(&self, path: &str) -> Option<Location> {
        self.spans
            .span_of(path)
            .map(|s| Location::of_offset(self.text, s.start))
    }

    fn warn(&mut self, path: &str, message: String) {
        let at = self.at(path);
        self.warnings.push(Warning {
            path: path.to_owned(),
            at,
            message,
        });
    }

    fn out_of_range(&self, path: &str, value: impl Display, expected: impl Display) -> SceneError {
        SceneError::OutOfRange {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            value: value.to_string(),
            expected: expected.to_string(),
        }
    }

    fn missing(&self, path: &str, note: &str) -> SceneError {
        SceneError::Missing {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            note: note.to_owned(),
        }
    }

    fn invalid(&self, path: &str, message: impl Display) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            message: message.to_string(),
        }
    }

    fn inconsistent(&self, path: &str, message: impl Display) -> SceneError {
        SceneError::InconsistentLengths {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            message: message.to_string(),
        }
    }

    fn wrong_type(&self, path: &str, message: impl Display) -> SceneError {
        SceneError::WrongType {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            message: message.to_string(),
        }
    }

    fn unknown_name(&self, path: &str, value: &str, valid: &[&str]) -> SceneError {
        SceneError::UnknownName {
            file: self.file.to_owned(),
            path: path.to_owned(),
            at: self.at(path),
            value: value.to_owned(),
            valid: valid.iter().map(|s| (*s).to_owned()).collect(),
        }
    }

    /// `v > 0`.
    fn positive(&self, path: &str, v: f64) -> Result<f64> {
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.out_of_range(path, v, "> 0"))
        }
    }

    /// `v ≥ 0`.
    fn non_negative(&self, path: &str, v: f64) -> Result<f64> {
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(self.out_of_range(path, v, ">= 0"))
        }
    }

    /// A required number.
    fn required(&self, path: &str, v: Option<f64>, note: &str) -> Result<f64> {
        v.ok_or_else(|| self.missing(path, note))
    }

    /// Index of the rod called `name`, or an [`SceneError::UnknownRod`] at `path`.
    fn rod_ref(&self, path: &str, name: &str, rods: &[Rod]) -> Result<usize> {
        rods.iter()
            .position(|r| r.name == name)
            .ok_or_else(|| SceneError::UnknownRod {
                file: self.file.to_owned(),
                path: path.to_owned(),
                at: self.at(path),
                name: name.to_owned(),
                known: rods.iter().map(|r| r.name.clone()).collect(),
            })
    }

    fn scene(&mut self, raw: RawScene) -> Result<Scene> {
        let world = World {
            gravity: raw.world.and_then(|w| w.gravity).unwrap_or([0.0; 3]),
        };

        if raw.rod.is_empty() {
            return Err(self.missing("rod", " (a scene needs at least one [[rod]] table)"));
        }
        let mut rods: Vec<Rod> = Vec::with_capacity(raw.rod.len());
        for (i, r) in raw.rod.into_iter().enumerate() {
            let rod = self.rod(i, r)?;
            if let Some(j) = rods.iter().position(|o| o.name == rod.name) {
                return Err(self.invalid(
                    &format!("rod[{i}].name"),
                    format!("duplicate rod name {:?} (also rod[{j}])", rod.name),
                ));
            }
            rods.push(rod);
        }

        let run = self.run(raw.run)?;

        let cables = raw
            .cable
            .into_iter()
            .enumerate()
            .map(|(i, c)| self.cable(i, c, &rods))
            .collect::<Result<Vec<_>>>()?;
        let loads = raw
            .load
            .into_iter()
            .enumerate()
            .map(|(i, l)| self.load(i, l, &rods))
            .collect::<Result<Vec<_>>>()?;
        let initial = self.initial(raw.initial, &rods)?;
        let reference = raw
            .reference
            .map(|r| self.reference(r, &rods, &run))
            .transpose()?;

        Ok(Scene {
            source: self.file.to_owned(),
            world,
            rods,
            cables,
            loads,
            initial,
            run,
            reference,
        })
    }

    fn rod(&mut self, i: usize, r: RawRod) -> Result<Rod> {
        let p = format!("rod[{i}]");
        if r.name.trim().is_empty() {
            return Err(self.invalid(&format!("{p}.name"), "rod name must not be empty"));
        }
        let length = self.positive(&format!("{p}.length"), r.length)?;
        let explicit_lengths = r.piece_lengths.is_some();
        let piece_lengths = self.piece_lengths(&p, length, r.pieces, r.piece_lengths)?;
        let strains = self.strains(&format!("{p}.strains"), r.strains.as_ref())?;
        let rest_strain = r.rest_strain.unwrap_or([0.0, 0.0, 0.0, 1.0, 0.0, 0.0]);
        let base = self.base(&p, r.base)?;
        let section = self.section(&format!("{p}.section"), r.section)?;
        let material = self.material(&format!("{p}.material"), r.material)?;
        let drag = self.drag(&format!("{p}.drag"), r.drag)?;

        // Slenderness: a piece shorter than the section is outside what a rod
        // model describes well.
        let mut s0 = 0.0;
        let mut short = Vec::new();
        for (k, &l) in piece_lengths.iter().enumerate() {
            let radius = section
                .outer_radius_at(s0 / length)
                .max(section.outer_radius_at(((s0 + l) / length).min(1.0)));
            if l < radius {
                short.push((k, l, radius));
            }
            s0 += l;
        }
        if let Some(&(k, l, radius)) = short.first() {
            let key = if explicit_lengths {
                format!("{p}.piece_lengths")
            } else {
                format!("{p}.pieces")
            };
            self.warn(
                &key,
                format!(
                    "{} of {} pieces are shorter than the section radius (piece {k}: \
                     length {l} m < radius {radius} m); a rod model assumes slender pieces",
                    short.len(),
                    piece_lengths.len()
                ),
            );
        }

        Ok(Rod {
            name: r.name,
            length,
            piece_lengths,
            strains,
            rest_strain,
            base,
            section,
            material,
            drag,
        })
    }

    fn piece_lengths(
        &self,
        p: &str,
        length: f64,
        pieces: Option<i64>,
        piece_lengths: Option<Vec<f64>>,
    ) -> Result<Vec<f64>> {
        let pieces_path = format!("{p}.pieces");
        if let Some(n) = pieces
            && !(1..=MAX_PIECES).contains(&n)
        {
            return Err(self.out_of_range(&pieces_path, n, format!("in [1, {MAX_PIECES}]")));
        }
        let lp = format!("{p}.piece_lengths");
        match (pieces, piece_lengths) {
            (None, None) => Err(self.missing(
                &pieces_path,
                " (give pieces = N for equal pieces, or piece_lengths = [...])",
            )),
            (Some(n), None) => {
                let n = n as usize;
                Ok(vec![length / n as f64; n])
            }
            (pieces, Some(v)) => {
                if v.is_empty() {
                    return Err(self.invalid(&lp, "piece_lengths must list at least one piece"));
                }
                for (k, &l) in v.iter().enumerate() {
                    self.positive(&format!("{lp}[{k}]"), l)?;
                }
                if let Some(n) = pieces
                    && n as usize != v.len()
                {
                    return Err(self.inconsistent(
                        &pieces_path,
                        format!("pieces = {n} but piece_lengths lists {} pieces", v.len()),
                    ));
                }
                let sum: f64 = v.iter().sum();
                if (sum - length).abs() > PIECE_SUM_RTOL * length {
                    return Err(self.inconsistent(
                        &lp,
                        format!(
                            "piece_lengths sum to {sum} m but length = {length} m \
                             (must agree within {PIECE_SUM_RTOL:e} relative)"
                        ),
                    ));
                }
                Ok(v)
            }
        }
    }

    fn strains(&mut self, p: &str, v: Option<&toml::Value>) -> Result<StrainSelection> {
        let list = match v {
            None => return Ok(StrainSelection::ALL),
            Some(toml::Value::String(s)) if s == "all" => return Ok(StrainSelection::ALL),
            Some(toml::Value::String(s)) => {
                if STRAIN_NAMES.contains(&s.as_str()) {
                    return Err(self.wrong_type(
                        p,
                        format!("a single strain is written as a list: strains = [{s:?}]"),
                    ));
                }
                return Err(self.unknown_name(p, s, &["all"]));
            }
            Some(toml::Value::Array(a)) => a,
            Some(other) => {
                return Err(self.wrong_type(
                    p,
                    format!(
                        "expected \"all\" or a list of strain names (kx, ky, kz, qx, qy, qz), \
                         found {}",
                        other.type_str()
                    ),
                ));
            }
        };
        if list.is_empty() {
            return Err(self.invalid(
                p,
                "select at least one strain (kx, ky, kz, qx, qy, qz), or \"all\"",
            ));
        }
        let mut mask = [false; 6];
        let mut order = Vec::new();
        for (k, v) in list.iter().enumerate() {
            let pk = format!("{p}[{k}]");
            let Some(name) = v.as_str() else {
                return Err(self.wrong_type(
                    &pk,
                    format!("expected a strain name, found {}", v.type_str()),
                ));
            };
            let Some(j) = STRAIN_NAMES.iter().position(|&n| n == name) else {
                return Err(self.unknown_name(&pk, name, &STRAIN_NAMES));
            };
            if mask[j] {
                return Err(self.invalid(&pk, format!("strain {name:?} listed twice")));
            }
            mask[j] = true;
            order.push(j);
        }
        if order.windows(2).any(|w| w[0] > w[1]) {
            let sel = StrainSelection { mask };
            self.warn(
                p,
                format!(
                    "strains are not in canonical order; the coordinates of each piece follow \
                     the order kx, ky, kz, qx, qy, qz: {:?}",
                    sel.names()
                ),
            );
        }
        Ok(StrainSelection { mask })
    }

    fn base(&self, p: &str, b: Option<crate::raw::RawBase>) -> Result<Pose> {
        let Some(b) = b else {
            return Ok(Pose::IDENTITY);
        };
        let position = b.position.unwrap_or([0.0; 3]);
        let rotation = b.rotation.unwrap_or(Pose::IDENTITY.rotation);
        let r = &rotation;
        let mut dev: f64 = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                let rrt: f64 = (0..3).map(|k| r[i][k] * r[j][k]).sum();
                let id = if i == j { 1.0 } else { 0.0 };
                dev = dev.max((rrt - id).abs());
            }
        }
        let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
            - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
            + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
        if dev > ROTATION_TOL || (det - 1.0).abs() > ROTATION_TOL {
            return Err(self.invalid(
                &format!("{p}.base.rotation"),
                format!(
                    "not a rotation matrix: must be orthonormal with determinant +1 within \
                     {ROTATION_TOL:e} (max |R Rᵀ − I| = {dev:.3e}, det R = {det})"
                ),
            ));
        }
        Ok(Pose { position, rotation })
    }

    fn section(&self, p: &str, s: RawSection) -> Result<Section> {
        let given = [
            ("radius", s.radius),
            ("radius_base", s.radius_base),
            ("radius_tip", s.radius_tip),
            ("inner_radius", s.inner_radius),
            ("width", s.width),
            ("height", s.height),
        ];
        let (allowed, keys): (&[&str], &str) = match s.shape.as_str() {
            "circle" => (
                &["radius", "radius_base", "radius_tip"],
                "radius, or radius_base and radius_tip",
            ),
            "tube" => (&["radius", "inner_radius"], "radius and inner_radius"),
            "rectangle" => (&["width", "height"], "width and height"),
            other => {
                return Err(self.unknown_name(
                    &format!("{p}.shape"),
                    other,
                    &["circle", "tube", "rectangle"],
                ));
            }
        };
        for (k, v) in given {
            if v.is_some() && !allowed.contains(&k) {
                return Err(self.invalid(
                    &format!("{p}.{k}"),
                    format!(
                        "key {k:?} does not apply to shape {:?} (it takes {keys})",
                        s.shape
                    ),
                ));
            }
        }
        let path = |k: &str| format!("{p}.{k}");
        match s.shape.as_str() {
            "circle" => match (s.radius, s.radius_base, s.radius_tip) {
                (Some(r), None, None) => Ok(Section::Circle {
                    radius: self.positive(&path("radius"), r)?,
                }),
                (None, Some(b), Some(t)) => Ok(Section::TaperedCircle {
                    radius_base: self.positive(&path("radius_base"), b)?,
                    radius_tip: self.positive(&path("radius_tip"), t)?,
                }),
                (None, None, None) => {
                    Err(self.missing(&path("radius"), " (or radius_base and radius_tip)"))
                }
                (None, Some(_), None) => Err(self.missing(
                    &path("radius_tip"),
                    " (a tapered circle needs radius_base and radius_tip)",
                )),
                (None, None, Some(_)) => Err(self.missing(
                    &path("radius_base"),
                    " (a tapered circle needs radius_base and radius_tip)",
                )),
                (Some(_), _, _) => Err(self.invalid(
                    &path("radius"),
                    "give either radius or radius_base and radius_tip, not both",
                )),
            },
            "tube" => {
                let radius = self.required(&path("radius"), s.radius, "")?;
                let radius = self.positive(&path("radius"), radius)?;
                let inner = self.required(&path("inner_radius"), s.inner_radius, "")?;
                if !(0.0..radius).contains(&inner) {
                    return Err(self.out_of_range(
                        &path("inner_radius"),
                        inner,
                        format!("in [0, radius = {radius})"),
                    ));
                }
                Ok(Section::Tube {
                    radius,
                    inner_radius: inner,
                })
            }
            _ => {
                let width = self.required(&path("width"), s.width, "")?;
                let height = self.required(&path("height"), s.height, "")?;
                Ok(Section::Rectangle {
                    width: self.positive(&path("width"), width)?,
                    height: self.positive(&path("height"), height)?,
                })
            }
        }
    }

    fn material(&self, p: &str, m: RawMaterial) -> Result<Material> {
        let path = |k: &str| format!("{p}.{k}");
        let density = self.positive(&path("density"), m.density)?;
        let young = self.positive(&path("young"), m.young)?;
        let (shear_modulus, poisson) = match (m.poisson, m.shear_modulus) {
            (Some(nu), None) => {
                if !(nu > -1.0 && nu <= 0.5) {
                    return Err(self.out_of_range(&path("poisson"), nu, "in (-1, 0.5]"));
                }
                (young / (2.0 * (1.0 + nu)), Some(nu))
            }
            (None, Some(g)) => (self.positive(&path("shear_modulus"), g)?, None),
            (None, None) => return Err(self.missing(&path("poisson"), " (or shear_modulus)")),
            (Some(_), Some(_)) => {
                return Err(self.invalid(
                    &path("shear_modulus"),
                    "give either poisson or shear_modulus, not both",
                ));
            }
        };
        let viscosity = self.non_negative(&path("viscosity"), m.viscosity.unwrap_or(0.0))?;
        Ok(Material {
            density,
            young,
            shear_modulus,
            poisson,
            viscosity,
        })
    }

    fn drag(&self, p: &str, d: Option<RawDrag>) -> Result<Drag> {
        let Some(d) = d else {
            return Ok(Drag::default());
        };
        Ok(Drag {
            translational: self.non_negative(
                &format!("{p}.translational"),
                d.translational.unwrap_or(0.0),
            )?,
            rotational: self
                .non_negative(&format!("{p}.rotational"), d.rotational.unwrap_or(0.0))?,
        })
    }

    fn cable(&mut self, i: usize, c: RawCable, rods: &[Rod]) -> Result<Cable> {
        let p = format!("cable[{i}]");
        let path = |k: &str| format!("{p}.{k}");
        let rod_index = self.rod_ref(&path("rod"), &c.rod, rods)?;
        let rod = &rods[rod_index];
        let length = rod.length;
        let from = c.from.unwrap_or(0.0);
        let to = c.to.unwrap_or(length);
        if !(0.0..length).contains(&from) {
            return Err(self.out_of_range(
                &path("from"),
                from,
                format!("in [0, length = {length})"),
            ));
        }
        if !(to > from && to <= length) {
            return Err(self.out_of_range(
                &path("to"),
                to,
                format!("in (from = {from}, length = {length}]"),
            ));
        }
        let routing = match (c.offset, c.path) {
            (Some(o), None) => Routing::Offset(o),
            (None, Some(pts)) => self.cable_path(&path("path"), pts, length, from, to)?,
            (None, None) => return Err(self.missing(&path("offset"), " (or path)")),
            (Some(_), Some(_)) => {
                return Err(self.invalid(&path("path"), "give either offset or path, not both"));
            }
        };
        let tension = self.tension(&path("tension"), &c.tension)?;

        // Sanity: where the cable runs relative to the section.
        let mut probe: Vec<f64> = vec![from, to];
        if let Routing::Path(pts) = &routing {
            probe.extend(pts.iter().map(|q| q[0]).filter(|&s| s > from && s < to));
        }
        let routing_key = match routing {
            Routing::Offset(_) => path("offset"),
            Routing::Path(_) => path("path"),
        };
        if let Some(&s) = probe.iter().find(|&&s| {
            let [y, z] = routing.offset_at(s);
            !rod.section.contains(s / length, y, z)
        }) {
            let [y, z] = routing.offset_at(s);
            self.warn(
                &routing_key,
                format!(
                    "cable offset (y, z) = ({y}, {z}) m at s = {s} m lies outside the \
                     cross-section (outer radius {} m); legal (spacer disks), but check the units",
                    rod.section.outer_radius_at(s / length)
                ),
            );
        }
        if probe.iter().all(|&s| routing.offset_at(s) == [0.0, 0.0]) {
            self.warn(
                &routing_key,
                "cable runs along the centerline: it only compresses the rod".to_owned(),
            );
        }

        Ok(Cable {
            rod: c.rod,
            rod_index,
            routing,
            tension,
            from,
            to,
        })
    }

    fn cable_path(
        &self,
        p: &str,
        pts: Vec<[f64; 3]>,
        length: f64,
        from: f64,
        to: f64,
    ) -> Result<Routing> {
        if pts.len() < 2 {
            return Err(self.invalid(
                p,
                format!(
                    "a path needs at least two points [s, y, z], found {}; use offset for a \
                     constant routing",
                    pts.len()
                ),
            ));
        }
        for (k, pt) in pts.iter().enumerate() {
            let s = pt[0];
            if !(0.0..=length).contains(&s) {
                return Err(self.out_of_range(
                    &format!("{p}[{k}][0]"),
                    s,
                    format!("in [0, length = {length}] (s of point {k})"),
                ));
            }
            if k > 0 && s <= pts[k - 1][0] {
                return Err(self.invalid(
                    &format!("{p}[{k}]"),
                    format!(
                        "path abscissae must strictly increase: s = {s} at point {k} is not \
                         greater than s = {} at point {}",
                        pts[k - 1][0],
                        k - 1
                    ),
                ));
            }
        }
        let (first, last) = (pts[0][0], pts[pts.len() - 1][0]);
        let eps = 1e-12 * length;
        if first > from + eps || last < to - eps {
            return Err(self.invalid(
                p,
                format!(
                    "path covers s in [{first}, {last}] but the cable spans [from = {from}, \
                     to = {to}]; extend the path or set from/to"
                ),
            ));
        }
        Ok(Routing::Path(pts))
    }

    fn number(&self, p: &str, v: &toml::Value) -> Result<f64> {
        match v {
            toml::Value::Integer(i) => Ok(*i as f64),
            toml::Value::Float(f) => Ok(*f),
            other => {
                Err(self.wrong_type(p, format!("expected a number, found {}", other.type_str())))
            }
        }
    }

    fn numbers(&self, p: &str, v: &toml::Value) -> Result<Vec<f64>> {
        let toml::Value::Array(a) = v else {
            return Err(self.wrong_type(
                p,
                format!("expected a list of numbers, found {}", v.type_str()),
            ));
        };
        a.iter()
            .enumerate()
            .map(|(k, x)| self.number(&format!("{p}[{k}]"), x))
            .collect()
    }

    fn tension(&self, p: &str, v: &toml::Value) -> Result<Tension> {
        let toml::Value::Table(t) = v else {
            if !matches!(v, toml::Value::Integer(_) | toml::Value::Float(_)) {
                return Err(self.wrong_type(
                    p,
                    format!(
                        "expected a number (N) or a table {{ times = [...], values = [...] }}, \
                         found {}",
                        v.type_str()
                    ),
                ));
            }
            let f = self.number(p, v)?;
            return Ok(Tension::Constant(self.non_negative(p, f)?));
        };
        for k in t.keys() {
            if k != "times" && k != "values" {
                return Err(SceneError::UnknownKey {
                    file: self.file.to_owned(),
                    path: join(p, k),
                    at: self.at(&join(p, k)),
                    expected: "`times`, `values`".to_owned(),
                });
            }
        }
        let tp = join(p, "times");
        let vp = join(p, "values");
        let times = match t.get("times") {
            Some(x) => self.numbers(&tp, x)?,
            None => return Err(self.missing(&tp, "")),
        };
        let values = match t.get("values") {
            Some(x) => self.numbers(&vp, x)?,
            None => return Err(self.missing(&vp, "")),
        };
        if times.len() != values.len() {
            return Err(self.inconsistent(
                &vp,
                format!("{} values for {} times", values.len(), times.len()),
            ));
        }
        if times.is_empty() {
            return Err(self.invalid(&tp, "a tension schedule needs at least one point"));
        }
        for k in 1..times.len() {
            if times[k] <= times[k - 1] {
                return Err(self.invalid(
                    &format!("{tp}[{k}]"),
                    format!(
                        "times must strictly increase: {} is not greater than {}",
                        times[k],
                        times[k - 1]
                    ),
                ));
            }
        }
        for (k, &x) in values.iter().enumerate() {
            self.non_negative(&format!("{vp}[{k}]"), x)?;
        }
        Ok(Tension::Schedule { times, values })
    }

    fn load(&mut self, i: usize, l: RawLoad, rods: &[Rod]) -> Result<Load> {
        let p = format!("load[{i}]");
        let path = |k: &str| format!("{p}.{k}");
        let rod_index = self.rod_ref(&path("rod"), &l.rod, rods)?;
        let length = rods[rod_index].length;
        if !(0.0..=length).contains(&l.s) {
            return Err(self.out_of_range(&path("s"), l.s, format!("in [0, length = {length}]")));
        }
        let frame = match l.frame.as_deref() {
            None | Some("world") => LoadFrame::World,
            Some("body") => LoadFrame::Body,
            Some(other) => {
                return Err(self.unknown_name(&path("frame"), other, &["world", "body"]));
            }
        };
        let force = l.force.unwrap_or([0.0; 3]);
        let moment = l.moment.unwrap_or([0.0; 3]);
        if force == [0.0; 3] && moment == [0.0; 3] {
            self.warn(
                &p,
                "force and moment are both zero: the load has no effect".to_owned(),
            );
        }
        Ok(Load {
            rod: l.rod,
            rod_index,
            s: l.s,
            force,
            moment,
            frame,
        })
    }

    fn initial(&mut self, raw: Option<RawInitial>, rods: &[Rod]) -> Result<Initial> {
        let Some(raw) = raw else {
            return Ok(Initial::default());
        };
        let n_dof: usize = rods.iter().map(Rod::n_dof).sum();
        let per_rod = rods
            .iter()
            .map(|r| {
                format!(
                    "{}: {} pieces × {} strains",
                    r.name,
                    r.n_pieces(),
                    r.strains.count()
                )
            })
            .collect::<Vec<_>>()
            .join(", ");
        for (key, v) in [("q", &raw.q), ("qdot", &raw.qdot)] {
            if let Some(v) = v
                && v.len() != n_dof
            {
                return Err(self.inconsistent(
                    &format!("initial.{key}"),
                    format!(
                        "{} values but the scene has n_dof = {n_dof} ({per_rod})",
                        v.len()
                    ),
                ));
            }
        }
        if let Some(q) = &raw.q {
            self.warn_large_strains(q, rods);
        }
        Ok(Initial {
            q: raw.q,
            qdot: raw.qdot,
        })
    }

    /// Warns (once per rod) about initial strains far outside the small-strain range.
    fn warn_large_strains(&mut self, q: &[f64], rods: &[Rod]) {
        let mut offset = 0;
        for rod in rods {
            let idx = rod.strains.indices();
            let mut found = None;
            'pieces: for (k, &l) in rod.piece_lengths.iter().enumerate() {
                for (c, &j) in idx.iter().enumerate() {
                    let at = offset + k * idx.len() + c;
                    let xi = rod.rest_strain[j] + q[at];
                    let why = if j < 3 && (xi * l).abs() > PI {
                        Some(format!(
                            "{} = {xi} 1/m turns piece {k} ({l} m) by {:.2} rad, more than π",
                            STRAIN_NAMES[j],
                            (xi * l).abs()
                        ))
                    } else if j == 3 && xi <= 0.0 {
                        Some(format!(
                            "stretch qx = {xi} ≤ 0 in piece {k}: the piece is inverted"
                        ))
                    } else if j >= 3 && q[at].abs() > 0.5 {
                        Some(format!(
                            "{} deviates from rest by {} in piece {k}: a very large strain",
                            STRAIN_NAMES[j], q[at]
                        ))
                    } else {
                        None
                    };
                    if let Some(why) = why {
                        found = Some((at, why));
                        break 'pieces;
                    }
                }
            }
            if let Some((at, why)) = found {
                self.warn(
                    &format!("initial.q[{at}]"),
                    format!("rod {:?}: {why}", rod.name),
                );
            }
            offset += rod.n_dof();
        }
    }

    fn run(&mut self, raw: Option<RawRun>) -> Result<Run> {
        let Some(r) = raw else {
            return Ok(Run::default());
        };
        let d = Run::default();
        let mode = match r.mode.as_deref() {
            None => d.mode,
            Some("dynamics") => Mode::Dynamics,
            Some("statics") => Mode::Statics,
            Some(other) => {
                return Err(self.unknown_name("run.mode", other, &["dynamics", "statics"]));
            }
        };
        let duration = self.positive("run.duration", r.duration.unwrap_or(d.duration))?;
        let integrator = match r.integrator.as_deref() {
            None => d.integrator,
            Some(name) => name.parse::<Integrator>().map_err(|_| {
                let valid: Vec<&str> = Integrator::ALL.iter().map(|i| i.name()).collect();
                self.unknown_name("run.integrator", name, &valid)
            })?,
        };
        let rtol = self.positive("run.rtol", r.rtol.unwrap_or(d.rtol))?;
        let atol = self.positive("run.atol", r.atol.unwrap_or(d.atol))?;
        let dt = self.positive("run.dt", r.dt.unwrap_or(d.dt))?;
        let output_every = self.positive(
            "run.output_every",
            r.output_every.unwrap_or(duration / 1000.0),
        )?;
        let quadrature = match r.quadrature {
            None => d.quadrature,
            Some(n) if n >= 1 => n as usize,
            Some(n) => return Err(self.out_of_range("run.quadrature", n, ">= 1")),
        };
        let error_control = r.error_control.unwrap_or(d.error_control);
        if error_control && integrator != Integrator::GeneralizedAlpha {
            self.warn(
                "run.error_control",
                format!(
                    "error_control only applies to generalized-alpha ({integrator} is {}): ignored",
                    if integrator.is_adaptive() {
                        "adaptive already"
                    } else {
                        "fixed-step"
                    }
                ),
            );
        }
        let linearly_implicit = r.linearly_implicit.unwrap_or(d.linearly_implicit);
        if linearly_implicit && integrator != Integrator::GeneralizedAlpha {
            self.warn(
                "run.linearly_implicit",
                format!(
                    "linearly_implicit only applies to generalized-alpha ({integrator}): ignored"
                ),
            );
        }
        if r.dt.is_some() && dt > duration {
            self.warn(
                "run.dt",
                format!("dt = {dt} s is longer than the whole run (duration = {duration} s)"),
            );
        }
        if output_every > duration {
            self.warn(
                "run.output_every",
                format!(
                    "output_every = {output_every} s is longer than duration = {duration} s: \
                     only the initial and final states will be written"
                ),
            );
        }
        Ok(Run {
            mode,
            duration,
            integrator,
            rtol,
            atol,
            dt,
            output_every,
            quadrature,
            error_control,
            linearly_implicit,
        })
    }

    fn reference(&mut self, r: RawReference, rods: &[Rod], run: &Run) -> Result<Reference> {
        let rod_index = match &r.rod {
            Some(name) => self.rod_ref("reference.rod", name, rods)?,
            None => 0,
        };
        let tolerance = r
            .tolerance
            .map(|t| self.positive("reference.tolerance", t))
            .transpose()?;
        if let Some(t) = r.time
            && !(0.0..=run.duration).contains(&t)
        {
            return Err(self.out_of_range(
                "reference.time",
                t,
                format!("in [0, run.duration = {}]", run.duration),
            ));
        }
        if let Some(f) = &r.frequencies_hz {
            for (k, &x) in f.iter().enumerate() {
                self.positive(&format!("reference.frequencies_hz[{k}]"), x)?;
            }
        }
        if r.tip.is_none() && r.frequencies_hz.is_none() {
            self.warn(
                "reference",
                "states neither tip nor frequencies_hz: nothing to compare against".to_owned(),
            );
        }
        Ok(Reference {
            rod: rods[rod_index].name.clone(),
            rod_index,
            tip: r.tip,
            tolerance,
            time: r.time,
            frequencies_hz: r.frequencies_hz,
            note: r.note,
        })
    }
}
