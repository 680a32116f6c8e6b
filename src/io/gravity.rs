//! Gravity priors from files (`paper-notes/formats.md`, `[F15]`; convention `[G1]`: `g_i` is the
//! world's down direction in camera `i`'s frame, `R_i world_down = g_i`), matched to the nodes
//! of a view graph already read:
//!
//! - **JSON**: `{"gravity": [g | null, ...], "world_down": g}` (one entry per node, in node
//!   order; `world_down` optional, default `(0, 0, 1)`), or `{"gravity": {"KEY": g, ...}}`
//!   keyed by the graph's file id or image name;
//! - **text**: one `KEY gx gy gz` per line (GLOMAP's gravity file: `KEY` an image name, or
//!   a file id), `#` comments, whitespace separated;
//! - **a COLMAP database** (`*.db`, cargo feature `colmap`): the `gravity` column of its
//!   `pose_priors` table (COLMAP 4), camera priors keyed by image id. COLMAP's cameras have
//!   `y` down the image and its global mapper's world has gravity along `+y`, so the world's
//!   down direction is `(0, 1, 0)` for these priors.
//!
//! Keys the graph does not have are skipped and counted (a prior for an image the graph
//! dropped); nodes without a key have no prior (the mixed problem). A vector that is not
//! finite or is zero is an error naming its line.

use crate::error::{Error, Result};
use crate::io::content_lines;
use crate::io::detect::LoadedGraph;
use crate::multiple::gravity::GravityPriors;
use std::collections::HashMap;

/// The priors read and what was skipped.
#[derive(Debug, Clone, PartialEq)]
pub struct GravityRead {
    /// The priors, one entry per node of the graph.
    pub priors: GravityPriors,
    /// Entries whose key is not a node of the graph (skipped).
    pub unmatched: usize,
}

impl GravityRead {
    /// The warning `gravity_unmatched` for the entries of the file `path` that match no node
    /// (`None` when all match).
    pub fn unmatched_warning(&self, path: &str) -> Option<crate::warning::Warning> {
        (self.unmatched > 0).then(|| {
            crate::warning::Warning::new(
                "gravity_unmatched",
                format!(
                    "{path}: {} gravity entries match no node of the graph (not used)",
                    self.unmatched
                ),
            )
            .with_count(self.unmatched)
        })
    }
}

/// Where a node's prior comes from: its index by file id and by name.
struct Keys<'a> {
    by_id: HashMap<u64, usize>,
    by_name: HashMap<&'a str, usize>,
}

impl<'a> Keys<'a> {
    fn of(graph: &'a LoadedGraph) -> Self {
        Keys {
            by_id: graph
                .node_ids
                .iter()
                .enumerate()
                .map(|(k, id)| (*id, k))
                .collect(),
            by_name: graph
                .node_names
                .iter()
                .enumerate()
                .map(|(k, n)| (n.as_str(), k))
                .collect(),
        }
    }

    /// The node of `key`: an image name first, then a file id.
    fn node(&self, key: &str) -> Option<usize> {
        self.by_name.get(key).copied().or_else(|| {
            key.parse::<u64>()
                .ok()
                .and_then(|id| self.by_id.get(&id).copied())
        })
    }
}

/// Read the priors of `path` for `graph` (JSON, text, or a COLMAP database, told by content).
/// `world_down` replaces the file's (or the format's) world down direction when given.
pub fn read_gravity(
    path: &str,
    graph: &LoadedGraph,
    world_down: Option<[f64; 3]>,
) -> Result<GravityRead> {
    let p = std::path::Path::new(path);
    let bytes = std::fs::read(p).map_err(|e| Error::Io {
        path: path.into(),
        message: e.to_string(),
    })?;
    let (dirs, file_down, unmatched) = if bytes.starts_with(b"SQLite format 3\0") {
        colmap_priors(p, graph)?
    } else {
        let text = String::from_utf8(bytes)
            .map_err(|_| Error::parse(Some(path), None, "not UTF-8 text (nor a database)"))?;
        if text.trim_start().starts_with('{') {
            json_priors(path, &text, graph)?
        } else {
            let (d, u) = text_priors(path, &text, graph)?;
            (d, None, u)
        }
    };
    let priors = GravityPriors::new(dirs).map_err(|e| match e {
        Error::Empty { .. } => Error::parse(
            Some(path),
            None,
            "no gravity prior matches a node of the graph (keys are image names or file ids)",
        ),
        other => other,
    })?;
    let priors = match world_down.or(file_down) {
        Some(w) => priors.with_world_down(w)?,
        None => priors,
    };
    Ok(GravityRead { priors, unmatched })
}

