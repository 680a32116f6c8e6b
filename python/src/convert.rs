//! numpy in: array-likes (lists, ndarrays of any real dtype, objects with `as_matrix()` such as
//! `scipy.spatial.transform.Rotation`) to plain Rust vectors, with the shape checks of the
//! Python API. Only copies are made while the GIL is held; validation of the values (rotations,
//! weights, indices) happens afterwards, without the GIL, in the library's own checks.
//!
//! numpy out: rotations as `(N, 3, 3)` or `(3, 3)` float64 arrays (row-major, C order).

use crate::errors::Error;
use nalgebra::Matrix3;
use numpy::ndarray::Dimension;
use numpy::{AllowTypeChange, PyArray1, PyArrayLikeDyn, PyArrayMethods, PyUntypedArray};
use pyo3::prelude::*;
use rotavg::Rotation;
use rotavg::so3::{DEFAULT_ROTATION_TOLERANCE, rotation_from_matrix};

/// `obj` as a numpy array: `obj.as_matrix()` when `obj` is not an ndarray and has that method
/// (scipy's `Rotation`), else `numpy.asarray(obj)`; the dtype kind must be one of `kinds`
/// (numpy's one-letter codes: `f` float, `i` signed, `u` unsigned integer).
fn ndarray<'py>(obj: &Bound<'py, PyAny>, what: &str, kinds: &str) -> PyResult<Bound<'py, PyAny>> {
    let py = obj.py();
    let is_array = obj.cast::<PyUntypedArray>().is_ok();
    let obj = if !is_array && obj.hasattr("as_matrix")? {
        obj.call_method0("as_matrix")?
    } else {
        obj.clone()
    };
    let array = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| Error::new_err(format!("{what}: not an array of numbers ({e})")))?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    let size: usize = array.getattr("size")?.extract()?;
    // An empty list is float64 to numpy: let the size checks speak instead.
    if size > 0 && !kinds.contains(kind.as_str()) {
        let dtype = array.getattr("dtype")?.str()?.to_string();
        let expected = if kinds.contains('f') {
            "real numbers"
        } else {
            "integers"
        };
        return Err(Error::new_err(format!(
            "{what}: expected {expected}, got an array of dtype {dtype}"
        )));
    }
    Ok(array)
}

