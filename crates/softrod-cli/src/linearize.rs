//! `linearize`: the state-space model `(A, B)` about the static equilibrium;
//! on a closed model, of its constrained (Baumgarte-stabilized) dynamics
//! in the model's coordinates (docs/theory-derivatives.md CD9).

use std::path::Path;

use nalgebra::DMatrix;
use softrod::Equilibrium;

use crate::common::{CliError, failed, load};

/// Largest model whose `A` is printed as text (beyond: `--json`).
const TEXT_MAX_STATES: usize = 24;

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

pub fn linearize(path: &Path, json: bool) -> Result<(), CliError> {
    let mut l = load(path)?;
    let sim = &mut l.sim;
    let equilibrium = if sim.has_static_loads() {
        let s = sim.statics()?;
        // The validity rules of what is reported, as `statics` says them.
        for w in &s.warnings {
            eprintln!("softrod: warning: {w}");
        }
        Equilibrium::Statics(s.q)
    } else {
        Equilibrium::Rest
    };
    let n = sim.n_dof();
    let q = match &equilibrium {
        Equilibrium::Rest => vec![0.0; n],
        Equilibrium::Statics(q) => q.iter().copied().collect(),
    };
    let lin = sim.linearize(0.0, &q, &vec![0.0; n])?;
    if lin.a.iter().chain(lin.b.iter()).any(|v| !v.is_finite()) {
        return Err(failed("linearization gave a non-finite entry"));
    }
    let names = sim.q_names();
    let state: Vec<String> = names
        .iter()
        .map(|s| format!("q:{s}"))
        .chain(names.iter().map(|s| format!("qdot:{s}")))
        .collect();
    let mut inputs = Vec::new();
    for r in sim.model().rods() {
        inputs.extend((0..r.spec.cables.len()).map(|k| format!("{}.cable{k}", r.spec.name)));
    }
    // How far the point is from an equilibrium: |q̈| there (statics'
    // residual, seen through M⁻¹).
    let residual = lin.xdot.amax();
    // Closed models: the rows and the stabilization rate whose double
    // eigenvalue −α each independent row adds to A.
    let rows_closed = sim.model().n_constraints();
    let alpha = sim.model().baumgarte_rate();
    let eq_name = match equilibrium {
        Equilibrium::Rest => "rest",
        Equilibrium::Statics(_) => "statics",
    };
    if json {
        println!(
            "{}",
            serde_json::json!({
                "equilibrium": eq_name,
                "t": 0.0,
                "state": state,
                "inputs": inputs,
                "q": q,
                "u": lin.u.as_slice(),
                "xdot_residual": residual,
                "closure_rows": rows_closed,
                "baumgarte_rate": alpha,
                "A": rows(&lin.a),
                "B": rows(&lin.b),
            })
        );
        return Ok(());
    }
    println!(
        "linearization about the {} (x = (q, qdot), {} states, {} inputs; max |xdot| there {residual:.3e})",
        if eq_name == "rest" {
            "rest shape"
        } else {
            "static equilibrium"
        },
        2 * n,
        inputs.len()
    );
    if rows_closed > 0 {
        println!(
            "closed model: the constrained dynamics (Baumgarte-stabilized), {rows_closed} closure rows; \
             each independent row adds a double eigenvalue -alpha = {:.4e} 1/s",
            -alpha
        );
    }
    println!("state: {}", state.join(", "));
    if !inputs.is_empty() {
        println!("inputs (cable tensions, N): {}", inputs.join(", "));
    }
    if 2 * n > TEXT_MAX_STATES {
        println!(
            "A is {0}x{0}, B is {0}x{1}: use --json to print them",
            2 * n,
            inputs.len()
        );
        return Ok(());
    }
    println!("A =");
    for r in rows(&lin.a) {
        let cells: Vec<String> = r.iter().map(|v| format!("{v:>11.4e}")).collect();
        println!("  {}", cells.join(" "));
    }
    if !inputs.is_empty() {
        println!("B =");
        for r in rows(&lin.b) {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:>11.4e}")).collect();
            println!("  {}", cells.join(" "));
        }
    }
    Ok(())
}
