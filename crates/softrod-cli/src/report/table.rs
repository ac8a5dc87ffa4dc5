//! The rows of a study as tables: Markdown and CSV.

use std::fmt::Write as _;

use softrod::study::Row;

pub(super) fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3e}")
    } else {
        String::new()
    }
}

pub(super) fn md_table(rows: &[Row], analytic: bool) -> String {
    let mut md = String::from(
        "| integrator | setting | pieces | quadrature | wall s | error final m | error max m |",
    );
    if analytic {
        md.push_str(" error vs analytic m |");
    }
    md.push_str(" steps | rhs evaluations | Pareto | status |\n|---|---|---|---|---|---|---|");
    if analytic {
        md.push_str("---|");
    }
    md.push_str("---|---|---|---|\n");
    for r in rows {
        let _ = write!(
            md,
            "| {} | {} | {} | {} |",
            r.integrator, r.setting, r.pieces, r.quadrature
        );
        match &r.result {
            Ok(o) => {
                let _ = write!(
                    md,
                    " {:.4} | {} | {} |",
                    o.wall,
                    sci(r.err_final),
                    sci(r.err_max)
                );
                if analytic {
                    let _ = write!(md, " {} |", r.err_analytic.map_or(String::new(), sci));
                }
                let _ = writeln!(
                    md,
                    " {} | {} | {} | ok |",
                    o.stats.steps,
                    o.stats.rhs_evaluations,
                    if r.pareto { "★" } else { "" }
                );
            }
            Err(e) => {
                md.push_str(" | | |");
                if analytic {
                    md.push_str(" |");
                }
                let _ = writeln!(md, " | | | failed: {} |", e.replace('|', "/"));
            }
        }
    }
    md
}

/// The row's configuration as one text (the CSV's first column).
fn name(r: &Row) -> String {
    format!(
        "{} {} | pieces {} | quadrature {}",
        r.integrator, r.setting, r.pieces, r.quadrature
    )
}

pub(super) fn csv_rows(csv: &mut String, rows: &[Row]) {
    for r in rows {
        let mut f: Vec<String> = vec![
            name(r),
            r.study.to_string(),
            r.integrator.to_string(),
            r.setting.to_string(),
            r.pieces.to_string(),
            r.quadrature.to_string(),
        ];
        match &r.result {
            Ok(o) => f.extend([
                o.wall.to_string(),
                format!("{:e}", r.err_final),
                format!("{:e}", r.err_max),
                r.err_analytic.map_or(String::new(), |e| format!("{e:e}")),
                o.stats.steps.to_string(),
                o.stats.rejected_steps.to_string(),
                o.stats.rhs_evaluations.to_string(),
                r.pareto.to_string(),
                "ok".into(),
            ]),
            Err(e) => {
                f.extend(std::iter::repeat_n(String::new(), 7));
                f.extend(["false".into(), format!("failed: {e}")]);
            }
        }
        csv.push_str(&crate::outputs::csv_line(&f));
    }
}

pub(super) const CSV_HEADER: &str = "configuration,study,integrator,setting,pieces,quadrature,wall_seconds,error_final_m,error_max_m,error_analytic_m,steps,rejected_steps,rhs_evaluations,pareto,status\n";
