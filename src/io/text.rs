//! Reading a text input with bounded memory. Every reader of a path (and standard input) goes
//! through [`TextStream`], which refuses what cannot be a text input *before* reading it all:
//!
//! - a file larger than the limit is refused from its size alone (standard input as soon as it
//!   exceeds the limit);
//! - a NUL byte in the first [`SNIFF_BYTES`] marks binary data and is refused after reading
//!   only that block (e.g. a sparse file of zeros);
//! - text that is not UTF-8 is refused with the line of the first invalid byte.
//!
//! Then the input is either read whole ([`TextStream::into_string`], [`read_text`]: JSON, ground
//! truth, estimates, COLMAP `images.txt`, hand-eye streams; limit [`MAX_INPUT_BYTES`]) or
//! streamed line by line ([`TextStream::into_lines`], [`TextLines`]: the view-graph formats
//! g2o / TORO and 1DSfM `EGs.txt`, which can be large). A streamed input never holds more than
//! one line of text: a line longer than [`MAX_LINE_BYTES`] is an error naming it, and the byte
//! limit is the much larger [`MAX_STREAM_BYTES`] (it bounds the reading time, not the memory).
//! What bounds a streamed reader's memory is what it keeps: at most [`MAX_RECORDS`] edges and
//! vertices, each of a fixed size (about 100 bytes while reading; nothing is allocated from a
//! count a file announces).

use crate::error::{Error, Result};
use std::io::{BufRead, BufReader, Read};

/// The largest input read whole, bytes (1 GiB: a g2o file of about 3x10^6 edges, a 1DSfM
/// `EGs.txt` of about 5x10^6). Streamed inputs ([`TextLines`]) have [`MAX_STREAM_BYTES`].
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The largest input streamed line by line, bytes (64 GiB). Memory does not grow with it (a
/// streamed reader holds one line); it only bounds the time spent reading.
pub const MAX_STREAM_BYTES: u64 = 1 << 36;

/// The longest line of a streamed input, bytes (1 MiB, the line ending included); a longer
/// line is an error naming it.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The most records (edges plus vertex lines) a view-graph reader keeps (2^24 = 16 777 216):
/// the bound on its memory now that the byte limit of a streamed file no longer is one. At about
/// 100 bytes per record while reading, 2^24 records take about 1.6 GB; this is five times the
/// edges a 1 GiB g2o file held.
pub const MAX_RECORDS: usize = 1 << 24;

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
    if std::path::Path::new(path).is_dir() {
        return Err(io_error(folder_message(std::path::Path::new(path))));
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
    TextStream::open_limited(path, max_bytes)?.into_string(max_bytes)
}

/// An opened text input: its first block ([`SNIFF_BYTES`]) read and checked for NUL bytes, the
/// rest not read yet. Read it whole ([`Self::into_string`]) or line by line
/// ([`Self::into_lines`]); [`Self::head`] shows the first block, e.g. to detect the format.
///
/// ```
/// use rotavg::io::text::TextStream;
/// let text = "# a comment\nEDGE3 0 1 0 0 0 0 0 0\n\nEDGE3 1 2 0 0 0 0 0 0\n";
/// let stream = TextStream::from_reader("inline.g2o", text.as_bytes(), u64::MAX, None)?;
/// assert!(stream.head()?.starts_with("# a comment"));
/// let mut lines = stream.into_lines();
/// let mut seen = Vec::new();
/// while let Some((line, content)) = lines.next_content()? {
///     seen.push((line, content.split_whitespace().next().unwrap_or("").to_owned()));
/// }
/// assert_eq!(seen, [(2, "EDGE3".to_owned()), (4, "EDGE3".to_owned())]);
/// assert_eq!(lines.lines_read(), 4);
/// // Binary data is refused after the first block.
/// let err = TextStream::from_reader("zeros", &[0u8; 100][..], u64::MAX, None).err().unwrap();
/// assert!(err.to_string().contains("NUL byte at offset 0"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub struct TextStream<'a> {
    name: String,
    head: Vec<u8>,
    /// The head holds the whole input.
    ended: bool,
    rest: Box<dyn Read + 'a>,
    /// The size the file reported before reading (regular files only).
    file_len: Option<u64>,
    max_bytes: u64,
}

