//! The animated 3-D view: one self-contained HTML file (inline CSS, inline
//! WebGL 1 code of our own, the data as embedded JSON; no network access).
//!
//! # Budget
//!
//! A view keeps at most [`ViewOptions::max_frames`] frames (default
//! [`DEFAULT_MAX_FRAMES`] = 2000) spread evenly over the output times, the
//! first and last always included ([`crate::decimate::spread`]), and the
//! whole file stays within [`ViewOptions::max_bytes`] (default
//! [`DEFAULT_MAX_BYTES`] = 30 MB): when the frames would not fit, fewer are
//! kept. Tip traces keep up to [`ViewOptions::max_trace_points`] points
//! (default 20 000) each, independently. The page says how many frames of how
//! many it shows.
//!
//! # Embedded data (`<script type="application/json" id="softrod-data">`)
//!
//! Positions are integers `round((p − origin) / quantum)` with a power-of-two
//! `quantum` about 2⁻²⁰ of the scene's extent (a relative resolution of
//! ~1e-6, far below a pixel), quaternions are integers `round(10⁴ · q)` with
//! `w ≥ 0`. Keys:
//!
//! ```text
//! format "softrod-view", version 1, title, up [3], origin [3] (m), quantum (m),
//! quatScale 10000, sourceFrames M, frames [indices into the M output times],
//! times [s, one per kept frame], budget {maxFrames, maxBytes, maxTracePoints},
//! options {speed (null = auto), axes (bool)},
//! rods [{name, s [m], radius [m], frames [[x,y,z,qw,qx,qy,qz] × samples, one array per kept frame],
//!        trace {t [s], p [x,y,z,…]}}],
//! cables [{name, frames [[x,y,z,…] per kept frame]}],
//! bodies [{name, shape "box"|"sphere", size [3] | radius, frames [[x,y,z,qw,qx,qy,qz] per kept frame]}],
//! obstacles [{name, shape, mesh [x,y,z,nx,ny,nz, … per vertex] (m; relative to origin when fixed,
//!             in the carrier's frame when carried), triangles [i, j, k, …],
//!             frames null (fixed) | [[x,y,z,qw,qx,qy,qz] of the carrier per kept frame]}]
//! ```
//!
//! Obstacle meshes come from [`crate::obstacles::mesh`]: planes and
//! cylinders over the region around the rods and bodies.
//!
//! The output is deterministic: the same data and options give the same
//! bytes (no clock, no random numbers, no hash-map order).

use std::fmt::Write as _;
use std::path::Path;

use crate::data::{BodyShape, Pose, ViewData};
use crate::decimate::spread;
use crate::error::VizError;

/// Default most frames a view keeps.
pub const DEFAULT_MAX_FRAMES: usize = 2000;
/// Default largest file, bytes (30 MB: a browser parses it in about a second).
pub const DEFAULT_MAX_BYTES: usize = 30_000_000;
/// Default most points of each tip trace.
pub const DEFAULT_MAX_TRACE_POINTS: usize = 20_000;
/// Quaternion components are stored as integers of this many units.
pub const QUAT_SCALE: f64 = 10_000.0;
/// Positions are stored in units of about `extent · 2^-QUANT_BITS`.
pub const QUANT_BITS: i32 = 20;

/// How the view is built.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewOptions {
    /// Most frames kept (≥ 2).
    pub max_frames: usize,
    /// Largest file size, bytes.
    pub max_bytes: usize,
    /// Most points kept of each tip trace (≥ 2).
    pub max_trace_points: usize,
    /// Initial playback speed (simulated seconds per wall second); `None`:
    /// chosen so the run plays in about 10 s.
    pub speed: Option<f64>,
    /// Show the centreline frame axes at start.
    pub show_frame_axes: bool,
}

impl Default for ViewOptions {
    fn default() -> Self {
        Self {
            max_frames: DEFAULT_MAX_FRAMES,
            max_bytes: DEFAULT_MAX_BYTES,
            max_trace_points: DEFAULT_MAX_TRACE_POINTS,
            speed: None,
            show_frame_axes: false,
        }
    }
}

/// What [`render_html`] kept.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewStats {
    /// Indices of the kept output times (first and last included).
    pub frames: Vec<usize>,
    /// Number of output times in the input.
    pub source_frames: usize,
    /// Size of the page, bytes.
    pub bytes: usize,
}

