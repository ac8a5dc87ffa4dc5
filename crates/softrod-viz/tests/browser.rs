//! The 3-D view in a real headless browser (Debian's chromium, software
//! WebGL): the page loads without any error, draws the frame named in the
//! URL, and the rod's pixels move between two frames exactly where the data
//! says the tip went.
//!
//! Needs chromium: `apt-get install -y chromium` (or set `SOFTROD_CHROMIUM`
//! to the browser's path). Without it these tests FAIL, they do not skip.

use softrod_testkit::{
    HEIGHT, WIDTH, rod_pixel, rod_pixels_near, scratch, screenshot, status, status_in,
};

use softrod_viz::demo::SwingingRods;
use softrod_viz::{ViewOptions, write_html};

/// One rod: straight at t = 0, a semicircle a quarter period later. The
/// page is error-free at both frames, draws them, and the tube is found at
/// the tip position the page reports for that frame and not there in the
/// other frame; many pixels changed from rod to background and back.
#[test]
fn rod_pixels_move_between_frames_and_page_logs_no_error() {
    let dir = scratch(env!("CARGO_TARGET_TMPDIR"), "move");
    let demo = SwingingRods {
        times: 21,
        duration: 2.0,
        ..SwingingRods::default()
    };
    let page = dir.join("view.html");
    let stats = write_html(&page, &demo.build(), &ViewOptions::default()).unwrap();
    assert_eq!(stats.frames.len(), 21);
    // Frame 0: κ = 0 (straight, hanging down); frame 5: t = T/4, κ = π/L.
    let (fa, fb) = (0usize, 5usize);
    let hash = |f: usize| format!("frame={f}&trace=0&grid=0");
    let sa = status(&dir, &page, &hash(fa), "dom-a");
    let sb = status(&dir, &page, &hash(fb), "dom-b");
    for (s, f) in [(&sa, fa), (&sb, fb)] {
        assert_eq!(s.errors, 0, "page reported errors: {}", s.error_text);
        assert!(s.ready, "page did not finish drawing");
        assert_eq!(s.frame, f as i64, "page did not show the frame in the URL");
        assert_eq!(s.tips.len(), 1);
    }
    let (ta, tb) = (sa.tips[0], sb.tips[0]);
    let moved = ((ta.0 - tb.0).powi(2) + (ta.1 - tb.1).powi(2)).sqrt();
    // The tip travels ~0.36 m of a scene ~0.7 m across in a 640 px view.
    assert!(moved > 80.0, "tip moved only {moved:.1} px on screen");

    let ia = screenshot(&dir, &page, &hash(fa), "shot-a");
    let ib = screenshot(&dir, &page, &hash(fb), "shot-b");
    assert_eq!((ia.w, ia.h), (WIDTH as usize, HEIGHT as usize));
    // The tube is ~10 px wide at the tip (r = 5 mm): a disc of 12 px around
    // the reported tip holds tens of its pixels; the other frame's tube is far.
    const NEAR: f64 = 12.0;
    const MIN_TIP_PIXELS: usize = 25;
    let a_at_a = rod_pixels_near(&ia, ta, NEAR);
    let b_at_b = rod_pixels_near(&ib, tb, NEAR);
    let a_at_b = rod_pixels_near(&ia, tb, NEAR);
    let b_at_a = rod_pixels_near(&ib, ta, NEAR);
    assert!(
        a_at_a >= MIN_TIP_PIXELS && b_at_b >= MIN_TIP_PIXELS,
        "tube not drawn at the reported tips: {a_at_a}, {b_at_b} rod pixels"
    );
    assert!(
        a_at_b == 0 && b_at_a == 0,
        "tube found where the other frame's tip is: {a_at_b}, {b_at_a}"
    );
    let (mut gone, mut came) = (0, 0);
    for (pa, pb) in ia.rgb.iter().zip(&ib.rgb) {
        match (rod_pixel(*pa), rod_pixel(*pb)) {
            (true, false) => gone += 1,
            (false, true) => came += 1,
            _ => {}
        }
    }
    // The tube covers ~2000 px in each frame; most of it moves.
    assert!(
        gone > 500 && came > 500,
        "rod pixels gone {gone}, appeared {came}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Ten rods in 3-D with a cable and a body, a 1 mm rod, a run of one output
/// time and a 10 m rod: each
/// page loads and draws with no error, every tip on screen.
#[test]
fn varied_scenes_render_without_error() {
    let dir = scratch(env!("CARGO_TARGET_TMPDIR"), "varied");
    let cases = [
        (
            "ten",
            SwingingRods {
                rods: 10,
                times: 11,
                cable: true,
                body: true,
                ..SwingingRods::default()
            },
        ),
        (
            "tiny",
            SwingingRods {
                length: 1e-3,
                radius: 2e-5,
                times: 11,
                ..SwingingRods::default()
            },
        ),
        (
            "single_frame",
            SwingingRods {
                times: 1,
                ..SwingingRods::default()
            },
        ),
        (
            "large",
            SwingingRods {
                length: 10.0,
                radius: 0.2,
                rods: 2,
                times: 11,
                ..SwingingRods::default()
            },
        ),
    ];
    for (name, demo) in cases {
        let page = dir.join(format!("{name}.html"));
        let view = demo.build();
        write_html(&page, &view, &ViewOptions::default()).unwrap();
        let s = status(&dir, &page, "frame=last&axes=1", name);
        assert_eq!(
            s.errors, 0,
            "{name}: page reported errors: {}",
            s.error_text
        );
        assert!(s.ready, "{name}: not drawn");
        assert_eq!(s.frame as usize, view.times.len() - 1, "{name}");
        assert_eq!(s.tips.len(), view.rods.len(), "{name}");
        for (x, y) in &s.tips {
            assert!(
                (0.0..WIDTH as f64).contains(x) && (0.0..HEIGHT as f64).contains(y),
                "{name}: tip at ({x}, {y}) is off screen"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The error marker works: a page whose data is corrupted (a rod that is
/// `null`) reports the script error in the DOM and never claims to be drawn,
/// so the zero-error assertions above are not vacuous.
#[test]
fn a_script_error_is_reported_in_the_dom() {
    let dir = scratch(env!("CARGO_TARGET_TMPDIR"), "error");
    let view = SwingingRods {
        times: 3,
        ..SwingingRods::default()
    }
    .build();
    let (page, _) = softrod_viz::render_html(&view, &ViewOptions::default()).unwrap();
    let broken = page.replacen("\"rods\":[", "\"rods\":[null,", 1);
    assert_ne!(broken, page);
    let path = dir.join("broken.html");
    std::fs::write(&path, broken).unwrap();
    let s = status_in(&dir, &path, "frame=0", "broken", (WIDTH, HEIGHT));
    assert!(s.errors >= 1, "no error reported");
    assert!(!s.ready, "a broken page claims to be drawn");
    assert!(s.error_text.contains("error"), "{}", s.error_text);
    let _ = std::fs::remove_dir_all(&dir);
}
