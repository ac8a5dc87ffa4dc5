//! Scenes from Python objects: a scene as nested dicts and lists with the
//! keys of the TOML file (docs/scene-format.md), read by the scene loader
//! itself, so that Python and TOML share one set of keys, defaults,
//! checks and messages.
//!
//! Everything a scene can say — bodies, joints (fixed, revolute, prismatic,
//! universal, spherical, free; stiffness, damping, rest, prescribed),
//! trees, loop closures, obstacles and contact settings — reaches Python
//! this way: `Simulation.from_dict(scene)`, and `Simulation(rods, …,
//! bodies=, closures=, obstacles=, contact=)`, whose `softrod.Rod`s are
//! written as the scene tables they stand for ([`RodTables`]). The value
//! is written as TOML text and parsed; an error names the key path
//! (`obstacle[0].radius`) and the source name given, not a line of that
//! generated text.

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use softrod::mechanics as mech;
use toml::{Table, Value};

use crate::errors::{input, to_py};
use crate::model::{Material, Section};

/// The TOML value of the Python object `obj`, the scene value at key path
/// `path` (for messages). Dicts are tables (string keys; a key whose value
/// is None is left out, so that it takes the scene's default), lists and
/// tuples arrays, numpy arrays and scalars their Python values
/// (`tolist()`), `softrod.Section` and `softrod.Material` objects their
/// scene tables.
pub fn value(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<Value> {
    if let Ok(b) = obj.cast::<PyBool>() {
        return Ok(Value::Boolean(b.is_true()));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(Value::String(s.to_str()?.to_owned()));
    }
    if obj.is_instance_of::<PyInt>() {
        let i: i64 = obj
            .extract()
            .map_err(|_| input(format!("{path}: the integer {obj} does not fit in 64 bits")))?;
        return Ok(Value::Integer(i));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(Value::Float(obj.extract()?));
    }
    if let Ok(d) = obj.cast::<PyDict>() {
        return table(d, path).map(Value::Table);
    }
    if let Ok(s) = obj.cast::<Section>() {
        return Ok(Value::Table(section_table(&s.get().inner)));
    }
    if let Ok(m) = obj.cast::<Material>() {
        return Ok(Value::Table(material_table(&m.get().inner)));
    }
    let items: Option<Vec<Bound<'_, PyAny>>> = if let Ok(l) = obj.cast::<PyList>() {
        Some(l.iter().collect())
    } else if let Ok(t) = obj.cast::<PyTuple>() {
        Some(t.iter().collect())
    } else {
        None
    };
    if let Some(items) = items {
        let mut out = Vec::with_capacity(items.len());
        for (i, item) in items.iter().enumerate() {
            if item.is_none() {
                return Err(input(format!("{path}[{i}]: None is not a scene value")));
            }
            out.push(value(item, &format!("{path}[{i}]"))?);
        }
        return Ok(Value::Array(out));
    }
    // numpy arrays and scalars (np.int64, np.bool_ are not int, bool).
    if obj.hasattr("tolist")? {
        let v = obj.call_method0("tolist")?;
        if !v.is(obj) {
            return value(&v, path);
        }
    }
    if obj.cast::<crate::model::Rod>().is_ok() {
        return Err(input(format!(
            "{path}: a softrod.Rod stands for several tables (its cables and loads are \
             [[cable]] and [[load]] entries): pass it to Simulation(rods=[...]), or give its \
             [[rod]] keys as a dict"
        )));
    }
    let kind = obj.get_type().name()?;
    Err(input(format!(
        "{path}: a {kind} cannot be a scene value (give numbers, strings, booleans, lists or \
         dicts with the scene file's keys)"
    )))
}

/// The table of a dict: string keys, None values left out.
pub fn table(d: &Bound<'_, PyDict>, path: &str) -> PyResult<Table> {
    let mut t = Table::new();
    for (k, v) in d.iter() {
        let Ok(k) = k.cast::<PyString>() else {
            return Err(input(format!(
                "{}: keys must be strings, got {}",
                if path.is_empty() { "(top level)" } else { path },
                k.repr()?
            )));
        };
        let k = k.to_str()?.to_owned();
        if v.is_none() {
            continue;
        }
        let sub = if path.is_empty() {
            k.clone()
        } else {
            format!("{path}.{k}")
        };
        t.insert(k, value(&v, &sub)?);
    }
    Ok(t)
}

