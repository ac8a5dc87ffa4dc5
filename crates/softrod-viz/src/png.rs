//! PNG copies of the SVG figures (`--png`), rasterized with `resvg` (pure
//! Rust: `usvg` parses, `tiny-skia` draws).
//!
//! Text needs a font: the system's fonts are loaded (fontconfig's
//! directories, e.g. Debian's DejaVu / Liberation), the generic
//! `sans-serif` of the figures mapped to the first of [`SANS`] found. A
//! machine with no font at all still gets the PNG, without its text;
//! [`Rendered::text_drawn`] says so, and the CLI warns.

use std::path::{Path, PathBuf};

use resvg::{tiny_skia, usvg};

/// Families tried, in order, for the figures' `sans-serif`.
pub const SANS: [&str; 5] = [
    "DejaVu Sans",
    "Liberation Sans",
    "Arial",
    "Helvetica",
    "Noto Sans",
];

/// What one rasterization produced.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The PNG written.
    pub path: PathBuf,
    /// Pixels, the SVG's user units at 1 px each.
    pub width: u32,
    /// See `width`.
    pub height: u32,
    /// Whether a font was found for the figure's text.
    pub text_drawn: bool,
}

/// A font database with the system's fonts and `sans-serif` mapped to a
/// family that exists (loaded once per call of [`svg_to_png_all`]).
fn fonts() -> (usvg::fontdb::Database, bool) {
    let mut db = usvg::fontdb::Database::new();
    db.load_system_fonts();
    let have = |name: &str| {
        db.faces()
            .any(|f| f.families.iter().any(|(n, _)| n == name))
    };
    let sans = SANS.iter().find(|n| have(n)).map(|s| s.to_string());
    let any = db.faces().next().map(|f| f.families[0].0.clone());
    let family = sans.or(any);
    let found = family.is_some();
    if let Some(f) = family {
        db.set_sans_serif_family(f.clone());
        db.set_serif_family(f);
    }
    (db, found)
}

/// Rasterizes each SVG file to `NAME.png` beside it; a PNG that cannot be
/// written completely is removed.
pub fn svg_to_png_all(svgs: &[PathBuf]) -> Result<Vec<Rendered>, String> {
    let (db, found) = fonts();
    let mut opt = usvg::Options::default();
    *opt.fontdb_mut() = db;
    opt.font_family = SANS[0].to_string();
    svgs.iter().map(|p| render(p, &opt, found)).collect()
}

fn render(svg: &Path, opt: &usvg::Options, text: bool) -> Result<Rendered, String> {
    let data = std::fs::read(svg).map_err(|e| format!("{}: {e}", svg.display()))?;
    let tree = usvg::Tree::from_data(&data, opt).map_err(|e| format!("{}: {e}", svg.display()))?;
    let size = tree.size().to_int_size();
    let mut pixmap = tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| format!("{}: empty figure", svg.display()))?;
    resvg::render(&tree, tiny_skia::Transform::default(), &mut pixmap.as_mut());
    let path = svg.with_extension("png");
    let bytes = pixmap
        .encode_png()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    std::fs::write(&path, bytes).map_err(|e| {
        let _ = std::fs::remove_file(&path);
        format!("writing {}: {e}", path.display())
    })?;
    Ok(Rendered {
        path,
        width: size.width(),
        height: size.height(),
        text_drawn: text,
    })
}