impl std::fmt::Debug for TextStream<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TextStream")
            .field("name", &self.name)
            .field("head_bytes", &self.head.len())
            .field("file_len", &self.file_len)
            .field("max_bytes", &self.max_bytes)
            .finish_non_exhaustive()
    }
}

impl TextStream<'static> {
    /// Open the file at `path` (standard input for `-`) to stream it: refused from its size
    /// above [`MAX_STREAM_BYTES`], and when its first block holds a NUL byte. Errors name the
    /// path.
    pub fn open(path: &str) -> Result<Self> {
        Self::open_limited(path, MAX_STREAM_BYTES)
    }

    /// [`Self::open`] with another size limit, bytes.
    pub fn open_limited(path: &str, max_bytes: u64) -> Result<Self> {
        if path == "-" {
            return TextStream::from_reader(path, std::io::stdin().lock(), max_bytes, None);
        }
        let io_error = |message: String| Error::Io {
            path: path.into(),
            message,
        };
        if std::path::Path::new(path).is_dir() {
            return Err(io_error(folder_message(std::path::Path::new(path))));
        }
        let file = std::fs::File::open(path).map_err(|e| io_error(e.to_string()))?;
        let file_len = file
            .metadata()
            .ok()
            .filter(std::fs::Metadata::is_file)
            .map(|m| m.len());
        TextStream::from_reader(path, file, max_bytes, file_len)
    }
}

/// Why a folder given as an input file cannot be read as one: the folders the readers do take
/// (a COLMAP folder whose `database.db` is an SQLite file, for `multiple`; a hand-eye folder, for
/// `conjugate`), and what is wrong with a `database.db` that is not SQLite.
fn folder_message(path: &std::path::Path) -> String {
    let db = path.join("database.db");
    if db.is_file() {
        format!(
            "is a folder whose database.db is not an SQLite file (a COLMAP database starts with \
             \"SQLite format 3\"): {} cannot be read as a COLMAP database",
            db.display()
        )
    } else {
        "is a folder, not a file".into()
    }
}

impl<'a> TextStream<'a> {
    /// A stream over any reader, named `name` in errors. `file_len`, when known, is checked
    /// against `max_bytes` before anything is read; the bytes read are checked while reading.
    pub fn from_reader(
        name: &str,
        reader: impl Read + 'a,
        max_bytes: u64,
        file_len: Option<u64>,
    ) -> Result<Self> {
        let io_error = |message: String| Error::Io {
            path: name.into(),
            message,
        };
        check_file_len(file_len, max_bytes).map_err(io_error)?;
        let mut reader = reader.take(max_bytes.saturating_add(1));
        let mut head = vec![0u8; SNIFF_BYTES];
        let mut filled = 0;
        while filled < head.len() {
            match reader.read(&mut head[filled..]) {
                Ok(0) => break,
                Ok(k) => filled += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(io_error(e.to_string())),
            }
        }
        head.truncate(filled);
        if let Some(k) = head.iter().position(|&b| b == 0) {
            return Err(io_error(format!(
                "binary data (NUL byte at offset {k}), not a text input"
            )));
        }
        if head.len() as u64 > max_bytes {
            return Err(io_error(over_limit(max_bytes)));
        }
        Ok(TextStream {
            name: name.to_owned(),
            ended: filled < SNIFF_BYTES,
            head,
            rest: Box::new(reader),
            file_len,
            max_bytes,
        })
    }

