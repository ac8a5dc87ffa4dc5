//! The 3-D view of a real `softrod run`, in a real headless browser
//! (Debian's chromium, software WebGL): the page the CLI wrote loads with no
//! error, shows the first and the last frame, and the rod's pixels moved
//! between them to where the page reports the tip (the falling cantilever
//! drops ~0.2 m in 0.3 s).
//!
//! Needs chromium: `apt-get install -y chromium` (or set `SOFTROD_CHROMIUM`).
//! Without it this test FAILS, it does not skip. The browser helpers are
//! softrod-testkit's, shared with softrod-viz's browser test.

use std::path::Path;

use std::process::Command;

use softrod_testkit::{rod_pixel, rod_pixels_near, scratch, screenshot, status};

/// One rod: straight at t = 0, a semicircle a quarter period later. The
/// page is error-free at both frames, draws them, and the tube is found at
/// the tip position the page reports for that frame and not there in the

#[test]
fn the_run_view_shows_the_rod_moving_and_logs_no_error() {
    let dir = scratch(env!("CARGO_TARGET_TMPDIR"), "run");
    let example =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cantilever_gravity.toml");
    let text = std::fs::read_to_string(example).unwrap();
    let cut = text.find("[run]").unwrap();
    let scene = dir.join("falling.toml");
    std::fs::write(
        &scene,
        format!(
            "{}[run]\nduration = 0.3\noutput_every = 0.01\n",
            &text[..cut]
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
