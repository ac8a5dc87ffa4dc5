//! `trajectory.npz`: the trajectory as a NumPy `.npz` archive (a zip of
//! `.npy` files), for runs too large to parse as CSV.
//!
//! Written by hand rather than with a crate: `.npy` v1.0 is a 10-byte
//! preamble and a Python-literal header, and an `.npz` that `numpy.load`
//! reads needs only *stored* (uncompressed) zip entries, a few dozen lines;
//! the `zip` / `npyz` crates would add a compression stack and a dozen
//! crates to the build for that. The CRC-32 comes from `crc32fast`, already
//! in the dependency tree (via `png`).
//!
//! Entries are plain zip (not zip64), so each array and the whole archive
//! must stay below 4 GiB; [`check_size`] refuses a larger run up front.

use std::io::{self, Write};

/// The arrays of one archive, in order: `(name, array)`.
pub struct Archive {
    entries: Vec<(String, Vec<u8>)>,
}

/// Largest size a plain (non-zip64) zip can describe, bytes.
pub const ZIP_LIMIT: u64 = u32::MAX as u64;

impl Archive {
    pub fn new() -> Self {
        Self {
            entries: Vec::new(),
        }
    }

    /// Adds `NAME.npy`: a C-order little-endian `f64` array of `shape`
    /// (`data.len()` must be the product of `shape`).
    pub fn add_f64(&mut self, name: &str, shape: &[usize], data: &[f64]) {
        debug_assert_eq!(shape.iter().product::<usize>(), data.len());
        let mut bytes = npy_header("<f8", shape);
        bytes.reserve(8 * data.len());
        for v in data {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        self.entries.push((format!("{name}.npy"), bytes));
    }

    /// Adds `NAME.npy`: a 1-D unicode array (`<U{n}`, UTF-32LE, each string
    /// zero-padded to the longest one's code points, as NumPy stores `str`).
    pub fn add_strings(&mut self, name: &str, strings: &[String]) {
        let width = strings
            .iter()
            .map(|s| s.chars().count())
            .max()
            .unwrap_or(0)
            .max(1);
        let mut bytes = npy_header(&format!("<U{width}"), &[strings.len()]);
        for s in strings {
            let mut n = 0;
            for c in s.chars() {
                bytes.extend_from_slice(&(c as u32).to_le_bytes());
                n += 1;
            }
            bytes.resize(bytes.len() + 4 * (width - n), 0);
        }
        self.entries.push((format!("{name}.npy"), bytes));
    }

    /// Writes the archive (stored zip entries, a central directory).
    pub fn write_to(&self, w: &mut impl Write) -> io::Result<()> {
        let mut offset: u64 = 0;
        let mut central = Vec::new();
        for (name, data) in &self.entries {
            let crc = crc32fast::hash(data);
            let size = u32::try_from(data.len()).map_err(|_| too_large())?;
            let at = u32::try_from(offset).map_err(|_| too_large())?;
            let name_len = u16::try_from(name.len()).map_err(|_| too_large())?;
            // Local file header (APPNOTE 4.3.7): version 2.0, no flags,
            // method 0 (stored), DOS time 0 / date 1980-01-01.
            let mut local = Vec::with_capacity(30 + name.len());
            local.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
            local.extend_from_slice(&20u16.to_le_bytes());
            local.extend_from_slice(&0u16.to_le_bytes());
            local.extend_from_slice(&0u16.to_le_bytes());
            local.extend_from_slice(&DOS_DATE.to_le_bytes());
            local.extend_from_slice(&crc.to_le_bytes());
            local.extend_from_slice(&size.to_le_bytes());
            local.extend_from_slice(&size.to_le_bytes());
            local.extend_from_slice(&name_len.to_le_bytes());
            local.extend_from_slice(&0u16.to_le_bytes());
            local.extend_from_slice(name.as_bytes());
            w.write_all(&local)?;
            w.write_all(data)?;
            // Central directory header (APPNOTE 4.3.12).
            central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
            central.extend_from_slice(&20u16.to_le_bytes());
            central.extend_from_slice(&20u16.to_le_bytes());
            central.extend_from_slice(&0u16.to_le_bytes());
            central.extend_from_slice(&0u16.to_le_bytes());
            central.extend_from_slice(&DOS_DATE.to_le_bytes());
            central.extend_from_slice(&crc.to_le_bytes());
            central.extend_from_slice(&size.to_le_bytes());
            central.extend_from_slice(&size.to_le_bytes());
            central.extend_from_slice(&name_len.to_le_bytes());
            central.extend_from_slice(&[0; 8]); // extra, comment, disk, internal attributes
            central.extend_from_slice(&0u32.to_le_bytes()); // external attributes
            central.extend_from_slice(&at.to_le_bytes());
            central.extend_from_slice(name.as_bytes());
            offset += local.len() as u64 + data.len() as u64;
        }
        let cd_at = u32::try_from(offset).map_err(|_| too_large())?;
        let cd_len = u32::try_from(central.len()).map_err(|_| too_large())?;
        let n = u16::try_from(self.entries.len()).map_err(|_| too_large())?;
        w.write_all(&central)?;
        // End of central directory record (APPNOTE 4.3.16).
        let mut end = Vec::with_capacity(22);
        end.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
        end.extend_from_slice(&[0; 4]); // this disk, disk of the directory
        end.extend_from_slice(&n.to_le_bytes());
        end.extend_from_slice(&n.to_le_bytes());
        end.extend_from_slice(&cd_len.to_le_bytes());
        end.extend_from_slice(&cd_at.to_le_bytes());
        end.extend_from_slice(&0u16.to_le_bytes());
        w.write_all(&end)
    }
}

/// DOS time 00:00 (low half) and date 1980-01-01 (high half), the
/// earliest: the archive does not depend on when it was written.
const DOS_DATE: u32 = (1 << 5 | 1) << 16;

fn too_large() -> io::Error {
    io::Error::other("larger than 4 GiB, which a plain zip cannot hold")
}

/// An `.npy` v1.0 preamble and header for `descr` and `shape`, padded with
/// spaces to a multiple of 64 bytes and ended by `\n` (what NumPy writes).
fn npy_header(descr: &str, shape: &[usize]) -> Vec<u8> {
    let dims = match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut dict = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {dims}, }}");
    let unpadded = 10 + dict.len() + 1;
    dict.push_str(&" ".repeat(unpadded.next_multiple_of(64) - unpadded));
    dict.push('\n');
    let mut out = Vec::with_capacity(10 + dict.len());
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    // Header lengths are far below 65 536 (a short dict).
    out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out
}