/// A vector of three finite numbers from `parts`, or an error at `line`.
fn vector(path: &str, line: usize, parts: &[&str]) -> Result<[f64; 3]> {
    let mut v = [0.0; 3];
    if parts.len() != 3 {
        return Err(Error::parse(
            Some(path),
            Some(line),
            format!("expected `KEY gx gy gz`, found {} numbers", parts.len()),
        ));
    }
    for (k, s) in parts.iter().enumerate() {
        v[k] = s
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| {
                Error::parse(
                    Some(path),
                    Some(line),
                    format!("`{s}` is not a finite number"),
                )
            })?;
    }
    if v.iter().all(|x| *x == 0.0) {
        return Err(Error::parse(
            Some(path),
            Some(line),
            "a zero vector has no direction",
        ));
    }
    Ok(v)
}

type Directions = Vec<Option<[f64; 3]>>;

/// `KEY gx gy gz` lines.
fn text_priors(path: &str, text: &str, graph: &LoadedGraph) -> Result<(Directions, usize)> {
    let keys = Keys::of(graph);
    let mut dirs = vec![None; graph.problem.num_rotations()];
    let mut unmatched = 0;
    for (line, l) in content_lines(text) {
        let parts: Vec<&str> = l.split_whitespace().collect();
        let v = vector(path, line, &parts[1..])?;
        match keys.node(parts[0]) {
            Some(k) => dirs[k] = Some(v),
            None => unmatched += 1,
        }
    }
    Ok((dirs, unmatched))
}

/// The JSON forms.
fn json_priors(
    path: &str,
    text: &str,
    graph: &LoadedGraph,
) -> Result<(Directions, Option<[f64; 3]>, usize)> {
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Entries {
        List(Vec<Option<[f64; 3]>>),
        Keyed(HashMap<String, [f64; 3]>),
    }
    #[derive(serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        gravity: Entries,
        world_down: Option<[f64; 3]>,
    }
    let file: File = serde_json::from_str(text).map_err(|e| {
        Error::parse(
            Some(path),
            Some(e.line()),
            format!("{e} (expected {{\"gravity\": [[gx, gy, gz] | null, ...], \"world_down\": [x, y, z]}})"),
        )
    })?;
    let n = graph.problem.num_rotations();
    Ok(match file.gravity {
        Entries::List(list) if list.len() != n => {
            return Err(Error::parse(
                Some(path),
                None,
                format!(
                    "{} gravity entries for a graph of {n} nodes (one per node, null for none; \
                     or an object keyed by image name or file id)",
                    list.len()
                ),
            ));
        }
        Entries::List(list) => (list, file.world_down, 0),
        Entries::Keyed(map) => {
            let keys = Keys::of(graph);
            let mut dirs = vec![None; n];
            let mut unmatched = 0;
            for (key, v) in map {
                match keys.node(&key) {
                    Some(k) => dirs[k] = Some(v),
                    None => unmatched += 1,
                }
            }
            (dirs, file.world_down, unmatched)
        }
    })
}

/// COLMAP 4's `pose_priors.gravity` (camera priors, keyed by image id).
#[cfg(feature = "colmap")]
fn colmap_priors(
    path: &std::path::Path,
    graph: &LoadedGraph,
) -> Result<(Directions, Option<[f64; 3]>, usize)> {
    let rows = crate::io::colmap::database::gravity_priors(path)?;
    let keys = Keys::of(graph);
    let mut dirs = vec![None; graph.problem.num_rotations()];
    let mut unmatched = 0;
    for (image_id, g) in rows {
        match keys.by_id.get(&image_id) {
            Some(&k) => dirs[k] = Some(g),
            None => unmatched += 1,
        }
    }
    Ok((dirs, Some([0.0, 1.0, 0.0]), unmatched))
}

#[cfg(not(feature = "colmap"))]
fn colmap_priors(
    path: &std::path::Path,
    _graph: &LoadedGraph,
) -> Result<(Directions, Option<[f64; 3]>, usize)> {
    Err(Error::parse(
        Some(&path.display().to_string()),
        None,
        "a COLMAP database needs the `colmap` feature",
    ))
}