fn floats(v: &[f64]) -> Value {
    Value::Array(v.iter().map(|&x| Value::Float(x)).collect())
}

/// A section as the scene's `section` table.
pub fn section_table(s: &mech::Section) -> Table {
    let mut t = Table::new();
    let mut put = |k: &str, v: Value| {
        t.insert(k.to_owned(), v);
    };
    match *s {
        mech::Section::Circle { radius } => {
            put("shape", Value::String("circle".into()));
            put("radius", Value::Float(radius));
        }
        mech::Section::Tube {
            radius,
            inner_radius,
        } => {
            put("shape", Value::String("tube".into()));
            put("radius", Value::Float(radius));
            put("inner_radius", Value::Float(inner_radius));
        }
        mech::Section::Rectangle { width, height } => {
            put("shape", Value::String("rectangle".into()));
            put("width", Value::Float(width));
            put("height", Value::Float(height));
        }
        mech::Section::TaperedCircle {
            radius_base,
            radius_tip,
        } => {
            put("shape", Value::String("circle".into()));
            put("radius_base", Value::Float(radius_base));
            put("radius_tip", Value::Float(radius_tip));
        }
    }
    t
}

/// A material as the scene's `material` table, with its shear modulus
/// (the value the model uses, whichever way it was given).
pub fn material_table(m: &mech::Material) -> Table {
    let mut t = Table::new();
    t.insert("density".into(), Value::Float(m.density()));
    t.insert("young".into(), Value::Float(m.young()));
    t.insert("shear_modulus".into(), Value::Float(m.shear_modulus()));
    t.insert("viscosity".into(), Value::Float(m.viscosity()));
    t
}

/// A pose as the scene's `base` table.
pub fn pose_table(g: &softrod::lie::Pose) -> Table {
    let mut t = Table::new();
    t.insert("position".into(), floats(g.translation.as_slice()));
    let rows = (0..3)
        .map(|i| floats(&[g.rotation[(i, 0)], g.rotation[(i, 1)], g.rotation[(i, 2)]]))
        .collect();
    t.insert("rotation".into(), Value::Array(rows));
    t
}

/// A `softrod.Rod` as the scene tables it stands for: its `[[rod]]` table
/// (without `name`, set when it enters a simulation), and its cables and
/// loads as `[[cable]]` and `[[load]]` tables (without `rod`).
#[derive(Clone, Debug, Default)]
pub struct RodTables {
    pub rod: Table,
    pub cables: Vec<Table>,
    pub loads: Vec<Table>,
}

impl RodTables {
    /// Whether the rod needs the scene's path (a parent or a joint, which
    /// only a scene resolves).
    pub fn attached(&self) -> bool {
        self.rod.contains_key("parent") || self.rod.contains_key("joint")
    }
}

/// A cable as its `[[cable]]` table (without `rod`).
pub fn cable_table(c: &crate::model::Cable) -> Table {
    let mut t = Table::new();
    match &c.routing {
        mech::Routing::Offset { y, z } => {
            t.insert("offset".into(), floats(&[*y, *z]));
        }
        mech::Routing::Path(p) => {
            t.insert(
                "path".into(),
                Value::Array(p.iter().map(|r| floats(r)).collect()),
            );
        }
    }
    let tension = match &c.tension {
        mech::Tension::Constant(v) => Value::Float(*v),
        mech::Tension::Table { times, values } => {
            let mut s = Table::new();
            s.insert("times".into(), floats(times));
            s.insert("values".into(), floats(values));
            Value::Table(s)
        }
    };
    t.insert("tension".into(), tension);
    t.insert("from".into(), Value::Float(c.from));
    if c.friction != 0.0 {
        t.insert("friction".into(), Value::Float(c.friction));
    }
    if let Some(to) = c.to {
        t.insert("to".into(), Value::Float(to));
    }
    t
}

