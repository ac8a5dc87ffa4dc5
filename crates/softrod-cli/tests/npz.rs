//! `softrod run --npz`: `trajectory.npz` read back with a reader written
//! here from the zip and `.npy` specifications (central directory first, a
//! bitwise CRC-32, the header dict parsed as text), compared number for
//! number with `trajectory.csv` and name for name with `summary.json`.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use common::*;

/// One `.npy` array: its dtype text, shape and payload.
#[derive(Debug)]
struct Npy {
    descr: String,
    shape: Vec<usize>,
    data: Vec<u8>,
}

impl Npy {
    fn f64s(&self) -> Vec<f64> {
        assert_eq!(self.descr, "<f8");
        assert_eq!(self.data.len(), 8 * self.shape.iter().product::<usize>());
        self.data
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    fn strings(&self) -> Vec<String> {
        let width: usize = self.descr.strip_prefix("<U").unwrap().parse().unwrap();
        assert_eq!(self.shape.len(), 1);
        self.data
            .chunks_exact(4 * width)
            .map(|c| {
                c.chunks_exact(4)
                    .map(|u| u32::from_le_bytes(u.try_into().unwrap()))
                    .take_while(|&u| u != 0)
                    .map(|u| char::from_u32(u).unwrap())
                    .collect()
            })
            .collect()
    }
}

/// The CRC-32 of zip (reflected polynomial 0xEDB88320), bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

fn u16_at(b: &[u8], i: usize) -> usize {
    u16::from_le_bytes([b[i], b[i + 1]]) as usize
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(b[i..i + 4].try_into().unwrap())
}

fn parse_npy(b: &[u8]) -> Npy {
    assert_eq!(&b[..6], b"\x93NUMPY");
    assert_eq!((b[6], b[7]), (1, 0), "version 1.0");
    let hlen = u16_at(b, 8);
    assert_eq!((10 + hlen) % 16, 0, "header aligned (npy spec)");
    let header = std::str::from_utf8(&b[10..10 + hlen]).unwrap();
    assert!(header.ends_with('\n'));
    let field = |key: &str| {
        let at = header.find(&format!("'{key}': ")).unwrap() + key.len() + 4;
        &header[at..]
    };
    let descr = field("descr");
    let descr = descr[1..descr[1..].find('\'').unwrap() + 1].to_string();
    assert!(field("fortran_order").starts_with("False"));
    let shape = field("shape");
    let shape = &shape[1..shape.find(')').unwrap()];
    let shape = shape
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect();
    Npy {
        descr,
        shape,
        data: b[10 + hlen..].to_vec(),
    }
}

/// The arrays of an `.npz`, by name (without `.npy`).
fn read_npz(path: &Path) -> BTreeMap<String, Npy> {
    let z = std::fs::read(path).unwrap();
    let end = z.len() - 22;
    assert_eq!(u32_at(&z, end), 0x0605_4b50, "end of central directory");
    let n = u16_at(&z, end + 10);
    let mut at = u32_at(&z, end + 16) as usize;
    let mut out = BTreeMap::new();
    for _ in 0..n {
        assert_eq!(u32_at(&z, at), 0x0201_4b50, "central header");
        let (method, crc) = (u16_at(&z, at + 10), u32_at(&z, at + 16));
        let (size, name_len) = (u32_at(&z, at + 20) as usize, u16_at(&z, at + 28));
        let (extra, comment) = (u16_at(&z, at + 30), u16_at(&z, at + 32));
        let local = u32_at(&z, at + 42) as usize;
        let name = std::str::from_utf8(&z[at + 46..at + 46 + name_len])
            .unwrap()
            .to_string();
        at += 46 + name_len + extra + comment;
        assert_eq!(method, 0, "stored");
        assert_eq!(u32_at(&z, local), 0x0403_4b50, "local header of {name}");
        let data_at = local + 30 + u16_at(&z, local + 26) + u16_at(&z, local + 28);
        let data = &z[data_at..data_at + size];
        assert_eq!(crc32(data), crc, "CRC of {name}");
        let key = name.strip_suffix(".npy").unwrap().to_string();
        out.insert(key, parse_npy(data));
    }
    out
}

/// `CSV[cols]` of every row, flattened row by row (C order).
fn columns(header: &[String], rows: &[Vec<f64>], names: &[String]) -> Vec<f64> {
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            header
                .iter()
                .position(|h| h == n)
                .unwrap_or_else(|| panic!("{n}"))
        })
        .collect();
    rows.iter()
        .flat_map(|r| idx.iter().map(move |&i| r[i]))
        .collect()
}