    /// The name errors use.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// `true` when the first block ([`Self::head`]) is the whole input.
    pub fn head_is_whole(&self) -> bool {
        self.ended || self.file_len == Some(self.head.len() as u64)
    }

    /// Read one more block into the head (for format detection past long comments); `false`
    /// when the input has ended. The size limit applies; the NUL check was the first block's.
    pub fn extend_head(&mut self) -> Result<bool> {
        if self.head_is_whole() {
            return Ok(false);
        }
        let start = self.head.len();
        self.head.resize(start + SNIFF_BYTES, 0);
        let mut filled = start;
        while filled < self.head.len() {
            match self.rest.read(&mut self.head[filled..]) {
                Ok(0) => break,
                Ok(k) => filled += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => {
                    return Err(Error::Io {
                        path: self.name.clone(),
                        message: e.to_string(),
                    });
                }
            }
        }
        self.head.truncate(filled);
        self.ended = filled < start + SNIFF_BYTES;
        if self.head.len() as u64 > self.max_bytes {
            return Err(Error::Io {
                path: self.name.clone(),
                message: over_limit(self.max_bytes),
            });
        }
        Ok(filled > start)
    }

    /// The text of the first block (and of the blocks [`Self::extend_head`] added; a multi-byte
    /// character cut at its end left out); an error with the line when it holds a byte that is
    /// not UTF-8.
    pub fn head(&self) -> Result<&str> {
        match std::str::from_utf8(&self.head) {
            Ok(s) => Ok(s),
            Err(e) => {
                let at = e.valid_up_to();
                if e.error_len().is_some() || self.head_is_whole() {
                    return Err(utf8_error(&self.name, &self.head[..at], 0, at));
                }
                // a character cut by the end of the block: the valid prefix
                Ok(std::str::from_utf8(&self.head[..at]).unwrap_or_default())
            }
        }
    }

    /// Read the whole input as text, refused above `max_bytes` (from the file's size before
    /// reading when it is known) and when not UTF-8 (with the line of the first invalid byte).
    pub fn into_string(self, max_bytes: u64) -> Result<String> {
        let max_bytes = max_bytes.min(self.max_bytes);
        let name = self.name;
        let io_error = |message: String| Error::Io {
            path: name.clone(),
            message,
        };
        check_file_len(self.file_len, max_bytes).map_err(io_error)?;
        let mut bytes = self.head;
        if bytes.len() as u64 > max_bytes {
            return Err(io_error(over_limit(max_bytes)));
        }
        if !self.ended {
            let budget = max_bytes
                .saturating_add(1)
                .saturating_sub(bytes.len() as u64);
            self.rest
                .take(budget)
                .read_to_end(&mut bytes)
                .map_err(|e| io_error(e.to_string()))?;
        }
        if bytes.len() as u64 > max_bytes {
            return Err(io_error(over_limit(max_bytes)));
        }
        String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            utf8_error(&name, &e.as_bytes()[..at], 0, at)
        })
    }

    /// Stream the input line by line ([`TextLines`]), with the size limit of the stream.
    pub fn into_lines(self) -> TextLines<'a> {
        let reader = std::io::Cursor::new(self.head).chain(self.rest);
        TextLines {
            name: self.name,
            reader: Box::new(BufReader::with_capacity(SNIFF_BYTES, reader)),
            line: 0,
            offset: 0,
            buf: Vec::new(),
            max_bytes: self.max_bytes,
        }
    }
}

