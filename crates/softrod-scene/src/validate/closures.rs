//! `[[closure]]` (scene-format.md, "Bodies, joints, bases and closures";
//! the optional `name` is an extension, docs/scene-format-extensions.md):
//! into the library's [`Closure`]s, every problem naming its key path.

use serde::Deserialize;
use softrod_dynamics::{Closure, ClosureFrame, ClosureKind, Rod};
use softrod_lie::Vec3;

use super::{Ctx, Result};
use crate::raw::RawBase;
use crate::robot::Robot;

/// `[[closure]]`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawClosure {
    pub name: Option<String>,
    #[serde(rename = "type")]
    pub kind: Option<String>,
    pub a: Option<RawClosureFrame>,
    pub b: Option<RawClosureFrame>,
    pub axis: Option<[f64; 3]>,
}

/// `a = { element, at, base }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawClosureFrame {
    pub element: Option<String>,
    pub at: Option<f64>,
    pub base: Option<RawBase>,
}

const KINDS: [&str; 3] = ["weld", "ball", "slider"];

impl Ctx<'_> {
    /// The closures, checked: type known, both frames on a rod (with `at`
    /// in `[0, L]`), a body or the world, base rotations orthonormal, a
    /// slider's axis nonzero (only sliders have one), names unique.
    pub(super) fn closures(
        &mut self,
        raw: Vec<RawClosure>,
        rods: &[Rod],
        robot: &Robot,
    ) -> Result<Vec<Closure>> {
        let mut out: Vec<Closure> = Vec::with_capacity(raw.len());
        for (i, c) in raw.into_iter().enumerate() {
            let p = format!("closure[{i}]");
            let name = match c.name {
                Some(n) if n.trim().is_empty() => {
                    return Err(self
                        .r
                        .invalid(&format!("{p}.name"), "closure name must not be empty"));
                }
                Some(n) => n,
                None => p.clone(),
            };
            if let Some(k) = out.iter().position(|o| o.name == name) {
                return Err(self.r.invalid(
                    &format!("{p}.name"),
                    format!("duplicate closure name {name:?} (also closure[{k}])"),
                ));
            }
            let kind_name = c.kind.ok_or_else(|| {
                self.r
                    .missing(&format!("{p}.type"), " (\"weld\", \"ball\" or \"slider\")")
            })?;
            let kind = match kind_name.as_str() {
                "weld" => ClosureKind::Weld,
                "ball" => ClosureKind::Ball,
                "slider" => {
                    let ap = format!("{p}.axis");
                    let a = c.axis.ok_or_else(|| {
                        self.r
                            .missing(&ap, " (a slider: the line's direction in b's frame)")
                    })?;
                    let v = Vec3::from(a);
                    if v.norm() < 1e-12 {
                        return Err(self
                            .r
                            .invalid(&ap, format!("{a:?} is not a direction (zero vector)")));
                    }
                    ClosureKind::Slider { axis: v }
                }
                other => return Err(self.r.unknown_name(&format!("{p}.type"), other, &KINDS)),
            };
            if c.axis.is_some() && !matches!(kind, ClosureKind::Slider { .. }) {
                return Err(self.r.invalid(
                    &format!("{p}.axis"),
                    format!("a {kind_name} closure has no axis (only slider)"),
                ));
            }
            let a = self.closure_frame(&format!("{p}.a"), c.a, rods, robot)?;
            let b = self.closure_frame(&format!("{p}.b"), c.b, rods, robot)?;
            if a.element == "world" && b.element == "world" {
                return Err(self.r.invalid(
                    &format!("{p}.b.element"),
                    "both frames are the world: nothing to hold",
                ));
            }
            out.push(Closure::new(name, kind, a, b));
        }
        Ok(out)
    }

    fn closure_frame(
        &mut self,
        p: &str,
        raw: Option<RawClosureFrame>,
        rods: &[Rod],
        robot: &Robot,
    ) -> Result<ClosureFrame> {
        let f = raw.ok_or_else(|| {
            self.r.missing(
                p,
                " (a frame: { element = \"rod, body or world\", at = s, base = {…} })",
            )
        })?;
        let ep = format!("{p}.element");
        let element = f
            .element
            .ok_or_else(|| self.r.missing(&ep, " (a rod, a body or \"world\")"))?;
        let rod = rods.iter().find(|r| r.name == element);
        let is_body = robot.bodies.iter().any(|b| b.name == element);
        if element != "world" && rod.is_none() && !is_body {
            let mut valid: Vec<&str> = rods
                .iter()
                .map(|r| r.name.as_str())
                .chain(robot.bodies.iter().map(|b| b.name.as_str()))
                .collect();
            valid.push("world");
            return Err(self.r.unknown_name(&ep, &element, &valid));
        }
        if let Some(s) = f.at {
            match rod {
                Some(r) => {
                    let len = r.geometry.length();
                    if !(0.0..=len).contains(&s) {
                        return Err(self.r.out_of_range(
                            &format!("{p}.at"),
                            s,
                            format!("in [0, {len}] (the length of rod {element:?})"),
                        ));
                    }
                }
                None => self.warn(
                    &format!("{p}.at"),
                    format!("at is not used: {element:?} is not a rod"),
                ),
            }
        }
        let base = super::rods::base(f.base);
        let err = base.orthonormality_error();
        if err > 1e-9 || base.rotation.determinant() < 0.0 {
            return Err(self.r.invalid(
                &format!("{p}.base.rotation"),
                format!("not a rotation matrix (‖RᵀR − I‖ = {err:.2e}, det must be +1)"),
            ));
        }
        Ok(ClosureFrame::on(element, f.at, base))
    }
}