/// A point load as its `[[load]]` table (without `rod`).
pub fn load_table(l: &mech::PointLoad) -> Table {
    let mut t = Table::new();
    t.insert("s".into(), Value::Float(l.s));
    t.insert("force".into(), floats(l.force.as_slice()));
    t.insert("moment".into(), floats(l.moment.as_slice()));
    let frame = match l.frame {
        mech::LoadFrame::World => "world",
        mech::LoadFrame::Body => "body",
    };
    t.insert("frame".into(), Value::String(frame.into()));
    t
}

/// What `Simulation(rods, gravity, …)` was given beyond the rods, as scene
/// tables.
pub struct Extras<'a, 'py> {
    pub bodies: Option<&'a Bound<'py, PyAny>>,
    pub closures: Option<&'a Bound<'py, PyAny>>,
    pub obstacles: Option<&'a Bound<'py, PyAny>>,
    pub contact: Option<&'a Bound<'py, PyAny>>,
}

impl Extras<'_, '_> {
    /// Whether any was given.
    pub fn any(&self) -> bool {
        self.bodies.is_some()
            || self.closures.is_some()
            || self.obstacles.is_some()
            || self.contact.is_some()
    }
}

/// A scene document: its top-level keys and their values, in order (the
/// order of the rods and bodies is that of `q`).
pub type Document = Vec<(String, Value)>;

/// The document of a dict with the scene file's top-level keys, in the
/// dict's order.
pub fn dict_document(d: &Bound<'_, PyDict>) -> PyResult<Document> {
    let mut doc = Document::new();
    for (k, v) in table(d, "")?.into_iter() {
        doc.push((k, v));
    }
    // `table` sorts the keys: restore the dict's order.
    let order: Vec<String> = d
        .keys()
        .iter()
        .filter_map(|k| k.extract::<String>().ok())
        .collect();
    doc.sort_by_key(|(k, _)| order.iter().position(|o| o == k));
    Ok(doc)
}

/// The scene document of `Simulation(rods, gravity, quadrature=, …)`:
/// `rods` are `softrod.Rod`s or `[[rod]]` dicts (unnamed rods named rod0,
/// rod1, … by position), the extras the lists and table of the same keys;
/// rods come first in `q`, then the bodies.
pub fn document(
    rods: &Bound<'_, PyList>,
    gravity: Option<[f64; 3]>,
    quadrature: usize,
    extras: &Extras<'_, '_>,
) -> PyResult<Document> {
    let mut doc = Document::new();
    if let Some(g) = gravity {
        let mut w = Table::new();
        w.insert("gravity".into(), floats(&g));
        doc.push(("world".into(), Value::Table(w)));
    }
    let (mut rod_list, mut cables, mut loads) = (Vec::new(), Vec::new(), Vec::new());
    for (i, r) in rods.iter().enumerate() {
        let path = format!("rod[{i}]");
        if let Ok(rod) = r.cast::<crate::model::Rod>() {
            let rod = rod.get();
            let name = if rod.named {
                rod.spec.name.clone()
            } else {
                format!("rod{i}")
            };
            let mut t = rod.tables.rod.clone();
            t.insert("name".into(), Value::String(name.clone()));
            rod_list.push(Value::Table(t));
            for c in &rod.tables.cables {
                let mut c = c.clone();
                c.insert("rod".into(), Value::String(name.clone()));
                cables.push(Value::Table(c));
            }
            for l in &rod.tables.loads {
                let mut l = l.clone();
                l.insert("rod".into(), Value::String(name.clone()));
                loads.push(Value::Table(l));
            }
        } else if let Ok(d) = r.cast::<PyDict>() {
            let mut t = table(d, &path)?;
            if !t.contains_key("name") {
                t.insert("name".into(), Value::String(format!("rod{i}")));
            }
            rod_list.push(Value::Table(t));
        } else {
            return Err(input(format!(
                "Simulation(rods[{i}]) is neither a softrod.Rod nor a dict of [[rod]] keys"
            )));
        }
    }
    doc.push(("rod".into(), Value::Array(rod_list)));
    if !cables.is_empty() {
        doc.push(("cable".into(), Value::Array(cables)));
    }
    if !loads.is_empty() {
        doc.push(("load".into(), Value::Array(loads)));
    }
    for (key, given) in [
        ("body", extras.bodies),
        ("closure", extras.closures),
        ("obstacle", extras.obstacles),
    ] {
        if let Some(v) = given {
            match value(v, key)? {
                a @ Value::Array(_) => {
                    doc.push((key.into(), a));
                }
                _ => {
                    return Err(input(format!(
                        "{key}: give a list of dicts with the scene's [[{key}]] keys"
                    )));
                }
            }
        }
    }
    if let Some(c) = extras.contact {
        match value(c, "contact")? {
            t @ Value::Table(_) => {
                doc.push(("contact".into(), t));
            }
            _ => {
                return Err(input(
                    "contact: give a dict with the scene's [contact] keys (rods, self, friction, \
                     restitution)",
                ));
            }
        }
    }
    let mut run = Table::new();
    run.insert("quadrature".into(), Value::Integer(quadrature as i64));
    doc.push(("run".into(), Value::Table(run)));
    Ok(doc)
}

