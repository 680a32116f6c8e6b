//! Gravity priors from files (`paper-notes/formats.md`, `[F15]`; convention `[G1]`: `g_i` is the
//! world's down direction in camera `i`'s frame, `R_i world_down = g_i`), matched to the nodes
//! of a view graph already read:
//!
//! - **JSON**: `{"gravity": [g | null, ...], "world_down": g}` (one entry per node, in node
//!   order; `world_down` optional, default `(0, 0, 1)`), or `{"gravity": {"KEY": g, ...}}`
//!   keyed by the graph's file id or image name;
//! - **text**: one `KEY gx gy gz` per line (GLOMAP's gravity file: `KEY` an image name, or
//!   a file id), `#` comments, whitespace separated;
//! - in JSON and text, a fourth number after a direction is that prior's **relative weight**
//!   (soft priors weigh `--gravity-weight` times it; default 1;
//!   [`GravityPriors::with_scales`]);
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
    /// The priors read from `path`, soft of `weight` when given ([`GravityPriors::soft_if`]),
    /// with [`Self::warnings`].
    pub fn priors_and_warnings(
        self,
        path: &str,
        weight: Option<f64>,
    ) -> Result<(GravityPriors, Vec<crate::warning::Warning>)> {
        let warnings = self.warnings(path, weight);
        Ok((self.priors.soft_if(weight)?, warnings))
    }

    /// The warnings about the file `path` read for priors soft of `weight` (`None`: held):
    /// `gravity_unmatched` for entries that match no node, `gravity_scales_unused` for relative
    /// weights given to held priors (which have no weight).
    pub fn warnings(&self, path: &str, weight: Option<f64>) -> Vec<crate::warning::Warning> {
        use crate::warning::Warning;
        let mut out = Vec::new();
        if self.unmatched > 0 {
            let text = format!(
                "{path}: {} gravity entries match no node of the graph (not used)",
                self.unmatched
            );
            out.push(Warning::new("gravity_unmatched", text).with_count(self.unmatched));
        }
        let scaled = self.priors.num_scaled();
        if scaled > 0 && weight.is_none() {
            let text = format!(
                "{path}: {scaled} gravity priors have a relative weight (a fourth number), which \
                 only soft priors use: they are held as constraints here (add --gravity-weight W)"
            );
            out.push(Warning::new("gravity_scales_unused", text).with_count(scaled));
        }
        out
    }
}

/// Where a node's prior comes from: its index by file id and by name, and the node count.
struct Keys<'a> {
    by_id: HashMap<u64, usize>,
    by_name: HashMap<&'a str, usize>,
    n: usize,
}

impl<'a> Keys<'a> {
    /// The keys of nodes with file ids `ids` and names `names` (one each, or no names).
    fn new(ids: &[u64], names: &'a [String]) -> Self {
        Keys {
            by_id: ids.iter().enumerate().map(|(k, id)| (*id, k)).collect(),
            by_name: names
                .iter()
                .enumerate()
                .map(|(k, n)| (n.as_str(), k))
                .collect(),
            n: ids.len(),
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
    read_keyed(
        path,
        &Keys::new(&graph.node_ids, &graph.node_names),
        world_down,
    )
}

/// [`read_gravity`] for the images of a rig (`rotavg rig FILE --gravity`, `[G14]`): keyed by
/// image id (COLMAP's `image_id`; the index in a JSON rig) or image name (COLMAP's), one
/// entry per image in a JSON list.
pub fn read_rig_gravity(
    path: &str,
    rig: &crate::io::rig::LoadedRig,
    world_down: Option<[f64; 3]>,
) -> Result<GravityRead> {
    read_keyed(
        path,
        &Keys::new(&rig.image_ids, &rig.image_names),
        world_down,
    )
}

/// The text form of priors (`KEY gx gy gz` lines, `KEY` the node's or image's index; no line
/// for `None`), with a comment line saying what they are: what `read_gravity` and
/// `read_rig_gravity` read back for nodes keyed by index.
///
/// ```
/// use rotavg::io::gravity::write_gravity_text;
/// let text = write_gravity_text(&[Some([0.0, 0.0, 1.0]), None, Some([0.0, 0.5, 1.0])]);
/// assert_eq!(text.lines().filter(|l| !l.starts_with('#')).count(), 2);
/// assert!(text.contains("\n2 0 0.5 1\n"));
/// ```
pub fn write_gravity_text(directions: &[Option<[f64; 3]>]) -> String {
    let lines: String = (directions.iter().enumerate())
        .filter_map(|(a, d)| d.map(|d| format!("{a} {} {} {}\n", d[0], d[1], d[2])))
        .collect();
    format!("# image gx gy gz: the world's down direction in the camera\n{lines}")
}

/// The priors of `path` for the nodes `keys` name.
fn read_keyed(path: &str, keys: &Keys<'_>, world_down: Option<[f64; 3]>) -> Result<GravityRead> {
    let p = std::path::Path::new(path);
    let bytes = std::fs::read(p).map_err(|e| Error::Io {
        path: path.into(),
        message: e.to_string(),
    })?;
    let (dirs, file_down, unmatched) = if bytes.starts_with(b"SQLite format 3\0") {
        colmap_priors(p, keys)?
    } else {
        let text = String::from_utf8(bytes)
            .map_err(|_| Error::parse(Some(path), None, "not UTF-8 text (nor a database)"))?;
        if text.trim_start().starts_with('{') {
            json_priors(path, &text, keys)?
        } else {
            let (d, u) = text_priors(path, &text, keys)?;
            (d, None, u)
        }
    };
    let scales = dirs.iter().map(|d| d.and_then(|(_, s)| s)).collect();
    let dirs = dirs.into_iter().map(|d| d.map(|(g, _)| g)).collect();
    let priors = GravityPriors::new(dirs).map_err(|e| match e {
        Error::Empty { .. } => Error::parse(
            Some(path),
            None,
            "no gravity prior matches a node of the graph or an image of the rig (keys are image \
             names or file ids)",
        ),
        other => other,
    })?;
    let priors = match world_down.or(file_down) {
        Some(w) => priors.with_world_down(w)?,
        None => priors,
    };
    let priors = priors
        .with_scales(scales)
        .map_err(|e| Error::parse(Some(path), None, e.to_string()))?;
    Ok(GravityRead { priors, unmatched })
}

/// A direction of three finite numbers from `parts` and, when a fourth follows, its relative
/// weight (finite, positive), or an error at `line` (`None` for a JSON entry: no lines).
fn entry(path: &str, line: Option<usize>, parts: &[&str]) -> Result<Prior> {
    let numbers = parts
        .iter()
        .map(|s| {
            s.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    Error::parse(Some(path), line, format!("`{s}` is not a finite number"))
                })
        })
        .collect::<Result<Vec<f64>>>()?;
    prior(path, line, &numbers)
}

