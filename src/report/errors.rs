//! An error as the command line prints it (`rotavg: error: TEXT`; contract section 5): the
//! input named where the error does not name a file, and a folder given to a verb that reads
//! files turned into what that verb reads instead.

use crate::error::Error;

/// The text of `e` from the verb `verb` (`single`, `multiple`, `conjugate`, `rig`, `certify`,
/// `info`, `demo`) run on `input`. An error about the data that does not name a file yet (a
/// disconnected graph, degenerate hand-eye pairs, an empty input) names the input; a folder
/// given as the input of a verb that cannot read it: the reader's error (the operating system's
/// "Is a directory", or the readers' general note on folders) becomes what this verb reads
/// instead; a specific diagnosis (a database.db that is not SQLite, no hand-eye streams found)
/// is kept.
///
/// ```
/// use rotavg::report::error_text;
/// let e = rotavg::Error::Empty { what: "the edge list".into() };
/// assert!(error_text(e, Some("graph.g2o"), "multiple").starts_with("graph.g2o: "));
/// ```
pub fn error_text(e: Error, input: Option<&str>, verb: &str) -> String {
    let text = match (e, input) {
        (
            e @ (Error::Disconnected { .. } | Error::Degenerate { .. } | Error::Empty { .. }),
            Some(file),
        ) if file != "-" => format!("{file}: {e}"),
        (e, _) => e.to_string(),
    };
    let Some(accepts) = folder_readers(verb) else {
        return text;
    };
    let Some(path) = input.filter(|p| *p != "-" && std::path::Path::new(p).is_dir()) else {
        return text;
    };
    match text.strip_prefix(path).and_then(|t| t.strip_prefix(": ")) {
        Some(m) if m.starts_with("is a folder, not a file") || m.contains("os error 21") => {
            format!("{path}: is a folder: {accepts}")
        }
        _ => text,
    }
}

/// What `verb` reads, for an error about a folder it cannot read.
fn folder_readers(verb: &str) -> Option<&'static str> {
    Some(match verb {
        "single" => "`rotavg single` reads a file (JSON {\"rotations\": [R, ...]}), never a folder",
        "multiple" | "info" | "rig" => {
            "as a folder, `rotavg multiple` and `rotavg info` read only a COLMAP project (a \
             folder holding database.db); other view graphs are files (g2o, 1DSfM EGs.txt, JSON)"
        }
        "conjugate" => {
            "as a folder, `rotavg conjugate` reads a Tabb dataset (robot_cali.txt) or a hand \
             and a camera pose stream (CSV files named *hand*/*base_link*/*vicon* and \
             *camera*/*target*, or --hand/--camera)"
        }
        "certify" => {
            "`rotavg certify` reads the problem from a file (a view graph: g2o, 1DSfM \
             EGs.txt, JSON; a single or conjugate JSON problem)"
        }
        _ => return None,
    })
}
