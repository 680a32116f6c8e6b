//! Rotations saved by NumPy: a `.npy` file (`np.save("estimate.npy", R)`) or an array of a
//! `.npz` archive written by `np.savez` (stored, not compressed), read with the `npyz` crate.
//!
//! Accepted arrays: float64 or float32 (either byte order), C or Fortran order, of shape
//! `(n, 3, 3)` (rotation `k` is `a[k]`), `(n, 9)` (row-major rows) or `(3, 3)` (one rotation).
//! Every matrix is checked as a rotation (errors name the file and the rotation's index). The
//! data's size is checked against the file's before anything is allocated from the header.

use crate::error::{Error, Result};
use crate::io::detect::ReadOptions;
use crate::so3::{Rotation, rotation_from_matrix};
use nalgebra::Matrix3;

/// The first bytes of every `.npy` file.
const NPY_MAGIC: &[u8] = b"\x93NUMPY";
/// The first bytes of a zip archive's local file header (`.npz`).
const ZIP_LOCAL: &[u8] = b"PK\x03\x04";

/// Whether `bytes` start as a `.npy` file.
pub fn is_npy(bytes: &[u8]) -> bool {
    bytes.starts_with(NPY_MAGIC)
}

/// Whether `bytes` start as a zip archive (a `.npz` file is one).
pub fn is_zip(bytes: &[u8]) -> bool {
    bytes.starts_with(ZIP_LOCAL)
}

/// The rotations of a NumPy array: a `.npy` file's bytes, or a `.npz` archive's (its one
/// array, or the one named `rotations` or `estimate`). `(3, 3)` arrays give one rotation.
///
/// ```
/// use rotavg::io::detect::ReadOptions;
/// use rotavg::io::numpy::read_numpy_rotations;
/// // np.save of np.eye(3)[None] (shape (1, 3, 3), float64, C order)
/// let header = "{'descr': '<f8', 'fortran_order': False, 'shape': (1, 3, 3), }";
/// let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
/// let padded = format!("{header:<117}\n"); // header + padding: 128 bytes in all
/// bytes.extend_from_slice(&(padded.len() as u16).to_le_bytes());
/// bytes.extend_from_slice(padded.as_bytes());
/// for x in [1.0f64, 0., 0., 0., 1., 0., 0., 0., 1.] {
///     bytes.extend_from_slice(&x.to_le_bytes());
/// }
/// let r = read_numpy_rotations(&bytes, "est.npy", &ReadOptions::default())?;
/// assert_eq!(r.len(), 1);
/// assert!(r[0].angle() < 1e-15);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_numpy_rotations(
    bytes: &[u8],
    file: &str,
    options: &ReadOptions,
) -> Result<Vec<Rotation>> {
    if is_zip(bytes) {
        let (name, array) = npz_array(bytes, file)?;
        return read_npy(array, &format!("{file}[{name}]"), options);
    }
    read_npy(bytes, file, options)
}

/// The rotations of one `.npy` array.
fn read_npy(bytes: &[u8], file: &str, options: &ReadOptions) -> Result<Vec<Rotation>> {
    let bad = |reason: String| Error::parse(Some(file), None, reason);
    // npyz allocates the header length the file announces and multiplies the shape's
    // dimensions unchecked: both are checked here first
    check_header(bytes).map_err(bad)?;
    let npy = npyz::NpyFile::new(bytes).map_err(|e| bad(format!("not a .npy array: {e}")))?;
    let shape = npy.shape().to_vec();
    let strides = npy.strides().to_vec();
    let count = match shape.as_slice() {
        [n, 3, 3] | [n, 9] => *n,
        [3, 3] => 1,
        other => {
            return Err(bad(format!(
                "an array of shape {other:?}; rotations are saved as shape (n, 3, 3), (n, 9) \
                 or (3, 3)"
            )));
        }
    };
    let values = values(npy, count.saturating_mul(9), bytes.len(), file)?;
    (0..count as usize)
        .map(|k| {
            let m = Matrix3::from_fn(|r, c| {
                let index = match shape.len() {
                    3 => k as u64 * strides[0] + r as u64 * strides[1] + c as u64 * strides[2],
                    _ if shape == [3, 3] => r as u64 * strides[0] + c as u64 * strides[1],
                    _ => k as u64 * strides[0] + (3 * r + c) as u64 * strides[1],
                };
                values[index as usize]
            });
            rotation_from_matrix(&m, options.rotation_tolerance, &format!("rotation {k}"))
                .map_err(|e| e.in_file(file, None))
        })
        .collect()
}

