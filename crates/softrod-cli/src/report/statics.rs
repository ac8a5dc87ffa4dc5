//! The statics report's Markdown (`report.md`) and files, from the
//! facade's [`StaticsStudy`].

use std::fmt::Write as _;
use std::path::Path;

use softrod::study::{StaticsStudy, dist};
use softrod_scene::Scene;

use super::table::{CSV_HEADER, csv_rows, md_table, sci};
use super::{ReportOptions, chart, command, write};
use crate::common::CliError;

/// Writes `report.csv` and `report.svg`; returns `report.md`.
pub(super) fn statics_report(
    scene: &Scene,
    dir: &Path,
    o: ReportOptions,
    r: &StaticsStudy,
) -> Result<String, CliError> {
    let (rows, fine, fine_k, analytic, repeats, n0) =
        (&r.rows, &r.fine, r.fine_k, &r.analytic, r.repeats, r.pieces);
    let mut csv = String::from(CSV_HEADER);
    csv_rows(&mut csv, rows);
    write(dir, "report.csv", &csv)?;
    chart(
        &dir.join("report.svg"),
        &format!("statics work-precision: {}", scene.source),
        rows,
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
    md.push_str(&md_table(rows, false));
    md.push_str("\nPlot: `report.svg`. Data: `report.csv`.\n");
    Ok(md)
}