const TEMPLATE: &str = include_str!("assets/view.html");
const CSS: &str = include_str!("assets/view.css");
const JS: &str = include_str!("assets/view.js");
const GUARD_JS: &str = include_str!("assets/guard.js");

/// The page for `data`, and what it kept. Validates `data` first.
pub fn render_html(data: &ViewData, opts: &ViewOptions) -> Result<(String, ViewStats), VizError> {
    render_prepared(data, opts, None)
}

/// What a [`crate::collect::FrameCollector`] worked out about its rods'
/// frames while the run went on (on the run's writer thread), so that the
/// page after the run only quantizes positions: the same bytes as
/// [`render_html`] of the same data (tested), less work at the end.
pub(crate) struct Prepared<'a> {
    /// Per rod (in [`ViewData::rods`]'s order), the text [`push_rotation`]
    /// writes for each pose of each time of [`ViewData::times`].
    pub rotations: &'a [RotationText],
    /// Per time of [`ViewData::times`]: the lowest and highest coordinates
    /// of every rod's sample positions, `[lo, hi]` (m).
    pub boxes: &'a [[[f64; 3]; 2]],
}

/// The rotation text of one rod's poses, time after time (pose `j`
/// counts every pose of every time in order): what [`push_rotation`]
/// writes, each in a fixed slot (a unit quaternion's text never takes
/// more than [`ROTATION_TEXT`] bytes).
#[derive(Debug, Clone, Default)]
pub(crate) struct RotationText {
    pub slots: Vec<([u8; ROTATION_TEXT], u8)>,
}

impl RotationText {
    /// Appends the rotation text of `p`; false (nothing appended) if it
    /// does not fit a slot.
    pub fn push(&mut self, p: &Pose) -> bool {
        let mut line = [0u8; 4 * INT_TEXT];
        let end = put_rotation(&mut line, 0, &p.rotation);
        match line.get(..ROTATION_TEXT) {
            Some(head) if end <= ROTATION_TEXT => {
                let mut slot = [0u8; ROTATION_TEXT];
                slot.copy_from_slice(head);
                self.slots.push((slot, end as u8));
                true
            }
            _ => false,
        }
    }
}

/// [`render_html`], with what a collector prepared (`None`: nothing).
/// Prepared frames were checked as they came (finite, non-zero rotation):
/// their poses are not checked again.
pub(crate) fn render_prepared(
    data: &ViewData,
    opts: &ViewOptions,
    pre: Option<&Prepared<'_>>,
) -> Result<(String, ViewStats), VizError> {
    data.validate_frames(pre.is_none())?;
    if opts.max_frames < 2 || opts.max_trace_points < 2 {
        return Err(VizError::Invalid {
            what: "ViewOptions".into(),
            problem: format!(
                "max_frames = {} and max_trace_points = {} must be ≥ 2",
                opts.max_frames, opts.max_trace_points
            ),
        });
    }
    if let Some(v) = opts.speed.filter(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(VizError::Invalid {
            what: "ViewOptions::speed".into(),
            problem: format!("{v} (must be finite and > 0)"),
        });
    }
    let m = data.times.len();
    let q = Quantizer::new(data, pre.map(|p| p.boxes));
    let mut n = opts.max_frames.min(m);
    loop {
        let frames = spread(m, n);
        let page = assemble(data, opts, &q, &frames, pre);
        if page.len() <= opts.max_bytes {
            let bytes = page.len();
            return Ok((
                page,
                ViewStats {
                    frames,
                    source_frames: m,
                    bytes,
                },
            ));
        }
        if n <= 2 {
            return Err(VizError::TooLarge {
                bytes: page.len(),
                max_bytes: opts.max_bytes,
            });
        }
        // Per-frame bytes are nearly equal; shrink to fit with 2 % margin.
        let fixed = assemble(data, opts, &q, &[], pre).len();
        let per = (page.len() - fixed.min(page.len())) as f64 / n as f64;
        let fit = ((opts.max_bytes.saturating_sub(fixed)) as f64 / per * 0.98).floor() as usize;
        n = fit.clamp(2, n - 1);
    }
}

