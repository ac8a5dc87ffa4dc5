//! The page as text: the embedded data is the input (to the stated
//! quantization), decimation keeps the ends and respects the budgets, the
//! output is deterministic, needs no network, and survives hostile names.

use softrod_viz::demo::SwingingRods;
use softrod_viz::html::{QUAT_SCALE, embedded_data};
use softrod_viz::{ViewOptions, VizError, render_html};

/// serde_json's default parser may round the last bit of a float (its
/// `float_roundtrip` feature is off); the page's JSON.parse is exact. Floats
/// written with ryu are compared to this relative tolerance.
const PARSE_ULP: f64 = 2.5e-16;

fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() <= PARSE_ULP * x.abs().max(y.abs()))
}

fn nums(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Every kept frame decodes back to the input pose: positions within half
/// a quantum, quaternion components within half a unit of 1e-4.
#[test]
fn embedded_data_decodes_to_the_input() {
    let view = SwingingRods {
        rods: 3,
        times: 31,
        cable: true,
        body: true,
        ..SwingingRods::default()
    }
    .build();
    let (page, stats) = render_html(&view, &ViewOptions::default()).unwrap();
    assert_eq!(stats.frames, (0..31).collect::<Vec<_>>());
    let d = embedded_data(&page).expect("embedded JSON parses");
    assert_eq!(d["format"], "softrod-view");
    let origin = nums(&d["origin"]);
    let quantum = d["quantum"].as_f64().unwrap();
    // The quantum is a power of two near 2^-20 of the extent (~0.7 m here).
    assert_eq!(quantum.log2().fract(), 0.0);
    assert!(quantum < 1e-6 && quantum > 1e-7, "{quantum}");
    assert!(close(&nums(&d["times"]), &view.times));
    for (r, rod) in view.rods.iter().enumerate() {
        let jr = &d["rods"][r];
        assert_eq!(jr["name"], rod.name.as_str());
        assert!(close(&nums(&jr["s"]), &rod.s));
        assert!(close(&nums(&jr["radius"]), &rod.radius));
        for (k, frame) in rod.frames.iter().enumerate() {
            let f = nums(&jr["frames"][k]);
            assert_eq!(f.len(), 7 * rod.s.len());
            for (i, pose) in frame.iter().enumerate() {
                for j in 0..3 {
                    let back = origin[j] + f[7 * i + j] * quantum;
                    assert!((back - pose.position[j]).abs() <= 0.5 * quantum * (1.0 + 1e-9));
                }
                // Stored with w ≥ 0 (q and −q are the same rotation).
                let sign = if pose.rotation[0] < 0.0 { -1.0 } else { 1.0 };
                for j in 0..4 {
                    let back = f[7 * i + 3 + j] / QUAT_SCALE;
                    assert!((back - sign * pose.rotation[j]).abs() <= 0.5 / QUAT_SCALE + 1e-12);
                }
            }
        }
        // Tip trace = last sample by default.
        let tp = nums(&jr["trace"]["p"]);
        let last = rod.frames[30][rod.s.len() - 1].position;
        for j in 0..3 {
            assert!(
                (origin[j] + tp[3 * 30 + j] * quantum - last[j]).abs() <= 0.5 * quantum * 1.001
            );
        }
    }
    assert_eq!(d["cables"][0]["frames"].as_array().unwrap().len(), 31);
    assert_eq!(d["bodies"][0]["shape"], "sphere");
    assert_eq!(d["bodies"][0]["radius"].as_f64().unwrap(), 0.02);
}

#[test]
fn same_input_gives_the_same_bytes() {
    let view = SwingingRods {
        rods: 4,
        cable: true,
        ..SwingingRods::default()
    }
    .build();
    let a = render_html(&view, &ViewOptions::default()).unwrap().0;
    let b = render_html(&view.clone(), &ViewOptions::default())
        .unwrap()
        .0;
    assert!(a == b, "two renders differ");
}

/// Self-contained: no URL a browser would fetch, no external script or
/// style; the document has its parts in order and balanced script tags.
#[test]
fn page_needs_no_network_and_is_well_formed() {
    let view = SwingingRods::default().build();
    let page = render_html(&view, &ViewOptions::default()).unwrap().0;
    for bad in [
        "http:",
        "https:",
        "src=",
        "href=",
        "@import",
        "url(",
        "fetch(",
        "XMLHttpRequest",
    ] {
        assert!(!page.contains(bad), "page contains {bad:?}");
    }
    assert!(page.starts_with("<!DOCTYPE html>\n<html lang=\"en\">"));
    assert!(page.trim_end().ends_with("</html>"));
    assert_eq!(
        page.matches("<script").count(),
        page.matches("</script>").count()
    );
    assert_eq!(page.matches("<script").count(), 3, "guard, data, view");
    assert!(!page.contains("@@"), "a template marker was left");
    for id in [
        "id=\"gl\"",
        "id=\"slider\"",
        "id=\"play\"",
        "id=\"speed\"",
        "id=\"axes\"",
        "id=\"legend\"",
        "id=\"time\"",
    ] {
        assert!(page.contains(id), "{id} missing");
    }
}

/// Names that would break HTML, JSON or a template survive intact.
#[test]
fn hostile_names_are_escaped() {
    let mut view = SwingingRods {
        rods: 2,
        times: 3,
        ..SwingingRods::default()
    }
    .build();
    let nasty = "</script><script>alert(\"x\")</script> @@JS@@ & 'q', \\ \u{2028}";
    view.rods[0].name = nasty.into();
    view.title = "<b>title</b> @@DATA@@".into();
    let page = render_html(&view, &ViewOptions::default()).unwrap().0;
    assert_eq!(page.matches("</script>").count(), 3);
    let d = embedded_data(&page).unwrap();
    assert_eq!(d["rods"][0]["name"], nasty);
    assert_eq!(d["title"], "<b>title</b> @@DATA@@");
    assert!(page.contains("<title>&lt;b&gt;title&lt;/b&gt; @@DATA@@ · softrod</title>"));
}

/// 10 001 output times: 2000 frames kept, first and last among them, evenly.
#[test]
fn long_runs_are_decimated_to_the_frame_budget() {
    let view = SwingingRods {
        times: 10_001,
        samples: 6,
        ..SwingingRods::default()
    }
    .build();
    let (page, stats) = render_html(&view, &ViewOptions::default()).unwrap();
    assert_eq!(stats.frames.len(), 2000);
    assert_eq!(stats.frames[0], 0);
    assert_eq!(*stats.frames.last().unwrap(), 10_000);
    let d = embedded_data(&page).unwrap();
    let times = nums(&d["times"]);
    assert_eq!(times.len(), 2000);
    assert_eq!(times[0], 0.0);
    assert_eq!(*times.last().unwrap(), 2.0);
    assert_eq!(d["sourceFrames"], 10_001);
    // The trace keeps more points than the frames (its own budget).
    assert_eq!(d["rods"][0]["trace"]["t"].as_array().unwrap().len(), 10_001);
}

/// A byte budget smaller than all frames need: fewer frames, the page
/// within the budget, ends kept; a budget below two frames is an error
/// that says so.
#[test]
fn byte_budget_is_respected() {
    let view = SwingingRods {
        times: 400,
        ..SwingingRods::default()
    }
    .build();
    let full = render_html(&view, &ViewOptions::default()).unwrap().1.bytes;
    let max_bytes = full / 3;
    let opts = ViewOptions {
        max_bytes,
        ..ViewOptions::default()
    };
    let (page, stats) = render_html(&view, &opts).unwrap();
    assert!(page.len() <= max_bytes, "{} > {max_bytes}", page.len());
    assert_eq!(stats.bytes, page.len());
    assert!(
        stats.frames.len() < 400 && stats.frames.len() > 50,
        "{}",
        stats.frames.len()
    );
    assert_eq!((stats.frames[0], *stats.frames.last().unwrap()), (0, 399));
    let tiny = ViewOptions {
        max_bytes: 1000,
        ..ViewOptions::default()
    };
    match render_html(&view, &tiny) {
        Err(VizError::TooLarge { max_bytes, bytes }) => assert!(max_bytes == 1000 && bytes > 1000),
        other => panic!("expected TooLarge, got {other:?}"),
    }
}

#[test]
fn bad_input_is_a_structured_error() {
    let mut view = SwingingRods {
        times: 3,
        ..SwingingRods::default()
    }
    .build();
    view.rods[0].frames[1][2].position[1] = f64::NAN;
    match render_html(&view, &ViewOptions::default()) {
        Err(VizError::NotFinite { what, index, .. }) => {
            assert_eq!(what, "rods[0] ('rod 0').frames[1][2].position");
            assert_eq!(index, 1);
        }
        other => panic!("{other:?}"),
    }
    let mut view = SwingingRods {
        times: 3,
        ..SwingingRods::default()
    }
    .build();
    view.rods[0].radius.pop();
    assert!(matches!(
        render_html(&view, &ViewOptions::default()),
        Err(VizError::Count {
            got: 40,
            expected: 41,
            ..
        })
    ));
    view.rods.clear();
    assert!(matches!(
        render_html(&view, &ViewOptions::default()),
        Err(VizError::Empty(_))
    ));
}
