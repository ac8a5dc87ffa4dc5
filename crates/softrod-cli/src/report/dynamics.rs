//! The dynamics report's Markdown (`report.md`) and files, from the
//! facade's [`DynamicsStudy`].

use std::fmt::Write as _;
use std::path::Path;

use softrod::GENERALIZED_ALPHA_RHO_INF;
use softrod::study::{DynamicsStudy, N_COMPARE, dist};
use softrod_scene::Scene;

use super::table::{CSV_HEADER, csv_rows, md_table, sci};
use super::{ReportOptions, chart, command, write};
use crate::common::CliError;

/// `report.csv`, `report.svg` and `report_spatial.svg`.
pub(super) fn write_outputs(scene: &Scene, dir: &Path, r: &DynamicsStudy) -> Result<(), CliError> {
    let (n0, q0) = (r.pieces, r.quadrature);
    let (spatial, temporal) = (&r.spatial.rows, &r.temporal);
    let mut csv = String::from(CSV_HEADER);
    csv_rows(&mut csv, spatial);
    csv_rows(&mut csv, temporal);
    write(dir, "report.csv", &csv)?;
    chart(
        &dir.join("report.svg"),
        &format!(
            "temporal work-precision: {} ({n0} pieces, quadrature {q0})",
            scene.source
        ),
        temporal,
        |r| r.integrator.clone(),
    )?;
    chart(
        &dir.join("report_spatial.svg"),
        &format!(
            "spatial work-precision: {} (pieces x1, x2, x4)",
            scene.source
        ),
        spatial,
        |r| format!("quadrature {}", r.quadrature),
    )
}

/// `report.md`.
pub(super) fn markdown(scene: &Scene, o: ReportOptions, r: &DynamicsStudy) -> String {
    let (n0, q0, budget, repeats) = (r.pieces, r.quadrature, r.budget, r.repeats);
    let d = scene.run.duration;
    let (temporal, spatial, spatial_ref) = (&r.temporal, &r.spatial.rows, &r.spatial.reference);
    let (tight, temporal_ref, notes) = (&r.tight, &r.temporal_ref, &r.notes);
    let (observed_order, sp_dt, sp_temporal) =
        (r.spatial.observed_order, r.spatial.dt, r.sp_temporal);
    let (analytic, t_analytic) = (&r.analytic, r.t_analytic);
    let scene_spatial = spatial
        .iter()
        .find(|r| r.pieces == n0 && r.quadrature == q0)
        .map_or(f64::NAN, |r| r.err_max);
    let mut md = String::new();
    let _ = writeln!(md, "# softrod report: {}\n", scene.source);
    let _ = writeln!(
        md,
        "Regenerate with `{}` (release build). {} repeat(s) per configuration, wall time = median; \
         errors are distances of the first rod's tip: at the final time t = {d} s (`error final`) and \
         the largest over {} evenly spaced times (`error max`). Runs over a wall-time budget of {budget} s \
         are stopped and listed as failed.\n",
        command(scene, o),
        repeats,
        N_COMPARE + 1
    );
    md.push_str("## References\n\n");
    let _ = writeln!(
        md,
        "- **Temporal reference** (for the integrator study): {}, at the scene's {n0} pieces and \
         quadrature {q0}: {:.3} s wall, {} steps.",
        tight.text, temporal_ref.wall, temporal_ref.stats.steps
    );
    for n in notes {
        let _ = writeln!(md, "  (Tried first: {n}.)");
    }
    let _ = writeln!(
        md,
        "- **Spatial reference** (for the pieces/quadrature study): Richardson extrapolation \
         `x4 + (x4 − x2)/3` of the pieces x2 ({} pieces) and x4 ({} pieces) runs at quadrature 6, \
         order 2 (observed order from x1, x2, x4: {observed_order:.2}). The spatial runs use \
         generalized-α (ρ∞ = {GENERALIZED_ALPHA_RHO_INF}) at the fixed step {sp_dt:.3e} s; its \
         temporal error at the scene's pieces is {} m (max over the run, against the temporal \
         reference), which bounds how small a spatial error this study resolves.",
        n0 * 2,
        n0 * 4,
        sci(sp_temporal)
    );
    let _ = writeln!(
        md,
        "- The scene's pieces and quadrature are {} m (max over the run) from the spatial \
         reference: the scene's spatial error.",
        sci(scene_spatial)
    );
    if let (Some((tip, t, note)), Some(i)) = (analytic, t_analytic) {
        let _ = writeln!(
            md,
            "- **Analytic reference** (`[reference]`): tip {tip:?} m at t = {t} s{}; the spatial \
             reference is {} m from it, the temporal reference {} m.",
            note.as_ref().map_or(String::new(), |n| format!(" ({n})")),
            sci(dist(&spatial_ref[i], tip)),
            sci(dist(&temporal_ref.tips[i], tip))
        );
    }
    md.push_str(
        "\n## Spatial error: pieces and quadrature\n\nEach row against the spatial reference. \
         Plot: `report_spatial.svg` (one curve per quadrature order).\n\n",
    );
    md.push_str(&md_table(spatial, analytic.is_some()));
    md.push_str(
        "\n## Temporal error: integrators and tolerances\n\nThe scene's pieces and quadrature, each row \
         against the temporal reference (same model), so only the integrator's error is measured. \
         Plot: `report.svg` (log-log work-precision, one curve per integrator, Pareto front dashed \
         and ringed).\n\n",
    );
    md.push_str(&md_table(temporal, analytic.is_some()));
    md.push_str("\n## Cheapest setting per error target\n\n");
    let _ = writeln!(
        md,
        "The scene's own spatial error ({n0} pieces, quadrature {q0}) is {} m: integrator errors far \
         below it buy nothing.\n",
        sci(scene_spatial)
    );
    md.push_str("| target (max tip error) m | cheapest integrator setting | wall s | its error m |\n|---|---|---|---|\n");
    let mut targets = vec![1e-3, 1e-4, 1e-5, 1e-6];
    if scene_spatial.is_finite() {
        targets.insert(0, scene_spatial / 10.0);
    }
    for tgt in targets {
        let best = temporal
            .iter()
            .filter(|r| r.result.is_ok() && r.err_max <= tgt)
            .min_by(|a, b| a.wall().total_cmp(&b.wall()));
        match best {
            Some(r) => {
                let _ = writeln!(
                    md,
                    "| {} | {} {} | {:.4} | {} |",
                    sci(tgt),
                    r.integrator,
                    r.setting,
                    r.wall(),
                    sci(r.err_max)
                );
            }
            None => {
                let _ = writeln!(md, "| {} | none reached it | | |", sci(tgt));
            }
        }
    }
    md.push_str("\nData: `report.csv` (both studies, column `study`).\n");
    md
}
