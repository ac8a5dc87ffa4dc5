//! From raw TOML structs to a validated [`Scene`]: one file per scene
//! section. Values are checked by the library constructors they enter
//! (kinematics, mechanics, the rod builder); this module fills in defaults,
//! checks what only the file layout has (which keys go together, names,
//! the order of `q`), maps the library's errors to key paths (`crate::keys`)
//! and collects warnings.

mod bodies;
mod body;
mod cables;
pub(crate) mod closures;
pub(crate) mod contact;
mod initial;
mod loads;
mod reference;
mod rods;
mod run;
mod start;
pub(crate) mod targets;

pub use run::MAX_QUADRATURE;

use crate::error::{Location, SceneError, Warning};
use crate::locate::{MAX_MAGNITUDE, SpanMap, map_toml_error};
use crate::overrides::{self, Override};
use serde::Deserialize;

use crate::raw::RawScene;
use crate::reporter::Reporter;
use crate::robot::Robot;
use crate::scene::{Origins, Scene};

type Result<T> = std::result::Result<T, SceneError>;

/// Parses and validates a scene; `file` names it in messages.
pub(crate) fn parse(
    text: &str,
    file: &str,
    overrides: &[Override],
) -> Result<(Scene, Vec<Warning>)> {
    // Parsed once: the spanned document gives the key paths, then it is
    // deserialized (a 10⁷-value array is not parsed twice).
    let mut doc =
        toml::de::DeTable::parse(text).map_err(|e| map_toml_error(&e, text, file, None))?;
    // `--set` values enter the document before anything reads it: they are
    // validated exactly as the file's, and messages about them say so.
    let applied = overrides::apply(&mut doc, overrides, text.len(), file)?;
    match parse_document(doc, text, file) {
        Ok((scene, warnings)) => Ok((
            scene,
            warnings.into_iter().map(|w| applied.warning(w)).collect(),
        )),
        Err(e) => Err(applied.error(e)),
    }
}

fn parse_document(
    doc: toml::Spanned<toml::de::DeTable<'_>>,
    text: &str,
    file: &str,
) -> Result<(Scene, Vec<Warning>)> {
    let spans = SpanMap::of(&doc);
    let raw = RawScene::deserialize(toml::de::Deserializer::from(doc))
        .map_err(|e| map_toml_error(&e, text, file, Some(&spans)))?;
    if let Some((path, literal, span)) = &spans.non_finite {
        return Err(SceneError::NotFinite {
            file: file.to_owned(),
            path: path.clone(),
            at: Some(Location::of_offset(text, span.start)),
            value: literal.clone(),
            source: None,
        });
    }
    let mut cx = Ctx {
        r: Reporter::new(file, text, &spans),
        warnings: Vec::new(),
    };
    if let Some((path, literal)) = &spans.absurd {
        return Err(cx.r.out_of_range(
            path,
            literal,
            format!("a magnitude of at most {MAX_MAGNITUDE:e} (no physical scene comes near it)"),
        ));
    }
    let scene = cx.scene(raw)?;
    cx.check_start(&scene)?;
    Ok((scene, cx.warnings))
}

/// Validation context: where errors point, and the warnings so far.
struct Ctx<'a> {
    r: Reporter<'a>,
    warnings: Vec<Warning>,
}

