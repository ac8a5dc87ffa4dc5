//! The statics study: pieces and quadrature against `[reference] tip`, or
//! against pieces ×8, quadrature 6.

use std::time::Instant;

use softrod_dynamics::{Data, StaticsOptions, statics};
use softrod_integrate::Stats;
use softrod_scene::Scene;

use super::runs::{build_variant, dist, median, pieces, tip};
use super::{Outcome, Row, StudyOptions, mark_pareto};
use crate::error::{Error, Result};
use crate::record::WorldPoses;

/// What [`statics_study`] measured.
#[derive(Clone, Debug)]
pub struct StaticsStudy {
    /// Pieces ×{1, 2, 4}, quadrature {2, 4, 6}; errors against the
    /// reference (`analytic` if any, else `fine`).
    pub rows: Vec<Row>,
    /// The fine run (pieces ×`fine_k`, quadrature 6).
    pub fine: Outcome,
    /// Its piece multiple.
    pub fine_k: usize,
    /// The scene's `[reference] tip` \[m\] and note, if any.
    pub analytic: Option<([f64; 3], Option<String>)>,
    /// Repeats per configuration.
    pub repeats: usize,
    /// The scene's pieces (all rods).
    pub pieces: usize,
}

/// Runs the statics study of `scene` (see the [module docs](super)),
/// telling `progress` what it starts.
pub fn statics_study(
    scene: &Scene,
    o: StudyOptions,
    progress: &dyn Fn(&str),
) -> Result<StaticsStudy> {
    let repeats = o.repeats();
    let n0 = pieces(scene);
    let solve = |k: usize, q: usize| -> std::result::Result<(Outcome, usize), String> {
        let built = build_variant(scene, k, q).map_err(|e| e.report())?;
        let mut walls = Vec::new();
        let mut result = None;
        for _ in 0..repeats {
            let mut data = Data::new(&built.model);
            let start = Instant::now();
            let r = statics(
                &built.model,
                &mut data,
                built.q0.as_slice(),
                &StaticsOptions::default(),
            )
            .map_err(|e| crate::error::report(&e))?;
            walls.push(start.elapsed().as_secs_f64());
            result = Some(r);
        }
        let r = result.expect("one repeat");
        let mut poses = WorldPoses::new(&built.model);
        let p = tip(&mut poses, &built, 0.0, r.q.as_slice()).map_err(|e| e.report())?;
        let stats = Stats {
            steps: r.iterations,
            ..Stats::default()
        };
        Ok((
            Outcome {
                tips: vec![p],
                stats,
                wall: median(walls),
            },
            r.load_steps,
        ))
    };
    let analytic = scene
        .reference
        .as_ref()
        .filter(|r| r.rod_index == 0)
        .and_then(|r| r.tip.map(|t| (t, r.note.clone())));
    let fine_k = 8;
    progress(&format!(
        "reference: statics at pieces x{fine_k}, quadrature 6"
    ));
    let (fine, _) = solve(fine_k, 6).map_err(|e| Error::Study(format!("fine reference: {e}")))?;
    let reference = analytic.as_ref().map_or(fine.tips[0], |a| a.0);
    let mut rows = Vec::new();
    for k in [1usize, 2, 4] {
        for q in [2usize, 4, 6] {
            progress(&format!("statics: {} pieces, quadrature {q}", n0 * k));
            let res = solve(k, q);
            let (err, ea) = match &res {
                Ok((out, _)) => (
                    dist(&out.tips[0], &reference),
                    analytic.as_ref().map(|a| dist(&out.tips[0], &a.0)),
                ),
                Err(_) => (f64::NAN, None),
            };
            rows.push(Row {
                study: "statics",
                integrator: "newton".into(),
                setting: res
                    .as_ref()
                    .map_or(String::new(), |(_, ls)| format!("{ls} load step(s)")),
                pieces: n0 * k,
                quadrature: q,
                result: res.map(|(o, _)| o),
                err_final: err,
                err_max: err,
                err_analytic: ea,
                pareto: false,
            });
        }
    }
    mark_pareto(&mut rows);
    Ok(StaticsStudy {
        rows,
        fine,
        fine_k,
        analytic,
        repeats,
        pieces: n0,
    })
}
