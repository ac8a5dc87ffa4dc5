//! `[[cable]]`: the rod it runs on, its routing, span and tension, into the
//! library's `Cable` (which checks them against the rod).

use softrod_dynamics::Rod;
use softrod_mechanics::{Cable, Routing, Span, Tension};

use super::{Ctx, Result};
use crate::keys;
use crate::locate::join;
use crate::raw::RawCable;

impl Ctx<'_> {
    /// `cable[j]`, added to the rod it names; returns that rod's index.
    pub(super) fn cable(&mut self, j: usize, c: RawCable, rods: &mut [Rod]) -> Result<usize> {
        let p = format!("cable[{j}]");
        let path = |k: &str| format!("{p}.{k}");
        let i = self.rod_ref(&path("rod"), &c.rod, rods)?;
        let length = rods[i].properties.length();
        let span = match (c.from, c.to) {
            (None, None) => Span::Whole,
            (from, to) => Span::Between {
                from: from.unwrap_or(0.0),
                to: to.unwrap_or(length),
            },
        };
        let routing = match (c.offset, c.path) {
            (Some([y, z]), None) => Routing::Offset { y, z },
            (None, Some(pts)) => Routing::Path(pts),
            (None, None) => return Err(self.r.missing(&path("offset"), " (or path)")),
            (Some(_), Some(_)) => {
                return Err(self
                    .r
                    .invalid(&path("path"), "give either offset or path, not both"));
            }
        };
        let tension = self.tension(&path("tension"), &c.tension)?;
        let cable = Cable {
            routing,
            tension,
            span,
            friction: c.friction.unwrap_or(0.0),
        };
        cable
            .validate(rods[i].geometry.length())
            .map_err(|e| keys::mechanics(&self.r, &p, length, e))?;
        self.warn_routing(&p, &cable, &rods[i]);
        rods[i].cables.push(cable);
        Ok(i)
    }

    /// A number (N) or a table `{ times = [...], values = [...] }`.
    fn tension(&self, p: &str, v: &toml::Value) -> Result<Tension> {
        let toml::Value::Table(t) = v else {
            if !matches!(v, toml::Value::Integer(_) | toml::Value::Float(_)) {
                return Err(self.r.wrong_type(
                    p,
                    format!(
                        "expected a number (N) or a table {{ times = [...], values = [...] }}, \
                         found {}",
                        v.type_str()
                    ),
                ));
            }
            return Ok(Tension::Constant(self.number(p, v)?));
        };
        if let Some(k) = t.keys().find(|k| *k != "times" && *k != "values") {
            return Err(self.r.unknown_key(&join(p, k), "`times`, `values`"));
        }
        let list = |key: &str| {
            let kp = join(p, key);
            match t.get(key) {
                Some(x) => self.numbers(&kp, x),
                None => Err(self.r.missing(&kp, "")),
            }
        };
        Ok(Tension::Table {
            times: list("times")?,
            values: list("values")?,
        })
    }

    /// Where the cable runs relative to the section: outside it (legal with
    /// spacer disks, but often a unit slip), or on the centerline.
    fn warn_routing(&mut self, p: &str, cable: &Cable, rod: &Rod) {
        let (section, length) = (rod.properties.section(), rod.properties.length());
        let (from, to) = cable.bounds(length);
        let mut probe = vec![from, to];
        let key = match &cable.routing {
            Routing::Offset { .. } => join(p, "offset"),
            Routing::Path(pts) => {
                probe.extend(pts.iter().map(|q| q[0]).filter(|&s| s > from && s < to));
                join(p, "path")
            }
        };
        let at = |s: f64| {
            let d = cable.routing.offset(s).0;
            (d[1], d[2])
        };
        if let Some(&s) = probe.iter().find(|&&s| {
            let (y, z) = at(s);
            !section.contains(s / length, y, z)
        }) {
            let (y, z) = at(s);
            self.warn(
                &key,
                format!(
                    "cable offset (y, z) = ({y}, {z}) m at s = {s} m lies outside the \
                     cross-section (outer radius {} m); legal (spacer disks), but check the units",
                    section.half_size(s / length)
                ),
            );
        }
        if probe.iter().all(|&s| at(s) == (0.0, 0.0)) {
            self.warn(
                &key,
                "cable runs along the centerline: it only compresses the rod".to_owned(),
            );
        }
    }
}
