//! `parent`, `at`, `joint` on rods and bodies, `[[body]]`, and `[[load]]`
//! with `body = …`: into the library's `Joint`, `BodySpec`, `Attachment`
//! (scene-format.md, "Bodies, joints, bases and closures").

use nalgebra::Matrix3;
use softrod_dynamics::{
    Attachment, BodyLoad, BodySpec, Curve, ElementKind, Joint, JointActuator, JointForce,
    JointKind, Prescribed, Rod,
};
use softrod_lie::Vec3;
use softrod_mechanics::LoadFrame;

use super::{Ctx, Result};
use crate::keys;
use crate::raw::RawLoad;
use crate::robot::{RawBody, RawJoint, Robot};

/// What a `[[rod]]` says about where it hangs.
pub(super) type RodLink = (Option<String>, Option<f64>, Option<RawJoint>);

const JOINTS: [&str; 6] = [
    "fixed",
    "revolute",
    "prismatic",
    "universal",
    "spherical",
    "free",
];

impl Ctx<'_> {
    /// The elements' attachments and the bodies, checked: names unique over
    /// rods and bodies, parents known and acyclic, `at` within a parent
    /// rod (anywhere on it, D62), joints and bodies valid.
    pub(super) fn robot(
        &mut self,
        links: Vec<RodLink>,
        raw_bodies: Vec<RawBody>,
        rods: &[Rod],
    ) -> Result<Robot> {
        let mut robot = Robot::default();
        let mut parents: Vec<(String, Option<String>, Option<f64>)> = Vec::new();
        for (i, (parent, at, joint)) in links.into_iter().enumerate() {
            let p = format!("rod[{i}]");
            let joint = self.joint(&format!("{p}.joint"), joint)?;
            parents.push((p, parent.clone(), at));
            robot.rod_attachments.push(Attachment {
                parent: parent.filter(|n| n != "world"),
                at,
                joint,
            });
        }
        for (j, b) in raw_bodies.into_iter().enumerate() {
            let p = format!("body[{j}]");
            if b.name.trim().is_empty() {
                return Err(self
                    .r
                    .invalid(&format!("{p}.name"), "body name must not be empty"));
            }
            if b.name == "world" {
                return Err(self
                    .r
                    .invalid(&format!("{p}.name"), "\"world\" names the world frame"));
            }
            if let Some(i) = rods.iter().position(|r| r.name == b.name) {
                return Err(self.r.invalid(
                    &format!("{p}.name"),
                    format!("duplicate name {:?} (also rod[{i}])", b.name),
                ));
            }
            if let Some(k) = robot.bodies.iter().position(|o| o.name == b.name) {
                return Err(self.r.invalid(
                    &format!("{p}.name"),
                    format!("duplicate body name {:?} (also body[{k}])", b.name),
                ));
            }
            let joint = self.joint(&format!("{p}.joint"), b.joint)?;
            let body = self.body(&p, b.name, b.mass, &b.inertia, b.center_of_mass, b.base)?;
            parents.push((p, Some(b.parent.clone()), b.at));
            robot.body_attachments.push(Attachment {
                parent: Some(b.parent).filter(|n| n != "world"),
                at: b.at,
                joint,
            });
            robot.bodies.push(body);
        }
        if rods.iter().any(|r| r.name == "world") {
            let i = rods.iter().position(|r| r.name == "world").unwrap_or(0);
            if parents
                .iter()
                .any(|(_, p, _)| p.as_deref() == Some("world"))
            {
                return Err(self.r.invalid(
                    &format!("rod[{i}].name"),
                    "\"world\" names the world frame; rename the rod",
                ));
            }
        }
        // Elements by name: rods then bodies, as indices into `parents`.
        let names: Vec<String> = rods
            .iter()
            .map(|r| r.name.clone())
            .chain(robot.bodies.iter().map(|b| b.name.clone()))
            .collect();
        let n_rods = rods.len();
        let mut parent_of = vec![None; names.len()];
        for (e, (p, parent, at)) in parents.iter().enumerate() {
            let Some(name) = parent.as_deref().filter(|n| *n != "world") else {
                if at.is_some() {
                    self.warn(
                        &format!("{p}.at"),
                        "at is not used: the parent is the world".to_owned(),
                    );
                }
                continue;
            };
            let Some(k) = names.iter().position(|n| n == name) else {
                let mut valid: Vec<&str> = names.iter().map(String::as_str).collect();
                valid.push("world");
                return Err(self.r.unknown_name(&format!("{p}.parent"), name, &valid));
            };
            parent_of[e] = Some(k);
            if k < n_rods {
                let rod = &rods[k].geometry;
                let len = rod.length();
                if let Some(s) = *at {
                    if !(0.0..=len).contains(&s) {
                        return Err(self.r.out_of_range(
                            &format!("{p}.at"),
                            s,
                            format!("in [0, {len}] (the length of rod {name:?})"),
                        ));
                    }
                }
            } else if at.is_some() {
                self.warn(
                    &format!("{p}.at"),
                    format!("at is not used: the parent {name:?} is a body"),
                );
            }
        }
        for start in 0..names.len() {
            let mut e = start;
            for _ in 0..=names.len() {
                match parent_of[e] {
                    Some(k) if k == start => {
                        return Err(self.r.invalid(
                            &format!("{}.parent", parents[start].0),
                            format!("parent cycle: {:?} is its own ancestor", names[start]),
                        ));
                    }
                    Some(k) => e = k,
                    None => break,
                }
            }
        }
        // The order of the file: rods and bodies by where their tables start.
        // (line and column of the table, index, element)
        type Placed = (Option<(usize, usize)>, usize, ElementKind);
        let mut order: Vec<Placed> = Vec::new();
        for (e, (p, _, _)) in parents.iter().enumerate() {
            let kind = if e < n_rods {
                ElementKind::Rod(e)
            } else {
                ElementKind::Body(e - n_rods)
            };
            order.push((self.r.at(p).map(|l| (l.line, l.column)), e, kind));
        }
        order.sort_by_key(|(at, e, _)| (*at, *e));
        robot.order = order.into_iter().map(|(_, _, k)| k).collect();
        Ok(robot)
    }

    /// `joint = { … }` (default fixed).
    fn joint(&self, p: &str, raw: Option<RawJoint>) -> Result<Joint> {
        let Some(raw) = raw else {
            return Ok(Joint::fixed());
        };
        // The type first: the other keys' messages name it ("a helical
        // joint has no axis" would hide that no such joint exists).
        if !JOINTS.contains(&raw.kind.as_str()) {
            return Err(self
                .r
                .unknown_name(&format!("{p}.type"), &raw.kind, &JOINTS));
        }
        let axis = |key: &str, a: Option<[f64; 3]>| -> Result<Vec3> {
            let a = a.ok_or_else(|| {
                self.r
                    .missing(&format!("{p}.{key}"), &format!(" (a {} joint)", raw.kind))
            })?;
            let v = Vec3::from(a);
            if v.norm() < 1e-12 {
                return Err(self.r.invalid(
                    &format!("{p}.{key}"),
                    format!("{a:?} is not a direction (zero vector)"),
                ));
            }
            Ok(v)
        };
        let needs_axis = matches!(raw.kind.as_str(), "revolute" | "prismatic");
        if raw.axis.is_some() && !needs_axis {
            return Err(self.r.invalid(
                &format!("{p}.axis"),
                format!("a {} joint has no axis", raw.kind),
            ));
        }
        if raw.axes.is_some() && raw.kind != "universal" {
            return Err(self.r.invalid(
                &format!("{p}.axes"),
                format!("a {} joint has no axes (only universal)", raw.kind),
            ));
        }
        let kind = match raw.kind.as_str() {
            "fixed" => JointKind::Fixed,
            "revolute" => JointKind::Revolute {
                axis: axis("axis", raw.axis)?,
            },
            "prismatic" => JointKind::Prismatic {
                axis: axis("axis", raw.axis)?,
            },
            "universal" => {
                let axes = raw.axes.ok_or_else(|| {
                    self.r
                        .missing(&format!("{p}.axes"), " (a universal joint: two axes)")
                })?;
                let (a, b) = (Vec3::from(axes[0]), Vec3::from(axes[1]));
                for (k, v) in [a, b].iter().enumerate() {
                    if v.norm() < 1e-12 {
                        return Err(self
                            .r
                            .invalid(&format!("{p}.axes[{k}]"), "not a direction (zero vector)"));
                    }
                }
                if a.normalize().cross(&b.normalize()).norm() < 1e-9 {
                    return Err(self
                        .r
                        .invalid(&format!("{p}.axes"), "the two axes are parallel"));
                }
                JointKind::Universal { axes: [a, b] }
            }
            "spherical" => JointKind::Spherical,
            "free" => JointKind::Free,
            other => return Err(self.r.unknown_name(&format!("{p}.type"), other, &JOINTS)),
        };
        let mut joint = Joint::new(kind);
        let k = joint.dof();
        let per_dof = |key: &str, v: &Option<toml::Value>, non_negative: bool| {
            let Some(v) = v else {
                return Ok(Vec::new());
            };
            let path = format!("{p}.{key}");
            if k == 0 {
                return Err(self.r.invalid(&path, "a fixed joint has no coordinates"));
            }
            let values = match v {
                toml::Value::Array(_) => self.numbers(&path, v)?,
                _ => vec![self.number(&path, v)?; k],
            };
            if values.len() != k {
                return Err(self.r.inconsistent(
                    &path,
                    format!(
                        "{} values, but a {} joint has {k} coordinates",
                        values.len(),
                        raw.kind
                    ),
                ));
            }
            for (i, x) in values.iter().enumerate() {
                if non_negative && *x < 0.0 {
                    return Err(self.r.out_of_range(&format!("{path}[{i}]"), x, ">= 0"));
                }
            }
            Ok(values)
        };
        joint.stiffness = per_dof("stiffness", &raw.stiffness, true)?;
        joint.damping = per_dof("damping", &raw.damping, true)?;
        joint.rest = per_dof("rest", &raw.rest, false)?;
        if let Some(v) = &raw.prescribed {
            let path = format!("{p}.prescribed");
            if k == 0 {
                return Err(self.r.invalid(&path, "a fixed joint has no coordinates"));
            }
            for (key, given) in [
                ("stiffness", raw.stiffness.is_some()),
                ("damping", raw.damping.is_some()),
                ("rest", raw.rest.is_some()),
            ] {
                if given {
                    return Err(self.r.inconsistent(
                        &format!("{p}.{key}"),
                        "a prescribed joint follows its curve: it has no stiffness, damping or rest",
                    ));
                }
            }
            joint.prescribed = Some(self.prescribed(&path, v, k)?);
        }
        if let Some(v) = &raw.actuator {
            let path = format!("{p}.actuator");
            if k == 0 {
                return Err(self.r.invalid(
                    &path,
                    "a fixed joint has no coordinates to drive (an actuator needs revolute, \
                     prismatic, universal, spherical or free)",
                ));
            }
            if raw.prescribed.is_some() {
                return Err(self.r.inconsistent(
                    &path,
                    "a prescribed joint follows its curve: a force on it would do nothing",
                ));
            }
            joint.actuator = Some(self.actuator(&path, v, k, &raw.kind)?);
        }
        joint
            .validate(p)
            .map_err(|e| self.r.invalid(p, e.to_string()))?;
        Ok(joint)
    }

    /// `actuator = { force, max_force }` (docs/theory-control.md IS14):
    /// `force` a number (every coordinate), `k` numbers, or `{ times,
    /// values }` (values a list of numbers for one coordinate, else one row
    /// of `k` per time), default 0; `max_force` a number or `k` numbers,
    /// `≥ 0`, default none.
    fn actuator(&self, path: &str, v: &toml::Value, k: usize, kind: &str) -> Result<JointActuator> {
        let toml::Value::Table(t) = v else {
            return Err(self
                .r
                .wrong_type(path, format!("expected a table, found {}", v.type_str())));
        };
        if let Some(key) = t
            .keys()
            .find(|key| !["force", "max_force"].contains(&key.as_str()))
        {
            return Err(self
                .r
                .unknown_key(&format!("{path}.{key}"), "force or max_force"));
        }
        let per_dof = |kp: &str, x: &toml::Value| -> Result<Vec<f64>> {
            let values = match x {
                toml::Value::Array(_) => self.numbers(kp, x)?,
                _ => vec![self.number(kp, x)?; k],
            };
            if values.len() != k {
                return Err(self.r.inconsistent(
                    kp,
                    format!(
                        "{} values, but a {kind} joint has {k} coordinates",
                        values.len()
                    ),
                ));
            }
            Ok(values)
        };
        let fp = format!("{path}.force");
        let force = match t.get("force") {
            None => JointForce::Constant(vec![0.0; k]),
            Some(toml::Value::Table(ft)) => {
                if let Some(key) = ft
                    .keys()
                    .find(|key| !["times", "values"].contains(&key.as_str()))
                {
                    return Err(self
                        .r
                        .unknown_key(&format!("{fp}.{key}"), "times or values"));
                }
                let tp = format!("{fp}.times");
                let vp = format!("{fp}.values");
                let times = ft.get("times").ok_or_else(|| self.r.missing(&tp, ""))?;
                let times = self.numbers(&tp, times)?;
                if times.is_empty() {
                    return Err(self.r.invalid(&tp, "needs at least one time"));
                }
                if let Some(i) = (1..times.len()).find(|&i| times[i] <= times[i - 1]) {
                    return Err(self.r.invalid(
                        &format!("{tp}[{i}]"),
                        format!(
                            "times must increase strictly: {} after {}",
                            times[i],
                            times[i - 1]
                        ),
                    ));
                }
                let values = ft.get("values").ok_or_else(|| self.r.missing(&vp, ""))?;
                let values =
                    self.value_rows(&vp, values, times.len(), k, &format!("a {kind} joint"))?;
                JointForce::Table { times, values }
            }
            Some(x) => JointForce::Constant(per_dof(&fp, x)?),
        };
        let max_force = match t.get("max_force") {
            None => Vec::new(),
            Some(x) => {
                let mp = format!("{path}.max_force");
                let m = per_dof(&mp, x)?;
                if let Some((i, v)) = m.iter().enumerate().find(|(_, v)| **v < 0.0) {
                    let key = if matches!(x, toml::Value::Array(_)) {
                        format!("{mp}[{i}]")
                    } else {
                        mp.clone()
                    };
                    return Err(self.r.out_of_range(&key, v, ">= 0 (N or N m)"));
                }
                m
            }
        };
        let a = JointActuator { force, max_force };
        a.check(k).map_err(|e| self.r.invalid(path, e))?;
        Ok(a)
    }

    /// `prescribed = { times, values }` (a spline per coordinate through the
    /// samples; `values` a list of numbers for one coordinate, else one row
    /// of `k` numbers per time) or `prescribed = { sine = { amplitude,
    /// frequency, phase, offset } }` (each a number or `k` numbers).
    fn prescribed(&self, path: &str, v: &toml::Value, k: usize) -> Result<Prescribed> {
        let toml::Value::Table(t) = v else {
            return Err(self
                .r
                .wrong_type(path, format!("expected a table, found {}", v.type_str())));
        };
        if let Some(key) = t
            .keys()
            .find(|key| !["times", "values", "sine", "bounds"].contains(&key.as_str()))
        {
            return Err(self
                .r
                .unknown_key(&format!("{path}.{key}"), "times, values, sine or bounds"));
        }
        let motion = self.prescribed_curves(path, t, k)?;
        match t.get("bounds") {
            None => Ok(motion),
            Some(b) => {
                Ok(motion.with_bounds(self.prescribed_bounds(&format!("{path}.bounds"), b, k)?))
            }
        }
    }

    /// `bounds = [lo, hi]` (every coordinate) or `[[lo, hi], …]` (one pair
    /// per coordinate): the range of the targets the learning environments
    /// command (docs/envs.md), finite with `lo < hi`.
    fn prescribed_bounds(&self, path: &str, v: &toml::Value, k: usize) -> Result<Vec<[f64; 2]>> {
        let toml::Value::Array(items) = v else {
            return Err(self.r.wrong_type(
                path,
                format!(
                    "expected [lo, hi] or one [lo, hi] per coordinate, found {}",
                    v.type_str()
                ),
            ));
        };
        let pairs: Vec<Vec<f64>> = if matches!(items.first(), Some(toml::Value::Array(_))) {
            if items.len() != k {
                return Err(self.r.inconsistent(
                    path,
                    format!("{} pairs, but the joint has {k} coordinates", items.len()),
                ));
            }
            items
                .iter()
                .enumerate()
                .map(|(i, x)| self.numbers(&format!("{path}[{i}]"), x))
                .collect::<Result<_>>()?
        } else {
            vec![self.numbers(path, v)?; k]
        };
        let mut out = Vec::with_capacity(k);
        for (i, pair) in pairs.iter().enumerate() {
            let at = if matches!(items.first(), Some(toml::Value::Array(_))) {
                format!("{path}[{i}]")
            } else {
                path.to_string()
            };
            let [lo, hi] = pair[..] else {
                return Err(self.r.invalid(
                    &at,
                    format!("expected two numbers [lo, hi], got {}", pair.len()),
                ));
            };
            if !(lo.is_finite() && hi.is_finite()) {
                return Err(self
                    .r
                    .invalid(&at, format!("[{lo}, {hi}]: bounds must be finite")));
            }
            if lo >= hi {
                return Err(self
                    .r
                    .invalid(&at, format!("lo = {lo} must be below hi = {hi}")));
            }
            out.push([lo, hi]);
        }
        Ok(out)
    }

    /// The curves of `prescribed` (see [`Self::prescribed`]).
    fn prescribed_curves(
        &self,
        path: &str,
        t: &toml::map::Map<String, toml::Value>,
        k: usize,
    ) -> Result<Prescribed> {
        if let Some(sine) = t.get("sine") {
            let sp = format!("{path}.sine");
            if t.contains_key("times") || t.contains_key("values") {
                return Err(self
                    .r
                    .inconsistent(&sp, "give either sine or times and values, not both"));
            }
            let toml::Value::Table(st) = sine else {
                return Err(self
                    .r
                    .wrong_type(&sp, format!("expected a table, found {}", sine.type_str())));
            };
            const KEYS: [&str; 4] = ["amplitude", "frequency", "phase", "offset"];
            if let Some(key) = st.keys().find(|key| !KEYS.contains(&key.as_str())) {
                return Err(self.r.unknown_key(
                    &format!("{sp}.{key}"),
                    "amplitude, frequency, phase or offset",
                ));
            }
            let mut cols = [vec![0.0; k], vec![0.0; k], vec![0.0; k], vec![0.0; k]];
            for (c, key) in KEYS.iter().enumerate() {
                let kp = format!("{sp}.{key}");
                let values = match st.get(*key) {
                    None if c < 2 => return Err(self.r.missing(&kp, " (a sinusoid)")),
                    None => continue,
                    Some(x @ toml::Value::Array(_)) => self.numbers(&kp, x)?,
                    Some(x) => vec![self.number(&kp, x)?; k],
                };
                if values.len() != k {
                    return Err(self.r.inconsistent(
                        &kp,
                        format!("{} values, but the joint has {k} coordinates", values.len()),
                    ));
                }
                if c == 1 {
                    if let Some((i, f)) = values.iter().enumerate().find(|(_, f)| **f < 0.0) {
                        return Err(self.r.out_of_range(&format!("{kp}[{i}]"), f, ">= 0"));
                    }
                }
                cols[c] = values;
            }
            return Ok(Prescribed::new(
                (0..k)
                    .map(|i| Curve::Sine {
                        amplitude: cols[0][i],
                        frequency: cols[1][i],
                        phase: cols[2][i],
                        offset: cols[3][i],
                    })
                    .collect(),
            ));
        }
        let times_path = format!("{path}.times");
        let values_path = format!("{path}.values");
        let times = t
            .get("times")
            .ok_or_else(|| self.r.missing(&times_path, " (or sine)"))?;
        let times = self.numbers(&times_path, times)?;
        let values = t
            .get("values")
            .ok_or_else(|| self.r.missing(&values_path, ""))?;
        let rows = self.value_rows(&values_path, values, times.len(), k, "the joint")?;
        Prescribed::samples(&times, &rows).map_err(|e| self.r.invalid(path, e))
    }

    /// The `values` of a joint's time table at `path`: one row of `k`
    /// numbers per time (`n_times` of them), or plain numbers when `k = 1`.
    /// `joint` names the joint in the message of a row of another length.
    fn value_rows(
        &self,
        path: &str,
        values: &toml::Value,
        n_times: usize,
        k: usize,
        joint: &str,
    ) -> Result<Vec<Vec<f64>>> {
        let toml::Value::Array(rows) = values else {
            return Err(self.r.wrong_type(
                path,
                format!("expected a list, found {}", values.type_str()),
            ));
        };
        if rows.len() != n_times {
            return Err(self
                .r
                .inconsistent(path, format!("{} values for {n_times} times", rows.len())));
        }
        if k == 1 && !matches!(rows.first(), Some(toml::Value::Array(_))) {
            return Ok(self
                .numbers(path, values)?
                .into_iter()
                .map(|x| vec![x])
                .collect());
        }
        rows.iter()
            .enumerate()
            .map(|(i, r)| {
                let rp = format!("{path}[{i}]");
                let row = self.numbers(&rp, r)?;
                if row.len() != k {
                    return Err(self.r.inconsistent(
                        &rp,
                        format!("{} values, but {joint} has {k} coordinates", row.len()),
                    ));
                }
                Ok(row)
            })
            .collect()
    }

    /// `body[j]`'s mass, inertia, centre of mass and base.
    fn body(
        &self,
        p: &str,
        name: String,
        mass: f64,
        inertia: &toml::Value,
        center_of_mass: Option<[f64; 3]>,
        base: Option<crate::raw::RawBase>,
    ) -> Result<BodySpec> {
        if mass.is_nan() || mass <= 0.0 {
            return Err(self.r.out_of_range(&format!("{p}.mass"), mass, "> 0 kg"));
        }
        let ip = format!("{p}.inertia");
        let wrong = || {
            self.r.wrong_type(
                &ip,
                "expected principal moments [Ixx, Iyy, Izz] or a 3x3 matrix [[…], […], […]]",
            )
        };
        let toml::Value::Array(rows) = inertia else {
            return Err(wrong());
        };
        let m = match rows.first() {
            Some(toml::Value::Array(_)) => {
                if rows.len() != 3 {
                    return Err(wrong());
                }
                let mut m = Matrix3::zeros();
                for (i, row) in rows.iter().enumerate() {
                    let r = self.numbers(&format!("{ip}[{i}]"), row)?;
                    if r.len() != 3 {
                        return Err(wrong());
                    }
                    for (j, x) in r.iter().enumerate() {
                        m[(i, j)] = *x;
                    }
                }
                m
            }
            _ => {
                let d = self.numbers(&ip, inertia)?;
                if d.len() != 3 {
                    return Err(wrong());
                }
                Matrix3::from_diagonal(&Vec3::new(d[0], d[1], d[2]))
            }
        };
        let mut body = BodySpec::new(name, mass, m);
        body.center_of_mass = Vec3::from(center_of_mass.unwrap_or([0.0; 3]));
        body.base = super::rods::base(base);
        body.validate().map_err(|e| {
            let key = if e.to_string().contains("inertia") {
                ip.clone()
            } else {
                p.to_owned()
            };
            self.r.invalid(&key, &e).caused_by(Box::new(e.clone()))
        })?;
        softrod_mechanics::validity::inertia_validity(&body.inertia)
            .map_err(|e| self.r.invalid(&ip, format!("body {:?}: {e}", body.name)))?;
        Ok(body)
    }

    /// `load[j]` with `body = …`: a load at the body frame's origin.
    pub(super) fn body_load(&mut self, j: usize, l: RawLoad, robot: &mut Robot) -> Result<()> {
        let p = format!("load[{j}]");
        let name = l.body.as_deref().unwrap_or_default();
        for key in ["rod", "s"] {
            let given = if key == "rod" {
                l.rod.is_some()
            } else {
                l.s.is_some()
            };
            if given {
                return Err(self.r.invalid(
                    &format!("{p}.{key}"),
                    "a load on a body takes body = \"…\", not rod or s",
                ));
            }
        }
        let Some(b) = robot.bodies.iter().position(|x| x.name == name) else {
            if robot.bodies.is_empty() {
                return Err(self.r.invalid(
                    &format!("{p}.body"),
                    format!("no body {name:?}: there are no bodies ([[body]] tables) in the scene"),
                ));
            }
            let valid: Vec<&str> = robot.bodies.iter().map(|x| x.name.as_str()).collect();
            return Err(self.r.unknown_name(&format!("{p}.body"), name, &valid));
        };
        let frame = match l.frame.as_deref() {
            None => LoadFrame::World,
            Some(f) => f
                .parse::<LoadFrame>()
                .map_err(|e| keys::mechanics(&self.r, &p, f64::NAN, e))?,
        };
        let force = l.force.unwrap_or([0.0; 3]);
        let moment = l.moment.unwrap_or([0.0; 3]);
        if force == [0.0; 3] && moment == [0.0; 3] {
            self.warn(
                &p,
                "force and moment are both zero: the load has no effect".to_owned(),
            );
        }
        robot.bodies[b].loads.push(BodyLoad {
            force: Vec3::from(force),
            moment: Vec3::from(moment),
            frame,
        });
        Ok(())
    }
}
