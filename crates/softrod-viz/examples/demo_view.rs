//! Writes demo views (1 rod; 10 rods with a cable and a body; 1 rod with a
//! cable, a body and its frame axes shown; a 1 mm rod;
//! a 10 m rod) to the directory given as the first argument (default
//! `target/viz-demo`), and prints what each kept.
use softrod_viz::demo::SwingingRods;
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
        let stats = write_html(&path, &demo.build(), &opts)?;
        println!(
            "{}: {} of {} frames, {} bytes",
            path.display(),
            stats.frames.len(),
            stats.source_frames,
            stats.bytes
        );
    }
    Ok(())
}