/// The header of a `.npy` file checked before `npyz` reads it: its announced length within
/// the file (version 1: 2 bytes at offset 8; versions 2 and 3: 4 bytes), and a `shape` tuple
/// of at most three dimensions whose product does not overflow.
fn check_header(bytes: &[u8]) -> std::result::Result<(), String> {
    let (len_at, len_bytes) = match bytes.get(6) {
        Some(1) => (8, 2),
        Some(2 | 3) => (8, 4),
        _ => return Err("not a .npy array: unknown format version".into()),
    };
    let field = bytes
        .get(len_at..len_at + len_bytes)
        .ok_or("not a .npy array: truncated header")?;
    let header_len = field
        .iter()
        .rev()
        .fold(0usize, |acc, &b| (acc << 8) | b as usize);
    let header = bytes
        .get(len_at + len_bytes..len_at + len_bytes + header_len)
        .ok_or("not a .npy array: the header is longer than the file")?;
    let text = String::from_utf8_lossy(header);
    let shape = text
        .split_once("'shape'")
        .and_then(|(_, rest)| rest.split_once('('))
        .and_then(|(_, rest)| rest.split_once(')'))
        .map(|(dims, _)| dims)
        .ok_or("not a .npy array: no 'shape' tuple in the header")?;
    let dims: Vec<&str> = shape
        .split(',')
        .map(str::trim)
        .filter(|d| !d.is_empty())
        .collect();
    if dims.len() > 3 {
        return Err(format!(
            "an array of {} dimensions; rotations are saved as shape (n, 3, 3), (n, 9) or (3, 3)",
            dims.len()
        ));
    }
    dims.iter().try_fold(1u64, |product, d| {
        d.parse::<u64>()
            .ok()
            .and_then(|d| product.checked_mul(d))
            .ok_or_else(|| format!("not a .npy array: shape ({shape}) is not a product of sizes"))
    })?;
    Ok(())
}

/// The array's `len` values as f64 (float64 or float32 data), after checking that the file
/// holds them.
fn values<R: std::io::Read>(
    npy: npyz::NpyFile<R>,
    len: u64,
    file_len: usize,
    file: &str,
) -> Result<Vec<f64>> {
    let bad = |reason: String| Error::parse(Some(file), None, reason);
    let descr = npy.dtype().descr();
    let descr = descr.trim_matches('\'');
    let width = match descr.get(1..) {
        Some("f8") => 8,
        Some("f4") => 4,
        _ => {
            return Err(bad(format!(
                "an array of dtype {descr}; rotations are float64 or float32"
            )));
        }
    };
    if len.saturating_mul(width) > file_len as u64 {
        return Err(bad(format!(
            "the header announces {len} values, more than the file holds"
        )));
    }
    let read = |e: std::io::Error| bad(format!("cannot read the array's data: {e}"));
    if width == 8 {
        let data = npy.data::<f64>().map_err(|e| bad(e.to_string()))?;
        data.collect::<std::io::Result<Vec<f64>>>().map_err(read)
    } else {
        let data = npy.data::<f32>().map_err(|e| bad(e.to_string()))?;
        data.map(|x| x.map(f64::from))
            .collect::<std::io::Result<Vec<f64>>>()
            .map_err(read)
    }
}

