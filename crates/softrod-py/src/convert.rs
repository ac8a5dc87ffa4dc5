//! numpy arrays in and out.
//!
//! Inputs: a float64 C-contiguous numpy array is read in place (no copy);
//! anything else `numpy.ascontiguousarray(x, dtype=float64)` accepts (lists,
//! integer arrays, strided views) is converted first. A wrong shape is a
//! `softrod.InputError` (a `ValueError`) naming the argument and both shapes.
//! Outputs are new float64 C-contiguous arrays.

use nalgebra::{DMatrix, Matrix3, Vector3};
use numpy::{
    PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyAny;
use softrod::lie::Pose;

use crate::errors::input;

fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// A read-only float64 C-contiguous view of an argument.
pub struct Arg<'py> {
    array: PyReadonlyArrayDyn<'py, f64>,
}

impl Arg<'_> {
    /// The data in C order.
    pub fn slice(&self) -> &[f64] {
        self.array
            .as_slice()
            .expect("contiguous by construction (ascontiguousarray)")
    }

    /// Its shape.
    pub fn shape(&self) -> &[usize] {
        self.array.shape()
    }
}

/// `obj` as a float64 C-contiguous array (a view when it already is one).
pub fn array<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Arg<'py>> {
    let py = obj.py();
    let arr: Bound<'py, PyArrayDyn<f64>> = match obj.cast::<PyArrayDyn<f64>>() {
        Ok(a) if a.is_c_contiguous() => a.clone(),
        _ => {
            static ASCONTIGUOUS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
            let f = ASCONTIGUOUS.import(py, "numpy", "ascontiguousarray")?;
            let converted = f
                .call1((obj, numpy::dtype::<f64>(py)))
                .map_err(|e| input(format!("{name}: not an array of numbers ({e})")))?;
            converted
                .cast_into::<PyArrayDyn<f64>>()
                .map_err(|e| input(format!("{name}: {e}")))?
        }
    };
    let array = arr
        .try_readonly()
        .map_err(|e| input(format!("{name}: {e}")))?;
    Ok(Arg { array })
}

/// `obj` as a float64 array of exactly `shape`.
pub fn shaped<'py>(obj: &Bound<'py, PyAny>, name: &str, shape: &[usize]) -> PyResult<Arg<'py>> {
    let a = array(obj, name)?;
    if a.shape() != shape {
        return Err(input(format!(
            "{name} must have shape {}, got {}",
            shape_text(shape),
            shape_text(a.shape())
        )));
    }
    Ok(a)
}

/// `obj` as a vector of length `n`.
pub fn vector<'py>(obj: &Bound<'py, PyAny>, name: &str, n: usize) -> PyResult<Arg<'py>> {
    shaped(obj, name, &[n])
}

/// `obj` as an owned `[f64; 3]`.
pub fn vec3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<[f64; 3]> {
    let a = vector(obj, name, 3)?;
    let s = a.slice();
    Ok([s[0], s[1], s[2]])
}

/// `obj` as a 3×3 matrix (rows in C order).
pub fn mat3(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Matrix3<f64>> {
    let a = shaped(obj, name, &[3, 3])?;
    Ok(Matrix3::from_row_slice(a.slice()))
}

/// A new 1-D array.
pub fn vec_out<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// A new C-contiguous 2-D array holding `m` (nalgebra is column-major).
pub fn mat_out<'py>(py: Python<'py>, m: &DMatrix<f64>) -> Bound<'py, PyArray2<f64>> {
    let (r, c) = m.shape();
    let out = PyArray2::<f64>::zeros(py, [r, c], false);
    {
        let mut w = out.readwrite();
        let s = w.as_slice_mut().expect("new arrays are contiguous");
        for i in 0..r {
            for j in 0..c {
                s[i * c + j] = m[(i, j)];
            }
        }
    }
    out
}

/// `rows × cols` values in C order as a new array of `shape`.
pub fn array_out<'py>(
    py: Python<'py>,
    data: Vec<f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    PyArray1::from_vec(py, data).reshape(shape)
}

/// Writes the 4×4 homogeneous transform `[[R, p], [0, 1]]` of `g` into `out`
/// (16 values, C order).
pub fn pose_into(g: &Pose, out: &mut [f64]) {
    for i in 0..3 {
        for j in 0..3 {
            out[4 * i + j] = g.rotation[(i, j)];
        }
        out[4 * i + 3] = g.translation[i];
    }
    out[12..16].copy_from_slice(&[0.0, 0.0, 0.0, 1.0]);
}

/// A pose from a 4×4 homogeneous transform.
pub fn pose_from(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Pose> {
    let a = shaped(obj, name, &[4, 4])?;
    let s = a.slice();
    let r = Matrix3::new(s[0], s[1], s[2], s[4], s[5], s[6], s[8], s[9], s[10]);
    Ok(Pose::new(r, Vector3::new(s[3], s[7], s[11])))
}