fn names(prefix: &str, n: usize) -> Vec<String> {
    (0..n).map(|i| format!("{prefix}{i}")).collect()
}

fn strs(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

/// Runs `scene` with `--npz` and checks every array against the CSV and
/// summary.json; returns the arrays.
fn run_and_compare(scene: &Path, out: &Path) -> BTreeMap<String, Npy> {
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--npz",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    compare(out)
}

fn compare(out: &Path) -> BTreeMap<String, Npy> {
    let a = read_npz(&out.join("trajectory.npz"));
    let (header, rows) = csv(&out.join("trajectory.csv"));
    let summary = json_file(&out.join("summary.json"));
    let m = rows.len();
    let q_names: Vec<String> = serde_json::from_value(summary["q_names"].clone()).unwrap();
    let n = q_names.len();
    let count = |p: &str| header.iter().filter(|h| h.starts_with(p)).count();
    let nc = count("tension");
    let np = count("prescribed_force");
    let check = |name: &str, cols: Vec<String>| {
        let arr = &a[name];
        let expect_shape = if name == "t" {
            vec![m]
        } else {
            vec![m, cols.len()]
        };
        assert_eq!(arr.shape, expect_shape, "shape of {name}");
        // Exact: the CSV's numbers read back to the same f64s.
        assert_eq!(arr.f64s(), columns(&header, &rows, &cols), "{name}");
    };
    check("t", strs(&["t"]));
    check("q", names("q", n));
    check("qdot", names("qdot", n));
    check(
        "tip",
        strs(&[
            "tip_x", "tip_y", "tip_z", "tip_qw", "tip_qx", "tip_qy", "tip_qz",
        ]),
    );
    check(
        "energy",
        strs(&["energy", "kinetic", "elastic", "gravitational"]),
    );
    let mut expected: Vec<&str> = vec!["energy", "q", "q_names", "qdot", "t", "tip"];
    if nc > 0 {
        check("tension", names("tension", nc));
        check("power", names("power", nc));
        expected.extend(["power", "tension"]);
    }
    if np > 0 {
        check("prescribed", names("prescribed", np));
        check("prescribed_force", names("prescribed_force", np));
        let pn: Vec<String> = serde_json::from_value(summary["prescribed_names"].clone()).unwrap();
        assert_eq!(a["prescribed_names"].strings(), pn);
        expected.extend(["prescribed", "prescribed_force", "prescribed_names"]);
    }
    assert_eq!(a["q_names"].strings(), q_names);
    expected.sort_unstable();
    assert_eq!(a.keys().map(String::as_str).collect::<Vec<_>>(), expected);
    a
}

#[test]
fn npz_holds_the_csv_rows_and_the_names_with_cables() {
    let dir = tmp("cables");
    let scene = with_run(
        "cable_planar_arm.toml",
        "[run]\nduration = 0.2\nintegrator = \"dopri5\"\nrtol = 1e-5\natol = 1e-8\noutput_every = 0.01",
        &dir,
    );
    let out = dir.join("out");
    let a = run_and_compare(&scene, &out);
    assert_eq!(a["t"].shape, vec![21]);
    // The cables pull: the tensions are not all zero (the check is not vacuous).
    assert!(a["tension"].f64s().iter().any(|v| *v != 0.0));

    // A run without --npz removes the stale archive.
    let o = run_scene(&scene, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!out.join("trajectory.npz").exists());
}

#[test]
fn npz_holds_the_prescribed_joint_and_its_names() {
    let dir = tmp("prescribed");
    let scene = with_run(
        "oscillating_base.toml",
        "[run]\nduration = 0.1\noutput_every = 0.01",
        &dir,
    );
    let out = dir.join("out");
    let a = run_and_compare(&scene, &out);
    assert!(a["prescribed"].f64s().iter().any(|v| *v != 0.0));
}

#[test]
fn a_failed_run_leaves_an_archive_of_exactly_the_rows_written() {
    let dir = tmp("failed");
    let scene = with_run(
        "cantilever_gravity.toml",
        "[run]\nduration = 0.1\nintegrator = \"rk4\"\ndt = 1e-3\noutput_every = 0.01",
        &dir,
    );
    let out = dir.join("out");
    let o = run(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--npz",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!out.join("trajectory.npz.tmp").exists());
    let a = compare(&out);
    let summary = json_file(&out.join("summary.json"));
    assert_eq!(
        a["t"].shape[0] as u64,
        summary["output_rows"].as_u64().unwrap()
    );
}
