//! What `check` and `statics --json` say about loop closures
//! (scene-format.md, "Bodies, joints, bases and closures";
//! docs/scene-format-extensions.md).

use softrod::dynamics::{ClosureFrame, Data, Model, closure_residuals, constraint_rank};

use crate::common::{CliError, failed};

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
