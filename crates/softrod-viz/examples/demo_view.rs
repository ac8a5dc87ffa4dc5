//! Writes demo views (1 rod; 10 rods with a cable and a body; 1 rod with a
//! cable, a body and its frame axes shown; a 1 mm rod;
//! 10 rods over 10 001 output times; a 10 m rod) to the directory given as the first argument (default
//! `target/viz-demo`), and prints what each kept and how long it took.
use softrod_viz::demo::SwingingRods;
use softrod_viz::run_dir::{
    RadiusProfile, Rod, SHAPE_CSV, ShapeCsvWriter, VIEW_JSON, ViewSpec, write_view,
};
use softrod_viz::{ViewOptions, write_html};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "target/viz-demo".into());
    std::fs::create_dir_all(&dir)?;
    let cases = [
        ("one_rod", SwingingRods::default()),
        (
            "ten_rods",
            SwingingRods {
                rods: 10,
                cable: true,
                body: true,
                ..SwingingRods::default()
            },
        ),
        (
            "cable_body",
            SwingingRods {
                cable: true,
                body: true,
                samples: 61,
                ..SwingingRods::default()
            },
        ),
        (
            "tiny",
            SwingingRods {
                length: 1e-3,
                radius: 2e-5,
                ..SwingingRods::default()
            },
        ),
        (
            "long",
            SwingingRods {
                rods: 10,
                times: 10_001,
                duration: 20.0,
                ..SwingingRods::default()
            },
        ),
        (
            "large",
            SwingingRods {
                length: 10.0,
                radius: 0.2,
                rods: 3,
                ..SwingingRods::default()
            },
        ),
    ];
    for (name, demo) in cases {
        let path = std::path::Path::new(&dir).join(format!("{name}.html"));
        let opts = ViewOptions {
            show_frame_axes: name == "cable_body",
            ..ViewOptions::default()
        };
        let data = demo.build();
        let start = std::time::Instant::now();
        let stats = write_html(&path, &data, &opts)?;
        println!(
            "{}: {} of {} frames, {} bytes, written in {:.3} s",
            path.display(),
            stats.frames.len(),
            stats.source_frames,
            stats.bytes,
            start.elapsed().as_secs_f64()
        );
    }
    // The run-directory path: shape.csv + view.json written, view.html
    // rebuilt from the files (what `softrod view DIR` does).
    let run = std::path::Path::new(&dir).join("run_dir");
    std::fs::create_dir_all(&run)?;
    let data = SwingingRods {
        rods: 10,
        times: 1001,
        ..SwingingRods::default()
    }
    .build();
    let start = std::time::Instant::now();
    let mut w = ShapeCsvWriter::new(std::io::BufWriter::new(std::fs::File::create(
        run.join(SHAPE_CSV),
    )?))?;
    for (k, t) in data.times.iter().enumerate() {
        for r in &data.rods {
            w.write_frame(*t, &r.name, &r.s, &r.frames[k])?;
        }
    }
    w.flush()?;
    let wrote = start.elapsed().as_secs_f64();
    let mut spec = ViewSpec::new("run directory demo");
    for r in &data.rods {
        spec.rods.push(Rod {
            name: r.name.clone(),
            radius: RadiusProfile {
                s: vec![0.0, 0.5],
                r: vec![0.01, 0.005],
            },
        });
    }
    spec.write(&run.join(VIEW_JSON))?;
    let start = std::time::Instant::now();
    let (html, stats) = write_view(&run, &ViewOptions::default())?;
    println!(
        "{}: shape.csv of {} rows written in {wrote:.3} s; view.html ({} frames, {} bytes) rebuilt from the files in {:.3} s",
        html.display(),
        data.times.len() * data.rods.len() * data.rods[0].s.len(),
        stats.frames.len(),
        stats.bytes,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
