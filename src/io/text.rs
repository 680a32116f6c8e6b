//! Reading a text input with bounded memory: every reader of a path (and standard input) goes
//! through [`read_text`], which refuses what cannot be a text input *before* reading it all.
//!
//! - a file larger than [`MAX_INPUT_BYTES`] is refused from its size alone (standard input as
//!   soon as it exceeds the limit), so memory stays bounded by the limit;
//! - a NUL byte in the first [`SNIFF_BYTES`] marks binary data and is refused after reading
//!   only that block (e.g. a sparse file of zeros);
//! - text that is not UTF-8 is refused with the line of the first invalid byte.

use crate::error::{Error, Result};
use std::io::Read;

/// The largest input read, bytes (1 GiB: a g2o file of about 3x10^6 edges, a 1DSfM `EGs.txt`
/// of about 5x10^6).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The first block of an input, checked for NUL bytes before the rest is read.
pub const SNIFF_BYTES: usize = 1 << 16;

/// Read the text of the file at `path`, or standard input for `-`, with the checks of the
/// module docs. Errors name the path.
///
/// ```
/// use rotavg::io::text::read_text;
/// let dir = std::env::temp_dir();
/// let ok = dir.join(format!("rotavg-doc-text-{}.txt", std::process::id()));
/// std::fs::write(&ok, "EDGE3 0 1 0 0 0 0 0 0\n").unwrap();
/// assert!(read_text(ok.to_str().unwrap())?.starts_with("EDGE3"));
/// let bin = dir.join(format!("rotavg-doc-text-{}.bin", std::process::id()));
/// std::fs::write(&bin, [0u8; 100]).unwrap();
/// let err = read_text(bin.to_str().unwrap()).unwrap_err().to_string();
/// assert!(err.contains("NUL byte at offset 0"), "{err}");
/// # std::fs::remove_file(ok).unwrap(); std::fs::remove_file(bin).unwrap();
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_text(path: &str) -> Result<String> {
    read_text_limited(path, MAX_INPUT_BYTES)
}

/// Read the bytes of a binary input (the file at `path`, or standard input for `-`) with the
/// size limit [`MAX_INPUT_BYTES`] (refused from the file's size before reading); no NUL or
/// UTF-8 checks. Errors name the path. Binary readers (COLMAP `images.bin`) read through it.
///
/// ```
/// use rotavg::io::text::read_bytes;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-bytes-{}.bin", std::process::id()));
/// std::fs::write(&path, [0u8, 1, 2]).unwrap();
/// let bytes = read_bytes(path.to_str().unwrap());
/// std::fs::remove_file(&path).unwrap();
/// assert_eq!(bytes?, vec![0, 1, 2]);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_bytes(path: &str) -> Result<Vec<u8>> {
    let io_error = |message: String| Error::Io {
        path: path.into(),
        message,
    };
    let max_bytes = MAX_INPUT_BYTES;
    if path == "-" {
        return read_limited_binary(std::io::stdin().lock(), max_bytes).map_err(io_error);
    }
    let file = std::fs::File::open(path).map_err(|e| io_error(e.to_string()))?;
    if let Ok(meta) = file.metadata()
        && meta.is_file()
        && meta.len() > max_bytes
    {
        return Err(io_error(format!(
            "the file has {} bytes, more than the input limit of {max_bytes} bytes",
            meta.len()
        )));
    }
    read_limited_binary(file, max_bytes).map_err(io_error)
}

fn read_limited_binary(reader: impl Read, max_bytes: u64) -> std::result::Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    reader
        .take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > max_bytes {
        return Err(format!(
            "the input has more than the input limit of {max_bytes} bytes"
        ));
    }
    Ok(bytes)
}

/// [`read_text`] with another size limit, bytes.
pub fn read_text_limited(path: &str, max_bytes: u64) -> Result<String> {
    let io_error = |message: String| Error::Io {
        path: path.into(),
        message,
    };
    let bytes = if path == "-" {
        read_limited(std::io::stdin().lock(), max_bytes).map_err(io_error)?
    } else {
        read_file_limited(path, max_bytes).map_err(io_error)?
    };
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = 1 + e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count();
        Error::parse(
            Some(path),
            Some(line),
            format!("not UTF-8 text (invalid byte at offset {at})"),
        )
    })
}

fn read_file_limited(path: &str, max_bytes: u64) -> std::result::Result<Vec<u8>, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    if let Ok(meta) = file.metadata()
        && meta.is_file()
        && meta.len() > max_bytes
    {
        return Err(format!(
            "the file has {} bytes, more than the input limit of {max_bytes} bytes",
            meta.len()
        ));
    }
    read_limited(file, max_bytes)
}

fn read_limited(reader: impl Read, max_bytes: u64) -> std::result::Result<Vec<u8>, String> {
    let mut reader = reader.take(max_bytes.saturating_add(1));
    let mut bytes = Vec::new();
    // the first block: binary data is refused before the rest is read
    let mut first = vec![0u8; SNIFF_BYTES];
    let mut filled = 0;
    while filled < first.len() {
        match reader.read(&mut first[filled..]) {
            Ok(0) => break,
            Ok(k) => filled += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e.to_string()),
        }
    }
    first.truncate(filled);
    if let Some(k) = first.iter().position(|&b| b == 0) {
        return Err(format!(
            "binary data (NUL byte at offset {k}), not a text input"
        ));
    }
    bytes.extend_from_slice(&first);
    if filled == SNIFF_BYTES {
        reader.read_to_end(&mut bytes).map_err(|e| e.to_string())?;
    }
    if bytes.len() as u64 > max_bytes {
        return Err(format!(
            "the input has more than the input limit of {max_bytes} bytes"
        ));
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_nul() {
        assert_eq!(read_limited(&b"abc\n"[..], 10).unwrap(), b"abc\n");
        assert!(
            read_limited(&b"abcdefghijkl"[..], 10)
                .unwrap_err()
                .contains("limit")
        );
        let mut big = vec![b'a'; SNIFF_BYTES + 10];
        assert_eq!(
            read_limited(&big[..], 1 << 20).unwrap().len(),
            SNIFF_BYTES + 10
        );
        big[SNIFF_BYTES + 5] = 0; // after the sniffed block: still text to this reader, but
        // the parsers reject it as a malformed line
        assert!(read_limited(&big[..], 1 << 20).is_ok());
        assert!(
            read_limited(&b"ab\0c"[..], 10)
                .unwrap_err()
                .contains("offset 2")
        );
    }
}