/// A key as TOML writes it: bare, or quoted.
fn key_text(k: &str) -> String {
    let bare = !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        k.to_owned()
    } else {
        Value::String(k.to_owned()).to_string()
    }
}

fn is_table_array(v: &Value) -> bool {
    matches!(v, Value::Array(a) if !a.is_empty() && a.iter().all(Value::is_table))
}

/// The TOML text of a scene document, its tables and arrays of tables in
/// the document's order (which the scene reads as the order of the
/// elements), every value inline.
pub fn text(doc: &Document) -> String {
    let mut out = String::new();
    let line = |out: &mut String, k: &str, v: &Value| {
        out.push_str(&key_text(k));
        out.push_str(" = ");
        out.push_str(&v.to_string());
        out.push('\n');
    };
    // Plain values belong to the root: before any header.
    for (k, v) in doc {
        if !v.is_table() && !is_table_array(v) {
            line(&mut out, k, v);
        }
    }
    for (k, v) in doc {
        let entries: Vec<&Table> = match v {
            Value::Table(t) => {
                out.push_str(&format!("\n[{}]\n", key_text(k)));
                vec![t]
            }
            Value::Array(a) if is_table_array(v) => {
                for t in a.iter().filter_map(Value::as_table) {
                    out.push_str(&format!("\n[[{}]]\n", key_text(k)));
                    for (kk, vv) in t {
                        line(&mut out, kk, vv);
                    }
                }
                continue;
            }
            _ => continue,
        };
        for t in entries {
            for (kk, vv) in t {
                line(&mut out, kk, vv);
            }
        }
    }
    out
}

/// The facade's simulation of a scene document, its warnings and its
/// `[run] duration`. `name` stands for the source in messages; an error
/// names it and the key path, never a line of the generated text.
pub fn simulation(doc: &Document, name: &str) -> PyResult<(softrod::Simulation, Vec<String>, f64)> {
    let text = text(doc);
    match softrod::Simulation::from_toml(&text, name) {
        Ok((sim, scene, warnings)) => Ok((
            sim,
            warnings
                .iter()
                .map(|w| without_location(&w.to_string(), name))
                .collect(),
            scene.run.duration,
        )),
        Err(softrod::Error::Scene(e)) => {
            let message = softrod::Error::Scene(e).report();
            Err(crate::errors::SceneError::new_err(without_location(
                &message, name,
            )))
        }
        Err(e) => Err(to_py(e)),
    }
}

/// `name:12:3: key: …` → `name: key: …`: the line and column are those of
/// text nobody wrote.
fn without_location(message: &str, name: &str) -> String {
    let Some(rest) = message.strip_prefix(name) else {
        return message.to_owned();
    };
    let Some(rest) = rest.strip_prefix(':') else {
        return message.to_owned();
    };
    let digits = |s: &str| s.find(|c: char| !c.is_ascii_digit()).unwrap_or(s.len());
    let (l, after) = rest.split_at(digits(rest));
    if l.is_empty() {
        return message.to_owned();
    }
    let Some(after) = after.strip_prefix(':') else {
        return message.to_owned();
    };
    let (c, after) = after.split_at(digits(after));
    if c.is_empty() || !after.starts_with(':') {
        return message.to_owned();
    }
    format!("{name}{after}")
}

/// How a rod hangs in a robot: `parent`, `at`, `joint` as given.
pub type Attach<'a, 'py> = (Option<String>, Option<f64>, Option<&'a Bound<'py, PyAny>>);