/// The shape of an array as a Python-style tuple string, e.g. `(4, 3)`.
fn shape_text(shape: &[usize]) -> String {
    match shape {
        [one] => format!("({one},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The values of a real array-like, in C order, with its shape.
fn float_values(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let array = ndarray(obj, what, "fiu")?;
    let a: PyArrayLikeDyn<'_, f64, AllowTypeChange> = array.extract()?;
    let view = a.as_array();
    let shape = view.raw_dim().as_array_view().to_vec();
    let values = match view.as_slice() {
        Some(s) => s.to_vec(),
        None => view.iter().copied().collect(),
    };
    Ok((values, shape))
}

/// Rows of 9 numbers (row-major 3x3 matrices) of an `(N, 3, 3)` array-like.
pub fn matrices(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Matrices> {
    let (values, shape) = float_values(obj, what)?;
    match shape.as_slice() {
        [_, 3, 3] => Ok(Matrices {
            values,
            what: what.to_string(),
            tolerance: DEFAULT_ROTATION_TOLERANCE,
        }),
        _ => Err(Error::new_err(format!(
            "{what} must have shape (N, 3, 3), got {}",
            shape_text(&shape)
        ))),
    }
}

/// One row-major 3x3 matrix of a `(3, 3)` array-like.
pub fn matrix(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Matrices> {
    let (values, shape) = float_values(obj, what)?;
    match shape.as_slice() {
        [3, 3] => Ok(Matrices {
            values,
            what: what.to_string(),
            tolerance: DEFAULT_ROTATION_TOLERANCE,
        }),
        _ => Err(Error::new_err(format!(
            "{what} must have shape (3, 3), got {}",
            shape_text(&shape)
        ))),
    }
}

/// A 1-D real array-like of `len` entries (weights).
pub fn vector(obj: &Bound<'_, PyAny>, what: &str, len: usize) -> PyResult<Vec<f64>> {
    let (values, shape) = float_values(obj, what)?;
    match shape.as_slice() {
        [m] if *m == len => Ok(values),
        _ => Err(Error::new_err(format!(
            "{what} must have shape ({len},), got {}",
            shape_text(&shape)
        ))),
    }
}

/// Rows of an `(N, 3)` or `(N, 4)` real array-like (gravity vectors, and their relative
/// weights; NaN allowed: the caller decides), each with its fourth number (NaN for `(N, 3)`).
pub fn gravity_rows(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; 4]>> {
    let (values, shape) = float_values(obj, what)?;
    match shape.as_slice() {
        [_, 3] => Ok(values
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2], f64::NAN])
            .collect()),
        [_, 4] => Ok(values
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()),
        _ => Err(Error::new_err(format!(
            "{what} must have shape (N, 3) or (N, 4), got {}",
            shape_text(&shape)
        ))),
    }
}

/// A 1-D integer array-like (node indices).
pub fn indices(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<i64>> {
    let array = ndarray(obj, what, "iu")?;
    let a: PyArrayLikeDyn<'_, i64, AllowTypeChange> = array.extract()?;
    let view = a.as_array();
    match view.shape() {
        [_] => Ok(view.iter().copied().collect()),
        shape => Err(Error::new_err(format!(
            "{what} must be a 1-D array of node indices, got shape {}",
            shape_text(shape)
        ))),
    }
}

/// Matrices copied out of Python, not yet validated.
#[derive(Debug, Clone)]
pub struct Matrices {
    values: Vec<f64>,
    what: String,
    /// The rotation tolerance of [`Self::rotations`] (default
    /// [`DEFAULT_ROTATION_TOLERANCE`]; [`Self::within`]).
    tolerance: f64,
}

impl Matrices {
    /// These matrices, checked as rotations with `tolerance` (a `rotation_tolerance` keyword,
    /// validated by [`rotation_tolerance`]).
    pub fn within(mut self, tolerance: f64) -> Self {
        self.tolerance = tolerance;
        self
    }

    /// The rotation tolerance ([`Self::within`]).
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// Number of matrices.
    pub fn len(&self) -> usize {
        self.values.len() / 9
    }

    /// The matrices as given (row-major `3 x 3`), unchecked.
    pub fn matrices(&self) -> Vec<Matrix3<f64>> {
        self.values
            .chunks_exact(9)
            .map(Matrix3::from_row_slice)
            .collect()
    }

    /// The matrices as rotations, each checked by the library ([`rotation_from_matrix`], with
    /// the tolerance of [`Self::within`]); errors name `what[k]`.
    pub fn rotations(&self) -> rotavg::Result<Vec<Rotation>> {
        self.values
            .chunks_exact(9)
            .enumerate()
            .map(|(k, m)| {
                rotation_from_matrix(
                    &Matrix3::from_row_slice(m),
                    self.tolerance,
                    &format!("{}[{k}]", self.what),
                )
            })
            .collect()
    }

    /// The matrices as rotations where given: a matrix whose nine entries are all NaN is
    /// `None` (a node without ground truth); any other is checked as in [`Self::rotations`].
    pub fn optional_rotations(&self) -> rotavg::Result<Vec<Option<Rotation>>> {
        self.values
            .chunks_exact(9)
            .enumerate()
            .map(|(k, m)| {
                if m.iter().all(|x| x.is_nan()) {
                    return Ok(None);
                }
                rotation_from_matrix(
                    &Matrix3::from_row_slice(m),
                    self.tolerance,
                    &format!("{}[{k}]", self.what),
                )
                .map(Some)
            })
            .collect()
    }

    /// The single matrix of [`matrix`] as a rotation; the error names `what`.
    pub fn rotation(&self) -> rotavg::Result<Rotation> {
        rotation_from_matrix(
            &Matrix3::from_row_slice(&self.values),
            self.tolerance,
            &self.what,
        )
    }
}

/// Rotations as an `(N, 3, 3)` float64 array (row-major matrices).
pub fn rotations_array<'py>(
    py: Python<'py>,
    rotations: &[Rotation],
) -> PyResult<Bound<'py, PyAny>> {
    matrices_array(py, rotations.iter().map(Rotation::matrix))
}

/// `3 x 3` matrices as an `(N, 3, 3)` float64 array (row-major).
pub fn matrices_array<'py, 'm>(
    py: Python<'py>,
    matrices: impl ExactSizeIterator<Item = &'m Matrix3<f64>>,
) -> PyResult<Bound<'py, PyAny>> {
    let count = matrices.len();
    let mut values = Vec::with_capacity(9 * count);
    for m in matrices {
        for row in 0..3 {
            values.extend((0..3).map(|col| m[(row, col)]));
        }
    }
    Ok(PyArray1::from_vec(py, values)
        .reshape([count, 3, 3])?
        .into_any())
}