/// The `.npy` member of a `.npz` archive to read: the only one, or the one named `rotations`
/// or `estimate`. Only stored (uncompressed) members can be read (`np.savez`).
fn npz_array<'a>(bytes: &'a [u8], file: &str) -> Result<(String, &'a [u8])> {
    let members = zip_members(bytes, file)?;
    let chosen = match members.as_slice() {
        [one] => Some(one),
        _ => members
            .iter()
            .find(|m| m.name == "rotations.npy" || m.name == "estimate.npy"),
    };
    let Some(m) = chosen else {
        let names: Vec<&str> = members.iter().map(|m| m.name.as_str()).collect();
        return Err(Error::parse(
            Some(file),
            None,
            format!(
                "a .npz archive of {} arrays ({}); save one array, or name it `rotations` \
                 (np.savez(path, rotations=R))",
                names.len(),
                names.join(", ")
            ),
        ));
    };
    if m.method != 0 {
        return Err(Error::parse(
            Some(file),
            None,
            format!(
                "{}: a compressed .npz member (np.savez_compressed); save it with np.savez or \
                 np.save",
                m.name
            ),
        ));
    }
    let name = m.name.trim_end_matches(".npy").to_string();
    Ok((name, &bytes[m.start..m.start + m.size]))
}

/// A member of a zip archive, from its local file header.
struct ZipMember {
    name: String,
    /// Compression method (0: stored).
    method: u16,
    /// Offset of its data.
    start: usize,
    /// Size of its data as stored.
    size: usize,
}

/// The members of a zip archive, walking its local file headers (zip64 sizes included, as
/// NumPy writes them). Archives whose headers defer their sizes to a data descriptor are
/// refused.
fn zip_members(bytes: &[u8], file: &str) -> Result<Vec<ZipMember>> {
    let bad = |reason: &str| Error::parse(Some(file), None, format!("a .npz archive: {reason}"));
    let u16_at = |k: usize| {
        bytes
            .get(k..k + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let u32_at = |k: usize| {
        bytes
            .get(k..k + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let mut members = Vec::new();
    let mut at = 0;
    while bytes.get(at..at + 4) == Some(ZIP_LOCAL) {
        let field = |v: Option<u32>| v.ok_or_else(|| bad("truncated header"));
        let flags = field(u16_at(at + 6).map(u32::from))?;
        let method = field(u16_at(at + 8).map(u32::from))? as u16;
        let mut size = field(u32_at(at + 18))? as u64;
        let name_len = field(u16_at(at + 26).map(u32::from))? as usize;
        let extra_len = field(u16_at(at + 28).map(u32::from))? as usize;
        let name_at = at + 30;
        let extra_at = name_at + name_len;
        let name = bytes
            .get(name_at..extra_at)
            .map(|b| String::from_utf8_lossy(b).into_owned())
            .ok_or_else(|| bad("truncated header"))?;
        if flags & 8 != 0 {
            return Err(bad("sizes in a data descriptor (not written by NumPy)"));
        }
        if size == u64::from(u32::MAX) {
            size = zip64_size(bytes, extra_at, extra_len).ok_or_else(|| bad("bad zip64 field"))?;
        }
        let start = extra_at + extra_len;
        let end = usize::try_from(size)
            .ok()
            .and_then(|s| start.checked_add(s))
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| bad("a member larger than the file"))?;
        members.push(ZipMember {
            name,
            method,
            start,
            size: end - start,
        });
        at = end;
    }
    if members.is_empty() {
        return Err(bad("no member"));
    }
    Ok(members)
}

/// The compressed size in a local header's zip64 extra field (id 1: uncompressed size, then
/// compressed size, 8 bytes each).
fn zip64_size(bytes: &[u8], extra_at: usize, extra_len: usize) -> Option<u64> {
    let extra = bytes.get(extra_at..extra_at.checked_add(extra_len)?)?;
    let mut k = 0;
    while k + 4 <= extra.len() {
        let id = u16::from_le_bytes([extra[k], extra[k + 1]]);
        let len = u16::from_le_bytes([extra[k + 2], extra[k + 3]]) as usize;
        if id == 1 {
            let b = extra.get(k + 12..k + 20)?;
            return Some(u64::from_le_bytes(b.try_into().ok()?));
        }
        k += 4 + len;
    }
    None
}
