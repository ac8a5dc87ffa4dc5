//! What `check`, `statics --json` and `run` say about loop closures
//! (scene-format.md, "Bodies, joints, bases and closures";
//! docs/scene-format-extensions.md).

use softrod::dynamics::{
    ClosureFrame, Data, Model, closure_residuals, constraint_rank, max_closure_residual,
};

use crate::common::{CliError, failed};

/// `run` stops with an error when the largest closure residual exceeds this
/// fraction of the model's length scale (its longest rod): the loop has
/// come apart and the results mean nothing.
pub const RUN_FAIL_RELATIVE: f64 = 1e-3;
/// `run` warns when the largest closure residual exceeds this fraction of
/// the length scale (the Baumgarte stabilization normally holds it far
/// below; a tighter `rtol` reduces it).
pub const RUN_WARN_RELATIVE: f64 = 1e-6;

fn frame_text(f: &ClosureFrame, m: &Model) -> String {
    let is_rod = m.rods().iter().any(|r| r.spec.name == f.element);
    let at = if is_rod {
        match f.at {
            Some(s) => format!(" at s = {s} m"),
            None => " at its tip".to_owned(),
        }
    } else {
        String::new()
    };
    let what = if f.element == "world" {
        "the world".to_owned()
    } else if is_rod {
        format!("rod '{}'", f.element)
    } else {
        format!("body '{}'", f.element)
    };
    let p = f.base.translation;
    let offset = if f.base == softrod::lie::Pose::identity() {
        String::new()
    } else {
        format!(" offset by [{}, {}, {}] m", p[0], p[1], p[2])
    };
    format!("{what}{at}{offset}")
}

/// The length scale of the model's residuals: its longest rod \[m\].
pub fn length_scale(m: &Model) -> f64 {
    m.rods()
        .iter()
        .map(|r| r.spec.rod.length())
        .fold(0.0, f64::max)
}

/// `check`: one line per closure, then the constraint count, the rank of
/// the constraint Jacobian at the initial state and the net DoF.
pub fn print_closures(m: &Model, q0: &[f64]) -> Result<(), CliError> {
    if !m.has_closures() {
        return Ok(());
    }
    for c in m.closures() {
        let axis = match &c.kind {
            softrod::dynamics::ClosureKind::Slider { axis } => {
                format!(" along [{}, {}, {}] (b's frame)", axis[0], axis[1], axis[2])
            }
            _ => String::new(),
        };
        println!(
            "closure '{}': {}{axis}, a = {}, b = {}, {} constraints",
            c.name,
            c.kind.name(),
            frame_text(&c.a, m),
            frame_text(&c.b, m),
            c.kind.n_constraints()
        );
    }
    let mut data = Data::new(m);
    let rank = constraint_rank(m, &mut data, q0).map_err(failed)?;
    println!(
        "closure constraints: {}, independent at the initial state: {rank}; net DoF: {} \
         (Baumgarte rate {:.3e} 1/s)",
        m.n_constraints(),
        m.n_dof() - rank,
        m.baumgarte_rate()
    );
    Ok(())
}

/// `statics --json`: `"closures": [{ "name", "type", "residual" }]` (the
/// residual norm `max(‖d‖, ℓ‖r‖)` in m, docs/theory.md D66).
pub fn add_statics_json(m: &Model, q: &[f64], v: &mut serde_json::Value) -> Result<(), CliError> {
    if !m.has_closures() {
        return Ok(());
    }
    let mut data = Data::new(m);
    let res = closure_residuals(m, &mut data, q).map_err(failed)?;
    let list: Vec<_> = m
        .closures()
        .zip(res)
        .map(|(c, r)| serde_json::json!({ "name": c.name, "type": c.kind.name(), "residual": r }))
        .collect();
    v["closures"] = serde_json::json!(list);
    Ok(())
}

/// `run`: the largest closure residual at `q` \[m\] (0 without closures).
pub fn residual(m: &Model, data: &mut Data, q: &[f64]) -> Result<f64, String> {
    if !m.has_closures() {
        return Ok(0.0);
    }
    max_closure_residual(m, data, q).map_err(|e| e.to_string())
}