/// [`render_html`] written to `path`.
pub fn write_html(path: &Path, data: &ViewData, opts: &ViewOptions) -> Result<ViewStats, VizError> {
    write_prepared(path, data, opts, None)
}

/// [`write_html`] with what a collector prepared (see [`render_prepared`]).
pub(crate) fn write_prepared(
    path: &Path,
    data: &ViewData,
    opts: &ViewOptions,
    pre: Option<&Prepared<'_>>,
) -> Result<ViewStats, VizError> {
    let (page, stats) = render_prepared(data, opts, pre)?;
    std::fs::write(path, page).map_err(|source| VizError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(stats)
}

/// Maps world positions to integers.
struct Quantizer {
    origin: [f64; 3],
    quantum: f64,
}

impl Quantizer {
    /// From the extent of everything drawn; `boxes`: per time, the extent
    /// of the rods' sample positions (see [`Prepared::boxes`]): the same
    /// lowest and highest coordinates as the frames themselves give (the
    /// positions are finite and `−0` is written `0`, so the order of `min`
    /// and `max` does not matter).
    fn new(d: &ViewData, boxes: Option<&[[[f64; 3]; 2]]>) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut add = |p: &[f64; 3]| {
            for ((l, h), v) in lo.iter_mut().zip(hi.iter_mut()).zip(p) {
                *l = l.min(*v);
                *h = h.max(*v);
            }
        };
        match boxes {
            Some(boxes) => {
                for [l, h] in boxes {
                    add(l);
                    add(h);
                }
            }
            None => {
                for rod in &d.rods {
                    rod.frames.iter().flatten().for_each(|f| add(&f.position));
                }
            }
        }
        for rod in &d.rods {
            rod.tip_trace.iter().flatten().for_each(&mut add);
        }
        d.cables
            .iter()
            .flat_map(|c| c.points.iter().flatten())
            .for_each(&mut add);
        d.bodies
            .iter()
            .flat_map(|b| &b.poses)
            .for_each(|p| add(&p.position));
        let origin = [0, 1, 2].map(|j| 0.5 * (lo[j] + hi[j]));
        let extent = (0..3).map(|j| 0.5 * (hi[j] - lo[j])).fold(0.0, f64::max);
        let extent = if extent > 0.0 { extent } else { 1.0 };
        let quantum = 2f64.powi(extent.log2().ceil() as i32 - QUANT_BITS);
        Self { origin, quantum }
    }

    fn push_point(&self, out: &mut String, p: &[f64; 3]) {
        let mut line = [0u8; 3 * INT_TEXT];
        let mut at = 0;
        for (x, o) in p.iter().zip(&self.origin) {
            at = put_int(&mut line, at, round_to_i64((x - o) / self.quantum));
        }
        out.push_str(ascii(&line[..at]));
    }

    fn push_pose(&self, out: &mut String, p: &Pose) {
        self.push_point(out, &p.position);
        push_rotation(out, &p.rotation);
    }

    /// [`Quantizer::push_pose`] of a pose at `position` whose rotation's
    /// text is `rotation` (a [`RotationText`] slot), into `line` at `at`;
    /// returns the end. `line` has `3·INT_TEXT + ROTATION_TEXT` bytes
    /// from `at`.
    #[inline(always)]
    fn put_pose_text(
        &self,
        line: &mut [u8],
        mut at: usize,
        position: &[f64; 3],
        rotation: &([u8; ROTATION_TEXT], u8),
    ) -> usize {
        for (x, o) in position.iter().zip(&self.origin) {
            at = put_int(line, at, round_to_i64((x - o) / self.quantum));
        }
        line[at..at + ROTATION_TEXT].copy_from_slice(&rotation.0);
        at + rotation.1 as usize
    }
}

/// The longest text [`put_int`] writes: `i64::MIN` and its comma.
const INT_TEXT: usize = 21;
/// The longest rotation text of a unit quaternion: four integers within
/// ±[`QUAT_SCALE`], each with its comma.
pub(crate) const ROTATION_TEXT: usize = 4 * 7;

/// `10^k` for `k` in `0..20`, and `u64::MAX` (no `u64` reaches it).
const POW10: [u64; 21] = {
    let mut p = [u64::MAX; 21];
    let mut k = 0;
    let mut v = 1u64;
    while k < 20 {
        p[k] = v;
        v = v.wrapping_mul(10);
        k += 1;
    }
    p
};

