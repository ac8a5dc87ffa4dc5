//! `softrod report`: the work–precision study of a scene
//! ([`softrod::study`]) written as `report.md`, `report.csv` and the
//! charts (drawn by `softrod-viz`). This module only formats: every
//! number comes from the facade's study.

mod dynamics;
mod statics;
mod table;

use std::path::{Path, PathBuf};

use softrod::study::{Row, StudyOptions, dynamics_study, statics_study};
use softrod_scene::{Mode, Scene};
use softrod_viz::plot::{WorkPrecisionPoint, work_precision};

use crate::common::{CliError, failed, load, out_dir};

/// How `softrod report` runs.
#[derive(Clone, Copy, Debug)]
pub struct ReportOptions {
    /// One repeat instead of three, and smaller time budgets.
    pub quick: bool,
    /// No progress messages, no table on stdout.
    pub quiet: bool,
}

pub(super) fn write(dir: &Path, name: &str, text: &str) -> Result<(), CliError> {
    let p = dir.join(name);
    std::fs::write(&p, text).map_err(|e| failed(format!("cannot write {}: {e}", p.display())))
}

/// The log-log work-precision chart of `rows` at `path`, one curve per
/// `key`, the Pareto front marked.
pub(super) fn chart(
    path: &Path,
    title: &str,
    rows: &[Row],
    key: impl Fn(&Row) -> String,
) -> Result<(), CliError> {
    let points: Vec<WorkPrecisionPoint> = rows
        .iter()
        .filter(|r| r.result.is_ok())
        .map(|r| WorkPrecisionPoint {
            group: key(r),
            wall: r.wall(),
            error: r.err_max,
            pareto: r.pareto,
        })
        .collect();
    work_precision(title, &points)
        .and_then(|f| f.write(path))
        .map_err(|e| failed(format!("plot {}: {}", path.display(), softrod::report(&e))))
}

pub fn report(path: &Path, out: Option<PathBuf>, o: ReportOptions) -> Result<(), CliError> {
    let l = load(path)?;
    let dir = out_dir(path, out);
    crate::outputs::prepare_out_dir(&dir)?;
    let progress = |m: &str| {
        if !o.quiet {
            eprintln!("softrod report: {m}");
        }
    };
    let options = StudyOptions { quick: o.quick };
    let scene = &l.scene;
    let md = match scene.run.mode {
        Mode::Statics => {
            let study = statics_study(scene, options, &progress)?;
            statics::statics_report(scene, &dir, o, &study)?
        }
        Mode::Dynamics => {
            let study = dynamics_study(scene, options, &progress)?;
            dynamics::write_outputs(scene, &dir, &study)?;
            dynamics::markdown(scene, o, &study)
        }
    };
    write(&dir, "report.md", &md)?;
    if !o.quiet {
        print!("{md}");
    }
    Ok(())
}

/// The command that regenerates a report (stated in it).
pub(super) fn command(scene: &Scene, o: ReportOptions) -> String {
    format!(
        "softrod report {}{}",
        scene.source,
        if o.quick { " --quick" } else { "" }
    )
}