/// The scene tables of a `softrod.Rod` built from `spec`: `pieces` when
/// given as a count (else `piece_lengths`), `strains` when given (the
/// selected indices), the rest strain and drag when given, the cables as
/// given (`cables`, already checked), and its attachment.
pub fn rod_tables(
    length: f64,
    spec: &softrod::dynamics::Rod,
    pieces: Option<i64>,
    strains: Option<Vec<usize>>,
    rest_given: bool,
    cables: Option<&Bound<'_, PyList>>,
    (parent, at, joint): Attach<'_, '_>,
) -> PyResult<RodTables> {
    let g = &spec.geometry;
    let mut t = Table::new();
    t.insert("length".into(), Value::Float(length));
    match pieces {
        Some(n) => {
            t.insert("pieces".into(), Value::Integer(n));
        }
        None => {
            t.insert(
                "piece_lengths".into(),
                floats(&g.piece_lengths().collect::<Vec<_>>()),
            );
        }
    }
    if let Some(idx) = strains {
        let names = idx
            .iter()
            .map(|&i| Value::String(softrod::kinematics::Strain::ALL[i].name().into()))
            .collect();
        t.insert("strains".into(), Value::Array(names));
    }
    if rest_given {
        t.insert(
            "rest_strain".into(),
            floats(g.pieces()[0].rest_strain.as_slice()),
        );
    }
    t.insert("base".into(), Value::Table(pose_table(g.base())));
    t.insert(
        "section".into(),
        Value::Table(section_table(spec.properties.section())),
    );
    t.insert(
        "material".into(),
        Value::Table(material_table(spec.properties.material())),
    );
    if let Some(d) = &spec.drag {
        let mut dt = Table::new();
        dt.insert("translational".into(), Value::Float(d.translational));
        dt.insert("rotational".into(), Value::Float(d.rotational));
        t.insert("drag".into(), Value::Table(dt));
    }
    if let Some(r) = spec.contact_radius {
        t.insert("contact_radius".into(), Value::Float(r));
    }
    if let Some(p) = parent {
        t.insert("parent".into(), Value::String(p));
    }
    if let Some(s) = at {
        t.insert("at".into(), Value::Float(s));
    }
    if let Some(j) = joint {
        let v = value(j, "Rod(joint)")?;
        if !v.is_table() {
            return Err(input(
                "Rod(joint) must be a joint table: softrod.Joint(...) or a dict with the \
                 scene's joint keys",
            ));
        }
        t.insert("joint".into(), v);
    }
    let mut out = RodTables {
        rod: t,
        cables: Vec::new(),
        loads: spec.point_loads.iter().map(load_table).collect(),
    };
    if let Some(list) = cables {
        for c in list.iter() {
            if let Ok(c) = c.cast::<crate::model::Cable>() {
                out.cables.push(cable_table(c.get()));
            }
        }
    }
    Ok(out)
}

/// Whether `Simulation(rods, …)` must go through the scene: extras, a rod
/// given as a dict, or a rod on a parent or a joint.
pub fn needs_scene(rods: &Bound<'_, PyList>, extras: &Extras<'_, '_>) -> bool {
    extras.any()
        || rods.iter().any(|r| match r.cast::<crate::model::Rod>() {
            Ok(r) => r.get().tables.attached(),
            Err(_) => r.cast::<PyDict>().is_ok(),
        })
}

/// `Simulation(rods, gravity, quadrature=, …)` through the scene: the
/// facade's simulation (sampling every thousandth of a run, as a
/// simulation of rods alone) and the scene's warnings.
pub fn simulation_with(
    rods: &Bound<'_, PyList>,
    gravity: Option<&Bound<'_, PyAny>>,
    quadrature: usize,
    extras: &Extras<'_, '_>,
) -> PyResult<(softrod::Simulation, Vec<String>)> {
    let g = match gravity {
        Some(g) => Some(crate::convert::vec3(g, "gravity")?),
        None => None,
    };
    let doc = document(rods, g, quadrature, extras)?;
    let (mut sim, warnings, _) = simulation(&doc, "Simulation")?;
    sim.set_settings(softrod::Settings {
        output_every: None,
        ..sim.settings().clone()
    })
    .map_err(to_py)?;
    Ok((sim, warnings))
}
