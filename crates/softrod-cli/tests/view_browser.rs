//! The 3-D view of a real `softrod run`, in a real headless browser
//! (Debian's chromium, software WebGL): the page the CLI wrote loads with no
//! error, shows the first and the last frame, and the rod's pixels moved
//! between them to where the page reports the tip (the falling cantilever
//! drops ~0.2 m in 0.3 s).
//!
//! Needs chromium: `apt-get install -y chromium` (or set `SOFTROD_CHROMIUM`).
//! Without it this test FAILS, it does not skip. The browser helpers are
//! softrod-testkit's, shared with softrod-viz's browser test.

mod common;
use common::*;

use softrod_testkit::{rod_pixel, rod_pixels_near, scratch, screenshot, status};

/// The falling cantilever, 0.3 s: the page is error-free at the first and
/// the last frame, draws both, the tube is found at the tip position the
/// page reports for each frame, and the rod's pixels moved between them.
#[test]
fn the_run_view_shows_the_rod_moving_and_logs_no_error() {
    let dir = scratch(env!("CARGO_TARGET_TMPDIR"), "run");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.3\noutput_every = 0.01\n",
        &dir,
    );
    let out = dir.join("out");
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let page = out.join("view.html");
    let hash = |f: &str| format!("frame={f}&trace=0&grid=0");
    let sa = status(&dir, &page, &hash("0"), "dom-a");
    let sb = status(&dir, &page, &hash("last"), "dom-b");
    for (s, f) in [(&sa, 0), (&sb, 30)] {
        assert_eq!(s.errors, 0, "page reported errors: {}", s.error_text);
        assert!(s.ready, "page did not finish drawing");
        assert_eq!(s.frame, f, "page did not show the frame in the URL");
        assert_eq!(s.tips.len(), 1);
    }
    let (ta, tb) = (sa.tips[0], sb.tips[0]);
    let moved = ((ta.0 - tb.0).powi(2) + (ta.1 - tb.1).powi(2)).sqrt();
    assert!(moved > 40.0, "tip moved only {moved:.1} px on screen");
    let ia = screenshot(&dir, &page, &hash("0"), "shot-a");
    let ib = screenshot(&dir, &page, &hash("last"), "shot-b");
    // The tube (r = 1 cm) is drawn at each frame's reported tip.
    const NEAR: f64 = 12.0;
    const MIN_TIP_PIXELS: usize = 25;
    let (a_at_a, b_at_b) = (
        rod_pixels_near(&ia, ta, NEAR),
        rod_pixels_near(&ib, tb, NEAR),
    );
    assert!(
        a_at_a >= MIN_TIP_PIXELS && b_at_b >= MIN_TIP_PIXELS,
        "tube not drawn at the reported tips: {a_at_a}, {b_at_b} rod pixels"
    );
    let (mut gone, mut came) = (0, 0);
    for (pa, pb) in ia.rgb.iter().zip(&ib.rgb) {
        match (rod_pixel(*pa), rod_pixel(*pb)) {
            (true, false) => gone += 1,
            (false, true) => came += 1,
            _ => {}
        }
    }
    assert!(
        gone > 300 && came > 300,
        "rod pixels gone {gone}, appeared {came}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