/// Two-digit groups, `"00"` to `"99"`.
const PAIRS: &[u8; 200] = b"0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Writes `v` in decimal (what `itoa` and `Display` write) and a comma at
/// `line[at..]`; returns the end. `line` has [`INT_TEXT`] bytes from `at`.
#[inline(always)]
fn put_int(line: &mut [u8], mut at: usize, v: i64) -> usize {
    if v < 0 {
        line[at] = b'-';
        at += 1;
    }
    let mut n = v.unsigned_abs();
    // The digit count from the bit length (1233/4096 ≈ log₁₀ 2), corrected
    // by one comparison.
    let bits = 64 - (n | 1).leading_zeros() as usize;
    let guess = (bits * 1233) >> 12;
    let digits = guess + usize::from(n >= POW10[guess]);
    let end = at + digits.max(1);
    let mut i = end;
    while n >= 100 {
        let d = (n % 100) as usize * 2;
        n /= 100;
        i -= 2;
        line[i] = PAIRS[d];
        line[i + 1] = PAIRS[d + 1];
    }
    if n >= 10 {
        let d = n as usize * 2;
        line[i - 2] = PAIRS[d];
        line[i - 1] = PAIRS[d + 1];
    } else {
        line[i - 1] = b'0' + n as u8;
    }
    line[end] = b',';
    end + 1
}

/// A rotation as the page holds it, at `line[at..]` (which has
/// `4·INT_TEXT` bytes): the quaternion normalized, with `w ≥ 0`, each
/// component as `round(10⁴ · q)` and its comma. Returns the end.
#[inline(always)]
fn put_rotation(line: &mut [u8], mut at: usize, r: &[f64; 4]) -> usize {
    let n = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3]).sqrt();
    let sign = if r[0] < 0.0 { -1.0 } else { 1.0 };
    for v in r {
        at = put_int(line, at, round_to_i64(sign * v / n * QUAT_SCALE));
    }
    at
}

/// [`put_rotation`] appended to `out`.
fn push_rotation(out: &mut String, r: &[f64; 4]) {
    let mut line = [0u8; 4 * INT_TEXT];
    let end = put_rotation(&mut line, 0, r);
    out.push_str(ascii(&line[..end]));
}

/// `bytes` as text: only ASCII digits, signs and commas are put there.
fn ascii(bytes: &[u8]) -> &str {
    std::str::from_utf8(bytes).unwrap_or_default()
}

/// `x.round() as i64` (halves away from zero, saturating) without a call:
/// x86-64's baseline has no rounding instruction, so `f64::round` is a
/// library call, and the page rounds seven numbers per sample and frame.
/// Truncation is exact and `x − trunc(x)` is exact for `|x| < 2⁵²` (above
/// it `x` is an integer and the difference is 0, or `trunc` saturated).
#[inline(always)]
fn round_to_i64(x: f64) -> i64 {
    let t = x as i64;
    let frac = x - t as f64;
    if frac >= 0.5 {
        t.saturating_add(1)
    } else if frac <= -0.5 {
        t.saturating_sub(1)
    } else {
        t
    }
}

fn close_array(out: &mut String) {
    if out.ends_with(',') {
        out.pop();
    }
    out.push(']');
}

/// `s` as a JSON string, `<` escaped (`\u003c`): with it a name such as
/// "</script>" cannot close the data block. Every string of the embedded
/// data goes through here; nothing else there holds a `<`.
pub(crate) fn json_str(s: &str) -> String {
    serde_json::to_string(s)
        .unwrap_or_else(|_| "\"\"".into())
        .replace('<', "\\u003c")
}

fn json_f64s(out: &mut String, v: impl Iterator<Item = f64>) {
    out.push('[');
    for x in v {
        // serde_json prints the shortest representation that reads back
        // exactly (ryu): deterministic.
        let _ = write!(out, "{},", serde_json::Value::from(x));
    }
    close_array(out);
}