/// [`entry`] of parsed numbers.
fn prior(path: &str, line: Option<usize>, numbers: &[f64]) -> Result<Prior> {
    let fail = |m: String| Error::parse(Some(path), line, m);
    let (g, scale) = match numbers {
        [x, y, z] => ([*x, *y, *z], None),
        [x, y, z, s] => ([*x, *y, *z], Some(*s)),
        other => {
            return Err(fail(format!(
                "expected `KEY gx gy gz [relative weight]`, found {} numbers",
                other.len()
            )));
        }
    };
    if g.iter().all(|x| *x == 0.0) {
        return Err(fail("a zero vector has no direction".into()));
    }
    if let Some(s) = scale
        && !(s.is_finite() && s > 0.0)
    {
        return Err(fail(format!(
            "relative weight {s}: it must be finite and positive"
        )));
    }
    Ok((g, scale))
}

/// A prior: its direction and, when given, its relative weight.
type Prior = ([f64; 3], Option<f64>);

type Directions = Vec<Option<Prior>>;

/// `KEY gx gy gz` lines.
fn text_priors(path: &str, text: &str, keys: &Keys<'_>) -> Result<(Directions, usize)> {
    let mut dirs = vec![None; keys.n];
    let mut unmatched = 0;
    for (line, l) in content_lines(text) {
        let parts: Vec<&str> = l.split_whitespace().collect();
        let v = entry(path, Some(line), &parts[1..])?;
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
    keys: &Keys<'_>,
) -> Result<(Directions, Option<[f64; 3]>, usize)> {
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Entries {
        List(Vec<Option<Vec<f64>>>),
        Keyed(HashMap<String, Vec<f64>>),
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
            format!("{e} (expected {{\"gravity\": [[gx, gy, gz(, weight)] | null, ...], \"world_down\": [x, y, z]}})"),
        )
    })?;
    let n = keys.n;
    Ok(match file.gravity {
        Entries::List(list) if list.len() != n => {
            return Err(Error::parse(
                Some(path),
                None,
                format!(
                    "{} gravity entries for {n} nodes or images (one each, null for none; or an \
                     object keyed by image name or file id)",
                    list.len()
                ),
            ));
        }
        Entries::List(list) => {
            let priors = list
                .iter()
                .map(|v| v.as_ref().map(|v| prior(path, None, v)).transpose())
                .collect::<Result<Directions>>()?;
            (priors, file.world_down, 0)
        }
        Entries::Keyed(map) => {
            let mut dirs = vec![None; n];
            let mut unmatched = 0;
            for (key, v) in map {
                match keys.node(&key) {
                    Some(k) => dirs[k] = Some(prior(path, None, &v)?),
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
    keys: &Keys<'_>,
) -> Result<(Directions, Option<[f64; 3]>, usize)> {
    let rows = crate::io::colmap::database::gravity_priors(path)?;
    let mut dirs = vec![None; keys.n];
    let mut unmatched = 0;
    for (image_id, g) in rows {
        match keys.by_id.get(&image_id) {
            Some(&k) => dirs[k] = Some((g, None)),
            None => unmatched += 1,
        }
    }
    Ok((dirs, Some([0.0, 1.0, 0.0]), unmatched))
}

#[cfg(not(feature = "colmap"))]
fn colmap_priors(
    path: &std::path::Path,
    _keys: &Keys<'_>,
) -> Result<(Directions, Option<[f64; 3]>, usize)> {
    Err(Error::parse(
        Some(&path.display().to_string()),
        None,
        "a COLMAP database needs the `colmap` feature",
    ))
}
