//! `summary.json`: what a run is and how far it got, rewritten atomically
//! as it goes, so that even a killed run says where it stopped.

use std::path::{Path, PathBuf};

use softrod::EnergyBalance;
use softrod::integrate::Stats;
use softrod_scene::Scene;

use crate::common::{CliError, failed};

/// `summary.json`: the run's fixed facts and, at each write, its progress.
/// Written atomically (a temporary file renamed over it), so a reader never
/// sees half a file, even of a killed run.
#[derive(Clone)]
pub struct Summary {
    path: PathBuf,
    fixed: serde_json::Map<String, serde_json::Value>,
}

impl Summary {
    pub fn new(
        dir: &Path,
        scene: &Scene,
        (q_names, prescribed_names): (Vec<String>, Vec<String>),
        rows_expected: usize,
    ) -> Self {
        let mut v = serde_json::json!({
            "pid": std::process::id(),
            "integrator": scene.run.integrator.name(),
            "duration": scene.run.duration,
            "output_rows_expected": rows_expected,
            "n_dof": scene.n_dof(),
            "q_names": q_names,
        });
        if !prescribed_names.is_empty() {
            v["prescribed_names"] = serde_json::json!(prescribed_names);
        }
        let serde_json::Value::Object(fixed) = v else {
            unreachable!("a JSON object literal")
        };
        Self {
            path: dir.join("summary.json"),
            fixed,
        }
    }

    /// Adds the run's energy balance (docs/scene-format-extensions.md,
    /// `[run] energy_tolerance`) and what the run's watch warned about.
    pub fn add_watch(&mut self, b: &EnergyBalance, warnings: &[String]) {
        for (key, value) in [
            ("energy_error", b.error),
            ("energy_error_relative", b.relative),
            ("energy_scale", b.scale),
            ("energy_change", b.change),
            ("energy_work", b.work),
        ] {
            self.fixed.insert(key.into(), serde_json::json!(value));
        }
        self.fixed
            .insert("warnings".into(), serde_json::json!(warnings));
    }

    /// Adds `closure_residual_max`, the largest closure residual norm over
    /// the output rows \[m\] (docs/scene-format-extensions.md).
    pub fn add_closures(&mut self, residual_max: f64) {
        self.fixed.insert(
            "closure_residual_max".into(),
            serde_json::json!(residual_max),
        );
    }

    /// Adds `max_penetration` (the largest `−gap` over the output rows,
    /// m) and `max_contacts` (the most contacts at one row), for a run with
    /// contact (scene-format.md, "Contact").
    /// Appends a warning to `warnings` (creating it).
    pub fn add_warning(&mut self, warning: String) {
        let list = self
            .fixed
            .entry("warnings")
            .or_insert_with(|| serde_json::json!([]));
        if let Some(a) = list.as_array_mut() {
            a.push(serde_json::json!(warning));
        }
    }

    pub fn add_contact(&mut self, max_penetration: f64, max_contacts: usize) {
        self.fixed
            .insert("max_penetration".into(), serde_json::json!(max_penetration));
        self.fixed
            .insert("max_contacts".into(), serde_json::json!(max_contacts));
    }

    /// Writes the summary with the given progress.
    pub fn write(
        &self,
        stats: &Stats,
        wall: f64,
        final_time: f64,
        status: &str,
        rows: usize,
    ) -> Result<(), CliError> {
        let mut v = serde_json::json!({
            "steps": stats.steps,
            "rejected_steps": stats.rejected_steps,
            "rhs_evaluations": stats.rhs_evaluations,
            "wall_seconds": wall,
            "final_time": final_time,
            "status": status,
            "jacobian_evaluations": stats.jacobian_evaluations,
            "factorizations": stats.factorizations,
            "output_rows": rows,
            "updated_unix_seconds": std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64()),
        });
        if let serde_json::Value::Object(m) = &mut v {
            m.extend(self.fixed.clone());
        }
        let text = serde_json::to_string_pretty(&v).map_err(failed)? + "\n";
        let tmp = self.path.with_extension("json.tmp");
        std::fs::write(&tmp, text)
            .and_then(|()| std::fs::rename(&tmp, &self.path))
            .map_err(|e| failed(format!("cannot write {}: {e}", self.path.display())))
    }
}
