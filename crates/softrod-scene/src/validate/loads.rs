//! `[[load]]`: a point force and moment on a rod, into the library's
//! `PointLoad` (which checks it against the rod).

use softrod_dynamics::Rod;
use softrod_lie::Vec3;
use softrod_mechanics::{LoadFrame, PointLoad};

use super::{Ctx, Result};
use crate::keys;
use crate::raw::RawLoad;

impl Ctx<'_> {
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