/// The lines of a text input, read one at a time: at most one line of text is held (up to
/// [`MAX_LINE_BYTES`]); errors name the input and the line (UTF-8, over-long lines, the size
/// limit). A lending iterator: each line borrows the reader until the next call.
///
/// ```
/// use rotavg::io::text::TextLines;
/// let mut lines = TextLines::from_text("t.txt", "  a b \r\n# c\n\n d\n");
/// assert_eq!(lines.next_content()?, Some((1, "a b")));
/// assert_eq!(lines.next_content()?, Some((4, "d")));
/// assert_eq!(lines.next_content()?, None);
/// assert_eq!(lines.lines_read(), 4);
/// // A line over the limit is an error naming it, not an allocation.
/// let long = format!("ok\n{}\n", "x".repeat(rotavg::io::text::MAX_LINE_BYTES + 1));
/// let mut lines = TextLines::from_text("long.txt", &long);
/// assert_eq!(lines.next_content()?, Some((1, "ok")));
/// let err = lines.next_content().unwrap_err().to_string();
/// assert!(err.starts_with("long.txt:2: the line is longer than"), "{err}");
/// # Ok::<(), rotavg::Error>(())
/// ```
pub struct TextLines<'a> {
    name: String,
    reader: Box<dyn BufRead + 'a>,
    line: usize,
    offset: u64,
    buf: Vec<u8>,
    max_bytes: u64,
}

impl std::fmt::Debug for TextLines<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TextLines")
            .field("name", &self.name)
            .field("line", &self.line)
            .field("offset", &self.offset)
            .finish_non_exhaustive()
    }
}

impl<'a> TextLines<'a> {
    /// The lines of text already in memory (no size limit; lines still at most
    /// [`MAX_LINE_BYTES`]), named `name` in errors.
    pub fn from_text(name: &str, text: &'a str) -> Self {
        TextLines {
            name: name.to_owned(),
            reader: Box::new(text.as_bytes()),
            line: 0,
            offset: 0,
            buf: Vec::new(),
            max_bytes: u64::MAX,
        }
    }

    /// The name errors use.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The number of lines read so far (after the end: the number of lines of the input, as
    /// [`str::lines`] counts them).
    pub fn lines_read(&self) -> usize {
        self.line
    }

    /// The next line, `(1-based line number, text without the line ending)`, `None` at the end.
    pub fn next_line(&mut self) -> Result<Option<(usize, &str)>> {
        if !self.read_raw_line()? {
            return Ok(None);
        }
        let start = self.offset - self.buf.len() as u64;
        let mut end = self.buf.len();
        if self.buf[..end].ends_with(b"\n") {
            end -= 1;
            if self.buf[..end].ends_with(b"\r") {
                end -= 1;
            }
        }
        match std::str::from_utf8(&self.buf[..end]) {
            Ok(s) => Ok(Some((self.line, s))),
            Err(e) => {
                let at = e.valid_up_to();
                Err(Error::parse(
                    Some(&self.name),
                    Some(self.line),
                    format!(
                        "not UTF-8 text (invalid byte at offset {})",
                        start + at as u64
                    ),
                ))
            }
        }
    }

    /// The next content line: `(1-based line number, trimmed line)`, skipping blank lines and
    /// `#` comments (as the line-oriented readers do); `None` at the end.
    pub fn next_content(&mut self) -> Result<Option<(usize, &str)>> {
        loop {
            let found = match self.next_line()? {
                None => return Ok(None),
                Some((_, l)) => {
                    let t = l.trim();
                    !t.is_empty() && !t.starts_with('#')
                }
            };
            if found {
                // read again through the buffer (the borrow of the loop ends above)
                let line = self.line;
                let text = self.current_text();
                return Ok(Some((line, text.trim())));
            }
        }
    }

    /// The text of the line last read by [`Self::next_line`] (already checked UTF-8).
    fn current_text(&self) -> &str {
        let mut end = self.buf.len();
        if self.buf[..end].ends_with(b"\n") {
            end -= 1;
            if self.buf[..end].ends_with(b"\r") {
                end -= 1;
            }
        }
        std::str::from_utf8(&self.buf[..end]).unwrap_or_default()
    }

