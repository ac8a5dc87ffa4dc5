//! Prints the criterion results under `target/criterion` as Markdown tables
//! (median and its 95 % interval per benchmark), for `docs/performance.md`:
//!
//! ```sh
//! cargo bench -p softrod-benches -- --warm-up-time 1 --measurement-time 2
//! cargo run -p softrod-benches --bin bench-tables > /tmp/tables.md
//! ```
//!
//! The numbers are whatever the last `cargo bench` measured; nothing is typed
//! by hand.
//!
//! On a shared virtual machine the same binary measures up to 1.6× slower in
//! some minutes than in others (docs/performance.md). Several complete runs,
//! each saved as a criterion baseline, are tabulated side by side with
//! `--runs`, plus the fastest median of each benchmark (contention only ever
//! adds time):
//!
//! ```sh
//! for r in run1 run2 run3; do
//!   cargo bench -p softrod-benches --bench dynamics -- --save-baseline $r
//! done
//! cargo run -p softrod-benches --bin bench-tables -- --runs run1,run2,run3
//! ```

use std::path::{Path, PathBuf};

fn median_ns(path: &Path) -> Option<(f64, f64, f64)> {
    let text = std::fs::read_to_string(path).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let m = &v["median"];
    Some((
        m["point_estimate"].as_f64()?,
        m["confidence_interval"]["lower_bound"].as_f64()?,
        m["confidence_interval"]["upper_bound"].as_f64()?,
    ))
}

fn fmt_time(ns: f64) -> String {
    if ns < 1e3 {
        format!("{ns:.1} ns")
    } else if ns < 1e6 {
        format!("{:.2} µs", ns / 1e3)
    } else {
        format!("{:.2} ms", ns / 1e6)
    }
}

/// Sorts ids numerically when they are piece counts, else by name.
fn sort_key(id: &str) -> (u64, String) {
    (id.parse::<u64>().unwrap_or(u64::MAX), id.to_string())
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let runs: Option<Vec<String>> = match args.iter().position(|a| a == "--runs") {
        Some(i) => {
            let Some(list) = args.get(i + 1).cloned() else {
                eprintln!("--runs needs a comma-separated list of baseline names");
                std::process::exit(2);
            };
            args.drain(i..i + 2);
            Some(list.split(',').map(str::to_string).collect())
        }
        None => None,
    };
    let root: PathBuf = args.first().map(PathBuf::from).unwrap_or_else(|| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join("target")
            .join("criterion")
    });
    let Ok(groups) = std::fs::read_dir(&root) else {
        eprintln!(
            "no criterion results in {} (run cargo bench first)",
            root.display()
        );
        std::process::exit(2);
    };
    let mut groups: Vec<PathBuf> = groups
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    groups.sort();
    if let Some(runs) = runs {
        print_runs(&groups, &runs);
        return;
    }
    println!("| benchmark | median | 95 % interval |");
    println!("|---|---|---|");
    for g in groups {
        let name = g.file_name().unwrap().to_string_lossy().to_string();
        if name == "report" {
            continue;
        }
        let mut ids: Vec<String> = std::fs::read_dir(&g)
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| e.path().join("new").join("estimates.json").exists())
            .map(|e| e.file_name().to_string_lossy().to_string())
            .collect();
        ids.sort_by_key(|id| sort_key(id));
        for id in ids {
            if let Some((m, lo, hi)) = median_ns(&g.join(&id).join("new").join("estimates.json")) {
                println!(
                    "| {name}/{id} | {} | {} – {} |",
                    fmt_time(m),
                    fmt_time(lo),
                    fmt_time(hi)
                );
            }
        }
    }
}

/// One column per saved baseline (its median) and the fastest of them.
fn print_runs(groups: &[PathBuf], runs: &[String]) {
    println!("| benchmark | {} | fastest |", runs.join(" | "));
    println!("|---|{}---|", "---|".repeat(runs.len()));
    for g in groups {
        let name = g.file_name().unwrap().to_string_lossy().to_string();
        if name == "report" {
            continue;
        }
        let mut ids: Vec<String> = std::fs::read_dir(g)
            .into_iter()
            .flatten()
            .flatten()
            .filter(|e| {
                runs.iter()
                    .any(|r| e.path().join(r).join("estimates.json").exists())
            })
            .map(|e| e.file_name().to_string_lossy().to_string())
            .collect();
        ids.sort_by_key(|id| sort_key(id));
        for id in ids {
            let medians: Vec<Option<f64>> = runs
                .iter()
                .map(|r| median_ns(&g.join(&id).join(r).join("estimates.json")).map(|m| m.0))
                .collect();
            let cells: Vec<String> = medians
                .iter()
                .map(|m| m.map_or_else(|| "–".to_string(), fmt_time))
                .collect();
            let best = medians
                .iter()
                .flatten()
                .copied()
                .fold(f64::INFINITY, f64::min);
            println!(
                "| {name}/{id} | {} | **{}** |",
                cells.join(" | "),
                fmt_time(best)
            );
        }
    }
}
