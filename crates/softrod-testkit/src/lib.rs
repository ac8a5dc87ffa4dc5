//! Test support shared by the browser tests of softrod-viz and softrod-cli:
//! headless chromium (software WebGL) loading a view page, its status
//! marker (`#softrod-status`: errors, readiness, frame, tip positions on
//! screen), screenshots decoded to RGB, and the first rod's pixel colour;
//! and the reading of the SVG figures' texts and body marks
//! ([`svg_texts`], [`svg_outlined_rect_centres`]).
//! Not published; its functions panic with a message, as tests do.
//!
//! Needs chromium (`apt-get install -y chromium`, or `SOFTROD_CHROMIUM`):
//! without it the tests FAIL, they do not skip.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Window size of the headless browser, CSS pixels (device pixel ratio 1).
pub const WIDTH: u32 = 960;
pub const HEIGHT: u32 = 640;
/// Longest a single browser run may take before the test fails (a
/// SwiftShader page load takes ~1 s here).
pub const BROWSER_TIMEOUT: Duration = Duration::from_secs(90);

pub fn chromium() -> PathBuf {
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

/// A fresh directory `base/softrod-browser-<pid>-<name>` (pass the test's
/// `env!("CARGO_TARGET_TMPDIR")` as `base`).
pub fn scratch(base: &str, name: &str) -> PathBuf {
    let d = Path::new(base).join(format!("softrod-browser-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs chromium headless with the flags the machine notes give (no
/// network chatter, fresh profile) plus `extra`; returns stdout.
pub fn run_browser(dir: &Path, tag: &str, window: (u32, u32), extra: &[String]) -> String {
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

pub fn url(page: &Path, hash: &str) -> String {
    format!("file://{}#{hash}", page.display())
}

/// The page's status marker after load.
pub struct Status {
    pub viewport: (u32, u32),
    pub errors: usize,
    pub ready: bool,
    pub frame: i64,
    pub tips: Vec<(f64, f64)>,
    pub error_text: String,
}

pub fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!("{name}=\"");
    let i = tag.find(&key)? + key.len();
    let j = tag[i..].find('"')? + i;
    Some(tag[i..j].to_string())
}

/// The page's status after load, in a viewport of `WIDTH × HEIGHT` like the
/// screenshots. `--dump-dom` gives the page a window less the browser's
/// frame (960×640 → 960×497 seen here), `--screenshot` the whole window, so
/// the window is enlarged by the difference the page reports.
pub fn status(dir: &Path, page: &Path, hash: &str, tag: &str) -> Status {
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

pub fn status_in(dir: &Path, page: &Path, hash: &str, tag: &str, window: (u32, u32)) -> Status {
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

pub struct Image {
    pub w: usize,
    pub h: usize,
    pub rgb: Vec<[u8; 3]>,
}

pub fn screenshot(dir: &Path, page: &Path, hash: &str, tag: &str) -> Image {
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
pub fn rod_pixel(p: [u8; 3]) -> bool {
    let [r, g, b] = p.map(f64::from);
    b > 40.0 && (0.52..0.80).contains(&(g / b)) && r / b < 0.45
}

/// Rod pixels within `radius` px of `(x, y)`.
pub fn rod_pixels_near(img: &Image, (x, y): (f64, f64), radius: f64) -> usize {
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

/// One `<text>` of an SVG figure: its anchor point (px), `text-anchor`,
/// whether it is rotated (a vertical axis label), and its text.
#[derive(Debug, Clone, PartialEq)]
pub struct SvgText {
    pub x: f64,
    pub y: f64,
    pub anchor: String,
    pub rotated: bool,
    pub text: String,
}

/// Every `<text>` element of `svg`, in document order.
pub fn svg_texts(svg: &str) -> Vec<SvgText> {
    svg.split("<text")
        .skip(1)
        .map(|t| {
            let end = t.find('>').expect("a closed <text> tag");
            let tag = &t[..end];
            let num = |k: &str| attr(tag, &format!(" {k}")).and_then(|v| v.parse().ok());
            let close = t.find("</text>").expect("a </text>");
            SvgText {
                x: num("x").unwrap_or(f64::NAN),
                y: num("y").unwrap_or(f64::NAN),
                anchor: attr(tag, " text-anchor").unwrap_or_default(),
                rotated: tag.contains("rotate("),
                text: t[end + 1..close].trim().to_string(),
            }
        })
        .collect()
}

/// Centres (px) of the outlined (`fill="none"`) rectangles of `svg`: the
/// rigid bodies' marks of the shape figures and their legend swatch.
pub fn svg_outlined_rect_centres(svg: &str) -> Vec<(f64, f64)> {
    svg.split("<rect")
        .skip(1)
        .map(|r| &r[..r.find('>').expect("a closed <rect> tag")])
        .filter(|t| t.contains("fill=\"none\""))
        .map(|t| {
            let num = |k: &str| -> f64 {
                attr(t, &format!(" {k}"))
                    .and_then(|v| v.parse().ok())
                    .unwrap_or_else(|| panic!("<rect{t}> has no number {k}"))
            };
            (
                num("x") + 0.5 * num("width"),
                num("y") + 0.5 * num("height"),
            )
        })
        .collect()
}