/// Rotations where known as an `(N, 3, 3)` float64 array, a matrix of NaN where not.
pub fn optional_rotations_array<'py>(
    py: Python<'py>,
    rotations: &[Option<Rotation>],
) -> PyResult<Bound<'py, PyAny>> {
    let mut values = Vec::with_capacity(9 * rotations.len());
    for r in rotations {
        match r {
            Some(r) => {
                let m = r.matrix();
                for row in 0..3 {
                    values.extend((0..3).map(|col| m[(row, col)]));
                }
            }
            None => values.extend([f64::NAN; 9]),
        }
    }
    Ok(PyArray1::from_vec(py, values)
        .reshape([rotations.len(), 3, 3])?
        .into_any())
}

/// The rotation parts of `(N, 4, 4)` homogeneous transforms (whose last row must be
/// `0 0 0 1` within the rotation tolerance) or `(N, 3, 3)` rotations (anything with `as_matrix()`, such as a scipy
/// `Rotation`, gives the latter).
pub fn pose_rotations(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Matrices> {
    let (values, shape) = float_values(obj, what)?;
    match shape.as_slice() {
        [_, 3, 3] => Ok(Matrices {
            values,
            what: what.to_string(),
            tolerance: DEFAULT_ROTATION_TOLERANCE,
        }),
        [_, 4, 4] => {
            let mut rotations = Vec::with_capacity(values.len() / 16 * 9);
            for (k, t) in values.chunks_exact(16).enumerate() {
                let last = [t[12], t[13], t[14], t[15]];
                let expected = [0.0, 0.0, 0.0, 1.0];
                if !last
                    .iter()
                    .zip(expected)
                    .all(|(x, e)| (x - e).abs() <= DEFAULT_ROTATION_TOLERANCE)
                {
                    return Err(Error::new_err(format!(
                        "{what}[{k}] is not a homogeneous transform: its last row is {last:?}, not [0, 0, 0, 1] (tolerance {DEFAULT_ROTATION_TOLERANCE:.0e})"
                    )));
                }
                for row in 0..3 {
                    rotations.extend_from_slice(&t[4 * row..4 * row + 3]);
                }
            }
            Ok(Matrices {
                values: rotations,
                what: what.to_string(),
                tolerance: DEFAULT_ROTATION_TOLERANCE,
            })
        }
        _ => Err(Error::new_err(format!(
            "{what} must have shape (N, 4, 4) (homogeneous transforms) or (N, 3, 3) (rotations), got {}",
            shape_text(&shape)
        ))),
    }
}

/// One rotation as a `(3, 3)` float64 array.
pub fn rotation_array<'py>(py: Python<'py>, rotation: &Rotation) -> PyResult<Bound<'py, PyAny>> {
    rotations_array(py, std::slice::from_ref(rotation))?.call_method1("reshape", (3, 3))
}

/// Mark a numpy array read-only (arrays that mirror data held on the Rust side).
pub fn read_only<'py>(array: Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    array.getattr("flags")?.setattr("writeable", false)?;
    Ok(array)
}

/// The path an argument names when it is a `str` or an `os.PathLike` (then read as the command
/// line reads that file), else None (an array).
pub fn path_of(obj: &Bound<'_, PyAny>) -> Option<String> {
    obj.extract::<std::path::PathBuf>()
        .ok()
        .map(|p| p.to_string_lossy().into_owned())
}

/// A `rotation_tolerance` keyword: positive and finite (the tolerance on `||R^T R - I||_F` and
/// `|det R - 1|` of every matrix given as a rotation, the command line's 1e-5 by default).
pub fn rotation_tolerance(tolerance: f64) -> PyResult<f64> {
    if tolerance.is_finite() && tolerance > 0.0 {
        Ok(tolerance)
    } else {
        Err(Error::new_err(format!(
            "rotation_tolerance must be positive and finite, got {tolerance}"
        )))
    }
}
