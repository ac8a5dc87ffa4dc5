//! `[world]` and `[reference]`.

use softrod_dynamics::Rod;

use super::{Ctx, Result};
use crate::raw::{RawReference, RawWorld};
use crate::run::Run;
use crate::scene::{Reference, World};

/// `[world]`: gravity, default none (its finiteness is checked with every
/// number of the file, and again when it enters the model).
pub(super) fn world(raw: Option<RawWorld>) -> World {
    World {
        gravity: raw.and_then(|w| w.gravity).unwrap_or([0.0; 3]),
    }
}

impl Ctx<'_> {
    pub(super) fn reference(
        &mut self,
        r: RawReference,
        rods: &[Rod],
        run: &Run,
    ) -> Result<Reference> {
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
            return Err(self.r.out_of_range(
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

    /// Index of the rod called `name`, or an unknown-rod error at `path`.
    pub(super) fn rod_ref(&self, path: &str, name: &str, rods: &[Rod]) -> Result<usize> {
        rods.iter().position(|r| r.name == name).ok_or_else(|| {
            self.r
                .unknown_rod(path, name, rods.iter().map(|r| r.name.clone()).collect())
        })
    }
}