/// Bytes of the archive of a run with `rows` output times and `columns`
/// numbers per row (all arrays together, headers aside): refused (exit 2,
/// naming `--npz`) when a plain zip cannot hold it.
pub fn check_size(rows: u64, columns: usize) -> Result<(), String> {
    // Headers, names: a few kB at most.
    let bytes = rows
        .saturating_mul(8 * columns as u64)
        .saturating_add(1 << 16);
    if bytes > ZIP_LIMIT {
        return Err(format!(
            "--npz: {rows} output rows of {columns} numbers need {bytes} bytes, more than the \
             4 GiB a plain zip holds; sample less often or use trajectory.csv alone"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headers_are_aligned_and_say_what_numpy_expects() {
        for (descr, shape) in [("<f8", vec![3]), ("<f8", vec![0, 5]), ("<U12", vec![7])] {
            let h = npy_header(descr, &shape);
            assert_eq!(h.len() % 64, 0);
            assert_eq!(&h[..8], b"\x93NUMPY\x01\x00");
            assert_eq!(u16::from_le_bytes([h[8], h[9]]) as usize, h.len() - 10);
            assert_eq!(*h.last().unwrap(), b'\n');
        }
        let h = npy_header("<f8", &[4]);
        let text = std::str::from_utf8(&h[10..]).unwrap();
        assert!(text.starts_with("{'descr': '<f8', 'fortran_order': False, 'shape': (4,), }"));
    }

    #[test]
    fn the_crc_is_the_standard_one() {
        // The CRC-32 (ISO-HDLC) check value.
        assert_eq!(crc32fast::hash(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn the_size_check_refuses_what_a_plain_zip_cannot_hold() {
        assert!(check_size(1000, 50).is_ok());
        let e = check_size(100_000_000, 50).unwrap_err();
        assert!(e.starts_with("--npz:"), "{e}");
    }
}
