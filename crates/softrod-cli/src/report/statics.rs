//! The statics report: pieces and quadrature against `[reference] tip`, or
//! against pieces x8, quadrature 6.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use softrod_dynamics::{Data, StaticsOptions, statics};
use softrod_integrate::Stats;
use softrod_scene::Scene;

use super::chart::work_precision_svg;
use super::runs::{Outcome, build_variant, dist, median, pieces};
use super::table::{CSV_HEADER, Row, csv_rows, mark_pareto, md_table, sci};
use super::{ReportOptions, command, write};
use softrod::record::WorldPoses;

use crate::common::{CliError, failed};

pub(super) fn statics_report(
    scene: &Scene,
    dir: &Path,
    o: ReportOptions,
) -> Result<String, CliError> {
    let say = |m: String| {
        if !o.quiet {
            eprintln!("softrod report: {m}");
        }
    };
    let repeats = if o.quick { 1 } else { 3 };
    let n0 = pieces(scene);
    let solve = |k: usize, q: usize| -> Result<(Outcome, usize), String> {
        let built = build_variant(scene, k, q).map_err(|e| e.to_string())?;
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
            .map_err(|e| e.to_string())?;
            walls.push(start.elapsed().as_secs_f64());
            result = Some(r);
        }
        let r = result.expect("one repeat");
        let mut poser = WorldPoses::new(&built.model);
        poser
            .update(&built.model, 0.0, r.q.as_slice())
            .map_err(|e| e.to_string())?;
        let p = poser.tip(0).translation;
        let stats = Stats {
            steps: r.iterations,
            ..Stats::default()
        };
        Ok((
            Outcome {
                tips: vec![[p[0], p[1], p[2]]],
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
    say(format!(
        "reference: statics at pieces x{fine_k}, quadrature 6"
    ));
    let (fine, _) = solve(fine_k, 6).map_err(|e| failed(format!("fine reference: {e}")))?;
    let reference = analytic.as_ref().map_or(fine.tips[0], |a| a.0);
    let mut rows = Vec::new();
    for k in [1usize, 2, 4] {
        for q in [2usize, 4, 6] {
            say(format!("statics: {} pieces, quadrature {q}", n0 * k));
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
    let mut csv = String::from(CSV_HEADER);
    csv_rows(&mut csv, &rows);
    write(dir, "report.csv", &csv)?;
    work_precision_svg(
        &dir.join("report.svg"),
        &format!("statics work-precision: {}", scene.source),
        &rows,
        |r| format!("quadrature {}", r.quadrature),
    )?;
    let mut md = String::new();
    let _ = writeln!(md, "# softrod report (statics): {}\n", scene.source);
    let _ = writeln!(
        md,
        "Regenerate with `{}` (release build). {repeats} repeat(s), wall time = median. Error = \
         distance of the first rod's tip from the reference; `steps` = Newton iterations.\n",
        command(scene, o)
    );
    match &analytic {
        Some((tip, note)) => {
            let _ = writeln!(
                md,
                "**Reference**: the scene's `[reference] tip` = {tip:?} m{}. pieces x{fine_k} \
                 ({} pieces), quadrature 6 is {} m from it (the reference's own accuracy and the \
                 model's, e.g. linear theory).\n",
                note.as_ref().map_or(String::new(), |n| format!(" ({n})")),
                n0 * fine_k,
                sci(dist(&fine.tips[0], tip))
            );
        }
        None => {
            let _ = writeln!(
                md,
                "**Reference**: statics at pieces x{fine_k} ({} pieces), quadrature 6 (the scene \
                 has no `[reference] tip`).\n",
                n0 * fine_k
            );
        }
    }
    md.push_str(&md_table(&rows, false));
    md.push_str("\nPlot: `report.svg`. Data: `report.csv`.\n");
    Ok(md)
}
