//! The 3-D view of a real `softrod run`, in a real headless browser
//! (Debian's chromium, software WebGL): the page the CLI wrote loads with no
//! error, shows the first and the last frame, and the rod's pixels moved
//! between them to where the page reports the tip (the falling cantilever
//! drops ~0.2 m in 0.3 s).
//!
//! Needs chromium: `apt-get install -y chromium` (or set `SOFTROD_CHROMIUM`).
//! Without it this test FAILS, it does not skip. The browser helpers are
//! those of softrod-viz's tests/browser.rs.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Window size of the headless browser, CSS pixels (device pixel ratio 1).
const WIDTH: u32 = 960;
const HEIGHT: u32 = 640;
/// Longest a single browser run may take before the test fails (a
/// SwiftShader page load takes ~1 s here).
const BROWSER_TIMEOUT: Duration = Duration::from_secs(90);

fn chromium() -> PathBuf {
    if let Some(p) = std::env::var_os("SOFTROD_CHROMIUM") {
        return PathBuf::from(p);
    }
    for p in [
        "/usr/bin/chromium",
        "/usr/bin/chromium-browser",
        "/usr/bin/google-chrome",
    ] {
        if Path::new(p).exists() {
            return PathBuf::from(p);
        }
    }
    panic!(
        "the browser test needs chromium and none was found (looked at $SOFTROD_CHROMIUM, \
         /usr/bin/chromium, /usr/bin/chromium-browser, /usr/bin/google-chrome).\n\
         Install it with:  apt-get update && apt-get install -y chromium\n\
         (or set SOFTROD_CHROMIUM to a Chromium/Chrome binary)"
    );
}

fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("softrod-cli-browser-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs chromium headless with the flags the machine notes give (no
/// network chatter, fresh profile) plus `extra`; returns stdout.
fn run_browser(dir: &Path, tag: &str, window: (u32, u32), extra: &[String]) -> String {
    let profile = dir.join(format!("profile-{tag}"));
    let mut cmd = Command::new(chromium());
    cmd.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--enable-unsafe-swiftshader",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--hide-scrollbars",
        "--force-device-scale-factor=1",
    ])
    .arg(format!("--user-data-dir={}", profile.display()))
    .arg(format!("--window-size={},{}", window.0, window.1))
    .args(extra)
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    let child = cmd
        .spawn()
        .unwrap_or_else(|e| panic!("cannot start chromium ({}): {e}", chromium().display()));
    let start = Instant::now();
    let id = child.id();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    loop {
        if let Ok(out) = rx.try_recv() {
            let out = out.expect("waiting for chromium");
            assert!(
                out.status.success(),
                "chromium failed ({}): {}",
                out.status,
                String::from_utf8_lossy(&out.stderr)
            );
            let _ = std::fs::remove_dir_all(&profile);
            return String::from_utf8_lossy(&out.stdout).into_owned();
        }
        if start.elapsed() > BROWSER_TIMEOUT {
            // Only the process this test started, by its id.
            let _ = Command::new("kill").arg(id.to_string()).status();
            panic!("chromium did not finish within {BROWSER_TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn url(page: &Path, hash: &str) -> String {
    format!("file://{}#{hash}", page.display())
}

/// The page's status marker after load.
struct Status {
    viewport: (u32, u32),
    errors: usize,
    ready: bool,
    frame: i64,
    tips: Vec<(f64, f64)>,
    error_text: String,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!("{name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(tag[i..j].to_string())
}

/// The page's status after load, in a viewport of `WIDTH × HEIGHT` like the
/// screenshots. `--dump-dom` gives the page a window less the browser's
/// frame (960×640 → 960×497 seen here), `--screenshot` the whole window, so
/// the window is enlarged by the difference the page reports.
fn status(dir: &Path, page: &Path, hash: &str, tag: &str) -> Status {
    let mut window = (WIDTH, HEIGHT);
    for _ in 0..3 {
        let s = status_in(dir, page, hash, tag, window);
        if s.viewport == (WIDTH, HEIGHT) {
            return s;
        }
        window.0 = window.0 + WIDTH - s.viewport.0.min(WIDTH);
        window.1 = window.1 + HEIGHT - s.viewport.1.min(HEIGHT);
    }
    panic!("could not give --dump-dom a {WIDTH}×{HEIGHT} viewport");
}

fn status_in(dir: &Path, page: &Path, hash: &str, tag: &str, window: (u32, u32)) -> Status {
    let dom = run_browser(dir, tag, window, &["--dump-dom".into(), url(page, hash)]);
    let i = dom
        .find("<div id=\"softrod-status\"")
        .unwrap_or_else(|| panic!("no status marker in the DOM:\n{dom}"));
    let tag_text = &dom[i..i + dom[i..].find('>').unwrap()];
    let errors_box = dom
        .find("id=\"errors\"")
        .map(|k| dom[k..].chars().take(2000).collect::<String>())
        .unwrap_or_default();
    let tips = attr(tag_text, "data-tips")
        .unwrap_or_default()
        .split(';')
        .filter(|s| !s.is_empty())
        .map(|p| {
            let (x, y) = p
                .split_once(',')
                .unwrap_or_else(|| panic!("tip {p:?} not on screen"));
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect();
    let viewport = attr(tag_text, "data-viewport").unwrap_or_default();
    let (vw, vh) = viewport.split_once('x').unwrap_or(("0", "0"));
    Status {
        viewport: (vw.parse().unwrap_or(0), vh.parse().unwrap_or(0)),
        errors: attr(tag_text, "data-errors").unwrap().parse().unwrap(),
        ready: attr(tag_text, "data-ready").as_deref() == Some("1"),
        frame: attr(tag_text, "data-frame").unwrap().parse().unwrap(),
        tips,
        error_text: errors_box,
    }
}

struct Image {
    w: usize,
    h: usize,
    rgb: Vec<[u8; 3]>,
}

fn screenshot(dir: &Path, page: &Path, hash: &str, tag: &str) -> Image {
    let png_path = dir.join(format!("{tag}.png"));
    run_browser(
        dir,
        tag,
        (WIDTH, HEIGHT),
        &[
            format!("--screenshot={}", png_path.display()),
            url(page, hash),
        ],
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&png_path).expect("screenshot written"),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    let rgb = buf[..info.buffer_size()]
        .chunks(ch)
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    Image {
        w: info.width as usize,
        h: info.height as usize,
        rgb,
    }
}

/// A pixel of the first rod's tube: the page's first palette colour
/// `#1f77b4` under its lighting (a factor 0.3 … 1.05 plus a grey specular
/// highlight keeps green/blue near 0.66 and red/blue low); the background,
/// the grey grid, the legend text and the blue z axis (`g/b ≈ 0.37`) fail it.
fn rod_pixel(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(f64::from);
    b > 40.0 && (0.52..0.80).contains(&(g / b)) && r / b < 0.45
}

/// Rod pixels within `radius` px of `(x, y)`.
fn rod_pixels_near(img: &Image, (x, y): (f64, f64), radius: f64) -> usize {
    let mut n = 0;
    for py in 0..img.h {
        for px in 0..img.w {
            let d2 = (px as f64 - x).powi(2) + (py as f64 - y).powi(2);
            if d2 <= radius * radius && rod_pixel(img.rgb[py * img.w + px]) {
                n += 1;
            }
        }
    }
    n
}

/// One rod: straight at t = 0, a semicircle a quarter period later. The
/// page is error-free at both frames, draws them, and the tube is found at
/// the tip position the page reports for that frame and not there in the

#[test]
fn the_run_view_shows_the_rod_moving_and_logs_no_error() {
    let dir = scratch("run");
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