/// Appends the embedded JSON for the kept `frames` to `o`.
fn data_json(
    o: &mut String,
    d: &ViewData,
    opts: &ViewOptions,
    q: &Quantizer,
    frames: &[usize],
    pre: Option<&Prepared<'_>>,
) {
    let up_n = d.up.iter().map(|v| v * v).sum::<f64>().sqrt();
    let _ = write!(
        o,
        "{{\"format\":\"softrod-view\",\"version\":1,\"title\":{},\"up\":",
        json_str(&d.title)
    );
    json_f64s(o, d.up.iter().map(|v| v / up_n));
    o.push_str(",\"origin\":");
    json_f64s(o, q.origin.iter().copied());
    let _ = write!(
        o,
        ",\"quantum\":{},\"quatScale\":{},\"sourceFrames\":{},\"frames\":[",
        serde_json::Value::from(q.quantum),
        QUAT_SCALE,
        d.times.len()
    );
    for k in frames {
        let _ = write!(o, "{k},");
    }
    close_array(o);
    o.push_str(",\"times\":");
    json_f64s(o, frames.iter().map(|&k| d.times[k]));
    let _ = write!(
        o,
        ",\"budget\":{{\"maxFrames\":{},\"maxBytes\":{},\"maxTracePoints\":{}}}",
        opts.max_frames, opts.max_bytes, opts.max_trace_points
    );
    let _ = write!(
        o,
        ",\"options\":{{\"speed\":{},\"axes\":{}}}",
        opts.speed
            .map(|v| serde_json::Value::from(v).to_string())
            .unwrap_or_else(|| "null".into()),
        opts.show_frame_axes
    );
    o.push_str(",\"rods\":[");
    let trace_idx = spread(d.times.len(), opts.max_trace_points);
    for (r, rod) in d.rods.iter().enumerate() {
        let _ = write!(o, "{{\"name\":{},\"s\":", json_str(&rod.name));
        json_f64s(o, rod.s.iter().copied());
        o.push_str(",\"radius\":");
        json_f64s(o, rod.radius.iter().copied());
        o.push_str(",\"frames\":[");
        let rotations = pre.map(|p| &p.rotations[r]);
        let mut frame: Vec<u8> = Vec::new();
        for &k in frames {
            o.push('[');
            match rotations {
                Some(text) => {
                    // A frame's text is made in bytes, a pose at a time,
                    // and appended at once (one check that it is text).
                    let first = k * rod.s.len();
                    let slots = &text.slots[first..first + rod.s.len()];
                    frame.clear();
                    for (p, rotation) in rod.frames[k].iter().zip(slots) {
                        let mut line = [0u8; 3 * INT_TEXT + ROTATION_TEXT];
                        let end = q.put_pose_text(&mut line, 0, &p.position, rotation);
                        frame.extend_from_slice(&line[..end]);
                    }
                    o.push_str(ascii(&frame));
                }
                None => {
                    for p in &rod.frames[k] {
                        q.push_pose(o, p);
                    }
                }
            }
            close_array(o);
            o.push(',');
        }
        close_array(o);
        o.push_str(",\"trace\":{\"t\":");
        json_f64s(o, trace_idx.iter().map(|&k| d.times[k]));
        o.push_str(",\"p\":[");
        for &k in &trace_idx {
            let p = match &rod.tip_trace {
                Some(t) => t[k],
                None => rod.frames[k][rod.s.len() - 1].position,
            };
            q.push_point(o, &p);
        }
        close_array(o);
        o.push_str("}},");
    }
    close_array(o);
    o.push_str(",\"cables\":[");
    for c in &d.cables {
        let _ = write!(o, "{{\"name\":{},\"frames\":[", json_str(&c.name));
        for &k in frames {
            o.push('[');
            for p in &c.points[k] {
                q.push_point(o, p);
            }
            close_array(o);
            o.push(',');
        }
        close_array(o);
        o.push_str("},");
    }
    close_array(o);
    o.push_str(",\"bodies\":[");
    for b in &d.bodies {
        let _ = write!(o, "{{\"name\":{},", json_str(&b.name));
        match b.shape {
            BodyShape::Box { size } => {
                o.push_str("\"shape\":\"box\",\"size\":");
                json_f64s(o, size.into_iter());
            }
            BodyShape::Sphere { radius } => {
                let _ = write!(
                    o,
                    "\"shape\":\"sphere\",\"radius\":{}",
                    serde_json::Value::from(radius)
                );
            }
        }
        o.push_str(",\"frames\":[");
        for &k in frames {
            o.push('[');
            q.push_pose(o, &b.poses[k]);
            close_array(o);
            o.push(',');
        }
        close_array(o);
        o.push_str("},");
    }
    close_array(o);
    o.push_str(",\"obstacles\":");
    crate::obstacles::push_view_json(o, d, frames, q.origin, &|o: &mut String, p: &Pose| {
        q.push_pose(o, p)
    });
    o.push('}');
}