    /// Read the next raw line (ending included) into `buf`; `false` at the end of the input.
    fn read_raw_line(&mut self) -> Result<bool> {
        self.buf.clear();
        loop {
            let available = match self.reader.fill_buf() {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => {
                    return Err(Error::Io {
                        path: self.name.clone(),
                        message: e.to_string(),
                    });
                }
            };
            if available.is_empty() {
                if self.buf.is_empty() {
                    return Ok(false);
                }
                self.line += 1;
                return Ok(true);
            }
            let (take, done) = match available.iter().position(|&b| b == b'\n') {
                Some(k) => (k + 1, true),
                None => (available.len(), false),
            };
            if self.buf.len() + take > MAX_LINE_BYTES {
                return Err(Error::parse(
                    Some(&self.name),
                    Some(self.line + 1),
                    format!("the line is longer than {MAX_LINE_BYTES} bytes (the limit of a line)"),
                ));
            }
            self.buf.extend_from_slice(&available[..take]);
            self.reader.consume(take);
            self.offset += take as u64;
            if self.offset > self.max_bytes {
                return Err(Error::Io {
                    path: self.name.clone(),
                    message: over_limit(self.max_bytes),
                });
            }
            if done {
                self.line += 1;
                return Ok(true);
            }
        }
    }
}

fn over_limit(max_bytes: u64) -> String {
    format!("the input has more than the input limit of {max_bytes} bytes")
}

fn check_file_len(file_len: Option<u64>, max_bytes: u64) -> std::result::Result<(), String> {
    match file_len {
        Some(len) if len > max_bytes => Err(format!(
            "the file has {len} bytes, more than the input limit of {max_bytes} bytes"
        )),
        _ => Ok(()),
    }
}

/// The error for an invalid byte at `offset + at`, `before` being the bytes of the input before
/// it (from `offset`), whose newlines give the line.
fn utf8_error(name: &str, before: &[u8], offset: u64, at: usize) -> Error {
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    Error::parse(
        Some(name),
        Some(line),
        format!(
            "not UTF-8 text (invalid byte at offset {})",
            offset + at as u64
        ),
    )
}

