//! Obstacles in the 3-D view, in a real headless browser (see
//! `browser.rs` for what it needs): a page with a table, a fixed ball and a
//! box carried across the scene loads without error; the page reports each
//! obstacle's anchor on screen; the fixed ones stay put between frames, the
//! carried one moves with its carrier; and the obstacle's colour is drawn
//! where its anchor is reported, and not where the box is in the other
//! frame.

use softrod_testkit::{HEIGHT, Image, WIDTH, attr, run_browser, scratch, screenshot, url};
use softrod_viz::demo::SwingingRods;
use softrod_viz::{ObstacleShape, ObstacleTrack, Pose, ViewOptions, write_html};

/// A pixel of a solid obstacle: the page's `#b8976a` under its lighting
/// (red > green > blue, red/blue ≈ 1.7); the background, the grey grid, the
/// see-through table (`#c9b894` over the background, red/blue ≈ 1.1) and
/// the blue rod fail it.
fn obstacle_pixel(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(f64::from);
    b > 15.0 && r > g && g > b && (1.4..2.2).contains(&(r / b)) && (1.15..1.7).contains(&(g / b))
}

fn obstacle_pixels_near(img: &Image, (x, y): (f64, f64), radius: f64) -> usize {
    let mut n = 0;
    for py in 0..img.h {
        for px in 0..img.w {
            let d2 = (px as f64 - x).powi(2) + (py as f64 - y).powi(2);
            if d2 <= radius * radius && obstacle_pixel(img.rgb[py * img.w + px]) {
                n += 1;
            }
        }
    }
    n
}

/// The anchors the page reports (CSS px), and its error count, in a
/// viewport of `WIDTH × HEIGHT` like the screenshots (`--dump-dom` gives the
/// page the window less the browser's frame: the window is enlarged by the
/// difference the page reports, as `softrod_testkit::status` does).
fn anchors(
    dir: &std::path::Path,
    page: &std::path::Path,
    hash: &str,
    tag: &str,
) -> (usize, Vec<(f64, f64)>) {
    let mut window = (WIDTH, HEIGHT);
    for _ in 0..3 {
        let dom = run_browser(dir, tag, window, &["--dump-dom".into(), url(page, hash)]);
        let i = dom
            .find("<div id=\"softrod-status\"")
            .expect("status marker");
        let tag_text = &dom[i..i + dom[i..].find('>').unwrap()];
        let viewport = attr(tag_text, "data-viewport").unwrap_or_default();
        let (vw, vh) = viewport.split_once('x').unwrap_or(("0", "0"));
        let (vw, vh): (u32, u32) = (vw.parse().unwrap_or(0), vh.parse().unwrap_or(0));
        if (vw, vh) != (WIDTH, HEIGHT) {
            window.0 = window.0 + WIDTH - vw.min(WIDTH);
            window.1 = window.1 + HEIGHT - vh.min(HEIGHT);
            continue;
        }
        let errors: usize = attr(tag_text, "data-errors").unwrap().parse().unwrap();
        assert_eq!(
            attr(tag_text, "data-ready").as_deref(),
            Some("1"),
            "not drawn"
        );
        let list = attr(tag_text, "data-obstacles").expect("data-obstacles");
        let points = list
            .split(';')
            .map(|p| {
                let (x, y) = p
                    .split_once(',')
                    .unwrap_or_else(|| panic!("{p:?} off screen"));
                (x.parse().unwrap(), y.parse().unwrap())
            })
            .collect();
        return (errors, points);
    }
    panic!("could not give --dump-dom a {WIDTH}×{HEIGHT} viewport");
}

#[test]
fn obstacles_are_drawn_and_carried_ones_move() {
    let dir = scratch(env!("CARGO_TARGET_TMPDIR"), "obstacles");
    let times = 11;
    let mut view = SwingingRods {
        times,
        duration: 1.0,
        ..SwingingRods::default()
    }
    .build();
    view.obstacles.push(ObstacleTrack::fixed(
        "table",
        ObstacleShape::Plane {
            position: [0.0, 0.0, -0.6],
            normal: [0.0, 0.0, 1.0],
        },
    ));
    view.obstacles.push(ObstacleTrack::fixed(
        "ball",
        ObstacleShape::Sphere {
            position: [0.35, 0.0, -0.3],
            radius: 0.06,
        },
    ));
    // A box in its carrier's frame, the carrier sliding along x from −0.4
    // to +0.4 m at z = −0.55.
    let mut crate_ = ObstacleTrack::fixed(
        "crate",
        ObstacleShape::Box {
            position: [0.0, 0.0, 0.0],
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            half_extents: [0.05, 0.05, 0.05],
        },
    );
    crate_.poses = Some(
        (0..times)
            .map(|k| Pose::at([-0.4 + 0.8 * k as f64 / (times - 1) as f64, 0.0, -0.55]))
            .collect(),
    );
    view.obstacles.push(crate_);
    let page = dir.join("view.html");
    write_html(&page, &view, &ViewOptions::default()).unwrap();
    let hash = |f: usize| format!("frame={f}&trace=0&grid=0");
    let (ea, a) = anchors(&dir, &page, &hash(0), "dom-a");
    let (eb, b) = anchors(&dir, &page, &hash(times - 1), "dom-b");
    assert_eq!((ea, eb), (0, 0), "page reported errors");
    assert_eq!((a.len(), b.len()), (3, 3));
    let dist = |p: (f64, f64), q: (f64, f64)| (p.0 - q.0).hypot(p.1 - q.1);
    assert!(
        dist(a[0], b[0]) < 0.5 && dist(a[1], b[1]) < 0.5,
        "fixed obstacles moved"
    );
    // 0.8 m of travel in a scene about a metre across, 960 px wide.
    let moved = dist(a[2], b[2]);
    assert!(moved > 150.0, "the carried box moved {moved:.1} px");

    let ia = screenshot(&dir, &page, &hash(0), "shot-a");
    let ib = screenshot(&dir, &page, &hash(times - 1), "shot-b");
    // The ball (~40 px across) and the box (~30 px) around their anchors.
    const NEAR: f64 = 10.0;
    for (img, at, what) in [
        (&ia, a[1], "ball, frame 0"),
        (&ib, b[1], "ball, last frame"),
        (&ia, a[2], "box, frame 0"),
        (&ib, b[2], "box, last frame"),
    ] {
        let n = obstacle_pixels_near(img, at, NEAR);
        assert!(n >= 60, "{what}: {n} obstacle pixels near its anchor");
    }
    assert_eq!(
        obstacle_pixels_near(&ia, b[2], NEAR),
        0,
        "box drawn where it is later"
    );
    assert_eq!(
        obstacle_pixels_near(&ib, a[2], NEAR),
        0,
        "box drawn where it was"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
