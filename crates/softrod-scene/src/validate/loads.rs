//! `[[load]]`: a point force and moment on a rod, into the library's
//! `PointLoad` (which checks it against the rod).

use softrod_dynamics::Rod;
use softrod_lie::Vec3;
use softrod_mechanics::{LoadFrame, PointLoad};

use super::{Ctx, Result};
use crate::keys;
use crate::raw::RawLoad;

impl Ctx<'_> {
    /// `load[j]` with `unknown = true` (IS13): a rod and `s` as a given
    /// load's, a world force (no `force`, `moment`, body or other frame),
    /// `max_force` a number (every component) or three, `≥ 0`.
    pub(super) fn unknown_load(
        &mut self,
        j: usize,
        l: RawLoad,
        rods: &[Rod],
    ) -> Result<crate::scene::UnknownLoad> {
        let p = format!("load[{j}]");
        for (key, given) in [
            ("body", l.body.is_some()),
            ("force", l.force.is_some()),
            ("moment", l.moment.is_some()),
        ] {
            if given {
                return Err(self.r.inconsistent(
                    &format!("{p}.{key}"),
                    "an unknown load (unknown = true) is a force on a rod that softrod inverse \
                     finds: it takes rod, s and max_force, not body, force or moment",
                ));
            }
        }
        if let Some(f) = l.frame.as_deref().filter(|f| *f != "world") {
            return Err(self.r.inconsistent(
                &format!("{p}.frame"),
                format!("an unknown load is a world force (frame {f:?} given)"),
            ));
        }
        let rod = l.rod.as_deref().ok_or_else(|| {
            self.r
                .missing(&format!("{p}.rod"), " (an unknown load acts on a rod)")
        })?;
        let i = self.rod_ref(&format!("{p}.rod"), rod, rods)?;
        let length = rods[i].properties.length();
        let s =
            l.s.ok_or_else(|| self.r.missing(&format!("{p}.s"), " (where along the rod)"))?;
        if !(0.0..=length).contains(&s) {
            return Err(self.r.out_of_range(
                &format!("{p}.s"),
                s,
                format!("in [0, {length}] (the rod's length)"),
            ));
        }
        let mp = format!("{p}.max_force");
        let max_force = match &l.max_force {
            None => [f64::INFINITY; 3],
            Some(v @ toml::Value::Array(_)) => {
                let m = self.numbers(&mp, v)?;
                if m.len() != 3 {
                    return Err(self.r.inconsistent(
                        &mp,
                        format!("{} values: give one bound or three (x, y, z)", m.len()),
                    ));
                }
                if let Some(k) = (0..3).find(|&k| m[k] < 0.0) {
                    return Err(self.r.out_of_range(&format!("{mp}[{k}]"), m[k], ">= 0 (N)"));
                }
                [m[0], m[1], m[2]]
            }
            Some(v) => {
                let m = self.number(&mp, v)?;
                if m < 0.0 {
                    return Err(self.r.out_of_range(&mp, m, ">= 0 (N)"));
                }
                [m; 3]
            }
        };
        Ok(crate::scene::UnknownLoad {
            load: j,
            rod: i,
            s,
            max_force,
        })
    }

    /// `load[j]`, added to the rod it names; returns that rod's index.
    pub(super) fn load(&mut self, j: usize, l: RawLoad, rods: &mut [Rod]) -> Result<usize> {
        let p = format!("load[{j}]");
        let rod = l
            .rod
            .as_deref()
            .ok_or_else(|| self.r.missing(&format!("{p}.rod"), " (or body = \"…\")"))?;
        let s =
            l.s.ok_or_else(|| self.r.missing(&format!("{p}.s"), " (where along the rod)"))?;
        let i = self.rod_ref(&format!("{p}.rod"), rod, rods)?;
        let length = rods[i].properties.length();
        let frame = match l.frame.as_deref() {
            None => LoadFrame::World,
            Some(name) => name
                .parse::<LoadFrame>()
                .map_err(|e| keys::mechanics(&self.r, &p, length, e))?,
        };
        let force = l.force.unwrap_or([0.0; 3]);
        let moment = l.moment.unwrap_or([0.0; 3]);
        let load = PointLoad {
            s,
            force: Vec3::from(force),
            moment: Vec3::from(moment),
            frame,
        };
        load.validate(rods[i].geometry.length())
            .map_err(|e| keys::mechanics(&self.r, &p, length, e))?;
        if force == [0.0; 3] && moment == [0.0; 3] {
            self.warn(
                &p,
                "force and moment are both zero: the load has no effect".to_owned(),
            );
        }
        rods[i].point_loads.push(load);
        Ok(i)
    }
}
