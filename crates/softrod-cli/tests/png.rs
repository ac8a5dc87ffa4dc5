//! `--png`: every SVG figure gets a PNG beside it, decoded here with the
//! `png` crate: the SVG's size, the first series colour (a rod in the tip
//! and mode figures) where the SVG draws it (≥ 90 % of the points along its
//! solid polylines; later markers may cover a few), and dark text pixels in
//! the title band (a font was found).

mod common;

use std::path::Path;

use common::*;

/// The rods' colour in the figures (softrod-viz's first palette colour).
const ROD: [u8; 3] = [0x1F, 0x77, 0xB4];

struct Image {
    width: usize,
    height: usize,
    rgba: Vec<u8>,
}

impl Image {
    fn read(path: &Path) -> Self {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgba, "{}", path.display());
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        buf.truncate(info.buffer_size());
        Self {
            width: info.width as usize,
            height: info.height as usize,
            rgba: buf,
        }
    }

    fn px(&self, x: usize, y: usize) -> [u8; 4] {
        let i = 4 * (y * self.width + x);
        self.rgba[i..i + 4].try_into().unwrap()
    }

    /// Whether a pixel within one of (x, y) is close to `c`.
    fn near(&self, x: f64, y: f64, c: [u8; 3]) -> bool {
        let (x, y) = (x.round() as i64, y.round() as i64);
        (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                let (u, v) = (x + dx, y + dy);
                if u < 0 || v < 0 || u >= self.width as i64 || v >= self.height as i64 {
                    return false;
                }
                let p = self.px(u as usize, v as usize);
                (0..3).all(|k| (p[k] as i32 - c[k] as i32).abs() <= 24)
            })
        })
    }
}

/// `width`, `height` of the root `<svg>`.
fn svg_size(svg: &str) -> (usize, usize) {
    let attr = |name: &str| -> usize {
        let at = svg.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        svg[at..at + svg[at..].find('"').unwrap()].parse().unwrap()
    };
    (attr("width"), attr("height"))
}

/// Points along the solid polylines drawn in the rod colour: their
/// vertices and, between them, a point every 4 px or less (the curves are
/// decimated, so few vertices can stand for a long stretch; a dashed
/// line's points may fall in its gaps and are left out).
fn rod_vertices(svg: &str) -> Vec<(f64, f64)> {
    let stroke = format!("stroke=\"#{:02X}{:02X}{:02X}\"", ROD[0], ROD[1], ROD[2]);
    svg.split("<polyline")
        .skip(1)
        .map(|e| &e[..e.find('>').unwrap()])
        .filter(|tag| tag.contains(&stroke) && !tag.contains("stroke-dasharray"))
        .flat_map(|tag| {
            let at = tag.find("points=\"").unwrap() + 8;
            let pts: Vec<(f64, f64)> = tag[at..at + tag[at..].find('"').unwrap()]
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect();
            let mut along = pts[..1].to_vec();
            for w in pts.windows(2) {
                let ((x0, y0), (x1, y1)) = (w[0], w[1]);
                let n = ((x1 - x0).hypot(y1 - y0) / 4.0).ceil().max(1.0) as usize;
                along.extend((1..=n).map(|k| {
                    let u = k as f64 / n as f64;
                    (x0 + u * (x1 - x0), y0 + u * (y1 - y0))
                }));
            }
            along
        })
        .collect()
}

/// Checks `NAME.png` against `NAME.svg` in `dir`; returns how many rod
/// vertices were checked.
fn check_png(dir: &Path, name: &str, text: bool) -> usize {
    let svg = std::fs::read_to_string(dir.join(format!("{name}.svg"))).unwrap();
    let img = Image::read(&dir.join(format!("{name}.png")));
    assert_eq!((img.width, img.height), svg_size(&svg), "{name}: size");
    let verts = rod_vertices(&svg);
    // Markers drawn later (the base dot, other series) may cover a few
    // vertices; nearly all must show the colour.
    let missing: Vec<_> = verts
        .iter()
        .filter(|&&(x, y)| !img.near(x, y, ROD))
        .collect();
    assert!(
        missing.len() <= (verts.len() / 10).max(1),
        "{name}: no stroke colour at {} of {} vertices: {missing:?}",
        missing.len(),
        verts.len()
    );
    // The title (dark text, top band) was drawn: a font was found.
    let dark = (0..40.min(img.height))
        .flat_map(|y| (0..img.width).map(move |x| (x, y)))
        .filter(|&(x, y)| img.px(x, y)[..3].iter().all(|&c| c < 80))
        .count();
    if text {
        assert!(dark > 100, "{name}: {dark} dark pixels in the title band");
    }
    verts.len()
}

#[test]
fn run_png_figures_match_their_svgs() {
    let dir = tmp("run");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.05\noutput_every = 0.01",
        &dir,
    );
    let out = dir.join("out");
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--png",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A machine without any font gets PNGs without text, and is told so.
    let text = !stderr(&o).contains("no font found");
    if !text {
        eprintln!("no system font: the text of the PNGs is not checked");
    }
    let mut svgs: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            n.strip_suffix(".svg").map(String::from)
        })
        .collect();
    svgs.sort();
    assert!(svgs.len() >= 4, "{svgs:?}");
    let rods: usize = svgs.iter().map(|n| check_png(&out, n, text)).sum();
    assert!(rods > 20, "rod vertices checked: {rods}");

    // Without --png the PNGs of the previous run go, like the SVGs.
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("shapes.png").exists());
}

/// `softrod COMMAND cantilever --out DIR --png`: its figure `NAME` as PNG.
fn command_png_matches_its_svg(command: &str, name: &str) {
    let dir = tmp(command);
    let out = dir.join("out");
    let scene = examples().join("cantilever_gravity.toml");
    let o = run(&[
        command,
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--png",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = !stderr(&o).contains("no font found");
    assert!(check_png(&out, name, text) > 10);
}

#[test]
fn statics_png_matches_its_svg() {
    command_png_matches_its_svg("statics", "statics_shape");
}

#[test]
fn modes_png_matches_its_svg() {
    command_png_matches_its_svg("modes", "modes");
}