impl Ctx<'_> {
    /// A sampled drive that ends before the run does and is still moving
    /// there stops abruptly (it holds its end value): warn.
    fn warn_drives_that_stop(&mut self, robot: &Robot, run: &crate::run::Run) {
        let joints = robot
            .rod_attachments
            .iter()
            .enumerate()
            .map(|(i, a)| (format!("rod[{i}]"), a))
            .chain(
                robot
                    .body_attachments
                    .iter()
                    .enumerate()
                    .map(|(j, a)| (format!("body[{j}]"), a)),
            );
        let mut found = Vec::new();
        for (owner, a) in joints {
            let Some(p) = &a.joint.prescribed else {
                continue;
            };
            for (c, curve) in p.curves.iter().enumerate() {
                if let softrod_dynamics::Curve::Spline(sp) = curve {
                    let (_, end) = sp.span();
                    let (_, rate, _) = sp.eval(end);
                    if end < run.duration && rate.abs() > 1e-12 {
                        found.push((
                            format!("{owner}.joint.prescribed.times"),
                            format!(
                                "coordinate {c} still moves at its last time {end} s (rate {rate:e}) \
                                 and then holds still: the drive stops abruptly before \
                                 run.duration = {} s",
                                run.duration
                            ),
                        ));
                    }
                }
            }
        }
        for (path, message) in found {
            self.warn(&path, message);
        }
    }

    fn warn(&mut self, path: &str, message: String) {
        let at = self.r.at(path);
        self.warnings.push(Warning {
            path: path.to_owned(),
            at,
            message,
        });
    }

    /// `v > 0` (for the scene's own settings; library values are checked
    /// where they enter the library).
    fn positive(&self, path: &str, v: f64) -> Result<f64> {
        if v > 0.0 {
            Ok(v)
        } else {
            Err(self.r.out_of_range(path, v, "> 0"))
        }
    }

    /// A number: an integer or a float.
    fn number(&self, p: &str, v: &toml::Value) -> Result<f64> {
        match v {
            toml::Value::Integer(i) => Ok(*i as f64),
            toml::Value::Float(f) => Ok(*f),
            other => Err(self
                .r
                .wrong_type(p, format!("expected a number, found {}", other.type_str()))),
        }
    }

    /// A list of numbers.
    fn numbers(&self, p: &str, v: &toml::Value) -> Result<Vec<f64>> {
        let toml::Value::Array(a) = v else {
            return Err(self.r.wrong_type(
                p,
                format!("expected a list of numbers, found {}", v.type_str()),
            ));
        };
        a.iter()
            .enumerate()
            .map(|(k, x)| self.number(&format!("{p}[{k}]"), x))
            .collect()
    }

    fn scene(&mut self, raw: RawScene) -> Result<Scene> {
        let world = reference::world(raw.world);
        let mut raw_rods = raw.rod;
        let links: Vec<bodies::RodLink> = raw_rods
            .iter_mut()
            .map(|r| (r.parent.take(), r.at.take(), r.joint.take()))
            .collect();
        let contact_radii = raw_rods
            .iter()
            .enumerate()
            .map(|(i, r)| self.contact_radius(i, r.contact_radius))
            .collect::<Result<Vec<_>>>()?;
        let mut rods = self.rods(raw_rods)?;
        for (rod, r) in rods.iter_mut().zip(contact_radii) {
            rod.contact_radius = r;
        }
        let mut robot = self.robot(links, raw.body, &rods)?;
        robot.closures = self.closures(raw.closure, &rods, &robot)?;
        let obstacles = self.obstacles(raw.obstacle, &rods, &robot)?;
        let contact = self.contact(raw.contact)?;
        let run = self.run(raw.run)?;
        let mut origins = Origins {
            cables: vec![Vec::new(); rods.len()],
            loads: vec![Vec::new(); rods.len()],
        };
        let mut max_tension = Vec::with_capacity(raw.cable.len());
        for (j, mut c) in raw.cable.into_iter().enumerate() {
            max_tension.push(self.max_tension(j, c.max_tension.take())?);
            let i = self.cable(j, c, &mut rods)?;
            origins.cables[i].push(j);
        }
        let targets = raw
            .target
            .into_iter()
            .enumerate()
            .map(|(j, t)| self.target(j, t, &rods, &robot))
            .collect::<Result<Vec<_>>>()?;
        let mut unknown_loads = Vec::new();
        for (j, l) in raw.load.into_iter().enumerate() {
            if l.unknown == Some(true) {
                unknown_loads.push(self.unknown_load(j, l, &rods)?);
                continue;
            }
            if l.max_force.is_some() {
                return Err(self.r.inconsistent(
                    &format!("load[{j}].max_force"),
                    "only an unknown load (unknown = true) has a max_force",
                ));
            }
            if l.body.is_some() {
                self.body_load(j, l, &mut robot)?;
                continue;
            }
            let i = self.load(j, l, &mut rods)?;
            origins.loads[i].push(j);
        }
        let initial = self.initial(raw.initial, &rods, &robot)?;
        self.warn_drives_that_stop(&robot, &run);
        let reference = raw
            .reference
            .map(|r| self.reference(r, &rods, &run))
            .transpose()?;
        Ok(Scene {
            source: self.r.file().to_owned(),
            world,
            rods,
            robot,
            initial,
            run,
            reference,
            obstacles,
            contact,
            targets,
            max_tension,
            unknown_loads,
            origins,
        })
    }
}
