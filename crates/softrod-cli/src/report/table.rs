//! The rows of a study and their tables: Pareto marks, Markdown, CSV.

use std::fmt::Write as _;

use super::runs::Outcome;

/// A row of a study.
pub(super) struct Row {
    pub(super) study: &'static str,
    pub(super) integrator: String,
    pub(super) setting: String,
    pub(super) pieces: usize,
    pub(super) quadrature: usize,
    pub(super) result: Result<Outcome, String>,
    pub(super) err_final: f64,
    pub(super) err_max: f64,
    pub(super) err_analytic: Option<f64>,
    pub(super) pareto: bool,
}

impl Row {
    fn name(&self) -> String {
        format!(
            "{} {} | pieces {} | quadrature {}",
            self.integrator, self.setting, self.pieces, self.quadrature
        )
    }
}

/// Marks the rows on the wall–error Pareto front (no other row is both
/// faster and more accurate), by `err_max`.
pub(super) fn mark_pareto(rows: &mut [Row]) {
    let mut idx: Vec<usize> = (0..rows.len())
        .filter(|&i| rows[i].result.is_ok() && rows[i].err_max.is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        let (wa, wb) = (wall(&rows[a]), wall(&rows[b]));
        wa.total_cmp(&wb)
            .then(rows[a].err_max.total_cmp(&rows[b].err_max))
    });
    let mut best = f64::INFINITY;
    for i in idx {
        if rows[i].err_max < best {
            best = rows[i].err_max;
            rows[i].pareto = true;
        }
    }
}

pub(super) fn wall(r: &Row) -> f64 {
    r.result.as_ref().map_or(f64::NAN, |o| o.wall)
}

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

pub(super) fn csv_rows(csv: &mut String, rows: &[Row]) {
    for r in rows {
        let mut f: Vec<String> = vec![
            r.name(),
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