fn html_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            _ => o.push(c),
        }
    }
    o
}

/// The page: the template's `@@NAME@@` markers replaced in one pass over
/// the template (so a marker inside the data is never expanded).
fn assemble(
    d: &ViewData,
    opts: &ViewOptions,
    q: &Quantizer,
    frames: &[usize],
    pre: Option<&Prepared<'_>>,
) -> String {
    let title = html_escape(&d.title);
    // The data is written in place, where its marker stands; its size is
    // about seven integers of four to seven digits per pose.
    let poses: usize = d.rods.iter().map(|r| r.s.len()).sum::<usize>() + d.bodies.len();
    let guess = 32 * poses * frames.len();
    let mut out =
        String::with_capacity(guess + TEMPLATE.len() + CSS.len() + JS.len() + GUARD_JS.len());
    let mut rest = TEMPLATE;
    while let Some(i) = rest.find("@@") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let Some(j) = after.find("@@") else {
            out.push_str(&rest[i..]);
            rest = "";
            break;
        };
        match &after[..j] {
            "TITLE" => out.push_str(&title),
            "CSS" => out.push_str(CSS),
            "GUARD" => out.push_str(GUARD_JS),
            "JS" => out.push_str(JS),
            "DATA" => data_json(&mut out, d, opts, q, frames, pre),
            other => {
                out.push_str("@@");
                out.push_str(other);
                out.push_str("@@");
            }
        }
        rest = &after[j + 2..];
    }
    out.push_str(rest);
    out
}

/// The JSON embedded in a page written by [`render_html`], parsed (for
/// tests and tools that read a view back).
pub fn embedded_data(page: &str) -> Option<serde_json::Value> {
    let start_tag = "<script type=\"application/json\" id=\"softrod-data\">";
    let i = page.find(start_tag)? + start_tag.len();
    let j = page[i..].find("</script>")? + i;
    serde_json::from_str(&page[i..j]).ok()
}

#[cfg(test)]
mod tests {
    use super::{INT_TEXT, put_int, round_to_i64};

    /// The page's integer text is the standard library's (`Display`,
    /// what `itoa` writes), each with its comma.
    #[test]
    fn integers_are_written_as_the_standard_library_writes_them() {
        let mut vs = vec![
            0,
            1,
            -1,
            9,
            10,
            -10,
            99,
            100,
            i64::MAX,
            i64::MIN,
            i64::MIN + 1,
        ];
        for d in 1..19 {
            let p = 10i64.pow(d);
            vs.extend([p - 1, p, p + 1, -p + 1, -p, -p - 1]);
        }
        let mut u = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..100_000 {
            u ^= u << 13;
            u ^= u >> 7;
            u ^= u << 17;
            vs.push(u as i64);
            vs.push((u as i64) >> (u % 64));
        }
        for v in vs {
            let mut line = [0u8; 3 + INT_TEXT];
            let end = put_int(&mut line, 3, v);
            assert_eq!(&line[3..end], format!("{v},").as_bytes(), "v = {v}");
        }
    }

    /// Against the standard library's `round` and `as` on halves, values
    /// next to halves, integers beyond 2⁵², saturation and NaN, and a
    /// sweep of scaled values like the page's.
    #[test]
    fn rounding_matches_the_standard_library() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            4503599627370497.0,
            9007199254740993.0,
            9.3e18,
            -9.3e18,
            1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
        ];
        let mut u = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..100_000 {
            u ^= u << 13;
            u ^= u >> 7;
            u ^= u << 17;
            let r = (u >> 11) as f64 / (1u64 << 53) as f64;
            xs.push((r - 0.5) * 2.0 * 1_048_576.0);
            xs.push(((r * 20_000.0).floor() - 10_000.0) + 0.5);
        }
        for x in xs {
            assert_eq!(round_to_i64(x), x.round() as i64, "x = {x:e}");
        }
    }
}