/// Check a line-by-line reader's record limit (`read` takes the lines and the limit): the text
/// `text` of `records` records is read with the limit `records` and refused with one less, the
/// error starting with `expected` (it names the file `t` and the line).
#[cfg(test)]
pub(crate) fn check_record_limit<T>(
    text: &str,
    records: usize,
    expected: &str,
    read: impl Fn(&mut TextLines<'_>, usize) -> Result<T>,
) {
    let read = |max| read(&mut TextLines::from_text("t", text), max);
    assert!(read(records).is_ok());
    let err = read(records - 1).err().expect("over the limit").to_string();
    assert!(err.starts_with(expected), "{err}");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn whole(bytes: &[u8], max: u64) -> Result<String> {
        TextStream::from_reader("t", bytes, max, None)?.into_string(max)
    }

    #[test]
    fn limits_and_nul() {
        assert_eq!(whole(b"abc\n", 10).unwrap(), "abc\n");
        assert!(
            whole(b"abcdefghijkl", 10)
                .unwrap_err()
                .to_string()
                .contains("limit")
        );
        let mut big = vec![b'a'; SNIFF_BYTES + 10];
        assert_eq!(whole(&big, 1 << 20).unwrap().len(), SNIFF_BYTES + 10);
        assert!(whole(&big, SNIFF_BYTES as u64 + 9).is_err());
        assert!(whole(&big, SNIFF_BYTES as u64 - 1).is_err());
        big[SNIFF_BYTES + 5] = 0; // after the sniffed block: still text to this reader, but
        // the parsers reject it as a malformed line
        assert!(whole(&big, 1 << 20).is_ok());
        assert!(
            whole(b"ab\0c", 10)
                .unwrap_err()
                .to_string()
                .contains("offset 2")
        );
        // the size a file reports is checked before reading
        let err = TextStream::from_reader("t", &b"ab"[..], 10, Some(11)).unwrap_err();
        assert!(err.to_string().contains("the file has 11 bytes"), "{err}");
    }

    #[test]
    fn streamed_lines_limits() {
        // the byte limit while streaming
        let text = "a\n".repeat(SNIFF_BYTES);
        let max = SNIFF_BYTES as u64 + 1000;
        let mut lines = TextStream::from_reader("t", text.as_bytes(), max, None)
            .unwrap()
            .into_lines();
        let mut err = None;
        for _ in 0..text.len() {
            match lines.next_line() {
                Ok(Some(_)) => {}
                Ok(None) => break,
                Err(e) => {
                    err = Some(e);
                    break;
                }
            }
        }
        let err = err.unwrap().to_string();
        assert!(
            err.contains(&format!("input limit of {max} bytes")),
            "{err}"
        );
        // UTF-8 errors name the line and the offset in the input
        let mut bytes = "x\n".repeat(SNIFF_BYTES).into_bytes();
        bytes.extend_from_slice(b"ok\ncaf\xe9\n");
        let mut lines = TextStream::from_reader("t", &bytes[..], u64::MAX, None)
            .unwrap()
            .into_lines();
        let err = loop {
            match lines.next_content() {
                Ok(Some(_)) => {}
                Ok(None) => panic!("no error"),
                Err(e) => break e.to_string(),
            }
        };
        let at = 2 * SNIFF_BYTES + 3 + 3;
        assert_eq!(
            err,
            format!(
                "t:{}: not UTF-8 text (invalid byte at offset {at})",
                SNIFF_BYTES + 2
            )
        );
        // lines as str::lines counts them, CRLF endings removed
        for text in [
            "",
            "\n",
            "a",
            "a\n",
            "a\r\nb",
            "a\n\n\nb\n",
            "\r\n\r\n",
            "a\r",
            "\r",
            "a\rb\n",
        ] {
            let mut lines = TextLines::from_text("t", text);
            let mut got = Vec::new();
            while let Some((_, l)) = lines.next_line().unwrap() {
                got.push(l.to_owned());
            }
            let want: Vec<String> = text.lines().map(str::to_owned).collect();
            assert_eq!(got, want, "{text:?}");
            assert_eq!(lines.lines_read(), want.len());
        }
    }

    /// The content lines streamed are those of the whole-text readers
    /// (`crate::io::content_lines`), also when the input arrives one byte at a time.
    #[test]
    fn content_lines_as_the_whole_text_readers() {
        struct Trickle<'a>(&'a [u8]);
        impl Read for Trickle<'_> {
            fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
                match (self.0.split_first(), buf.first_mut()) {
                    (Some((&b, rest)), Some(slot)) => {
                        *slot = b;
                        self.0 = rest;
                        Ok(1)
                    }
                    _ => Ok(0),
                }
            }
        }
        let texts = [
            "a\n  b c \r\n#d\n  # e\n\n\t\nf",
            "\u{2003}x\u{2003}\n\u{0b}\n\u{0c}y\n# z\r\n\r\n",
            "\r\rq\r\n",
            "#only\n#comments",
            "caf\u{e9} \u{1F600}\nlast line without newline",
        ];
        for text in texts {
            let want: Vec<(usize, String)> = crate::io::content_lines(text)
                .map(|(k, l)| (k, l.to_owned()))
                .collect();
            let collect = |mut lines: TextLines<'_>| {
                let mut got = Vec::new();
                while let Some((k, l)) = lines.next_content().unwrap() {
                    got.push((k, l.to_owned()));
                }
                (got, lines.lines_read())
            };
            let (got, count) = collect(TextLines::from_text("t", text));
            assert_eq!(got, want, "{text:?}");
            assert_eq!(count, crate::io::last_line(text).min(text.lines().count()));
            let stream =
                TextStream::from_reader("t", Trickle(text.as_bytes()), u64::MAX, None).unwrap();
            assert_eq!(collect(stream.into_lines()).0, want, "{text:?}");
        }
    }
}
