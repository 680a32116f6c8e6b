//! A warning: what the text output says on a `warning:` line, with a stable code and a count,
//! so that the JSON carries every warning the text prints (`warnings` of every `--json`
//! report, `docs/reference/cli.md`).
//!
//! | code | from | count |
//! |---|---|---|
//! | `skipped_lines` | g2o: lines with an unknown tag | lines |
//! | `mixed_dimensions` | g2o: 2-D and 3-D lines in one file | |
//! | `no_initial_estimate` | g2o: nodes without a vertex line | nodes |
//! | `without_information` | g2o / TORO: edge lines without an information matrix (weight 1) | edges |
//! | `information_symmetrized` | JSON, Python: information matrices asymmetric by rounding (their symmetric part used; `io::detect::information_symmetrized`) | edges |
//! | `skipped_by_config` | COLMAP: two-view geometries of a config without a rotation | geometries |
//! | `skipped_without_pose` | COLMAP: two-view geometries without a stored relative pose | geometries |
//! | `skipped_without_information` | COLMAP information (`--information auto` or `full`): geometries whose correspondences give none | geometries |
//! | `pairs_reestimated` | COLMAP information (`--information auto` or `full`): pairs measured by their pose re-estimated without their wrong matches, not by the stored rotation (`paper-notes/formats.md` `[F13]`) | pairs |
//! | `within_frame_information_pooled` | COLMAP rigs with information (`--information full`): within-frame pairs measured with their sensor pair's pooled information, not their own (`paper-notes/formats.md` `[F18]`) | pairs |
//! | `outliers_suspected` | least squares whose residuals look like outliers | suspected edges |
//! | `output_not_written` | `--edges-output` / `--inlier-output` with no robust solve | files |
//! | `database_without_information` | `--information auto` (the default) on a COLMAP database that gives no two-view information (no keypoints, no `tvec`, an unsupported camera, ...): read with weights 1, the reason named | - |
//! | `estimate_unmatched` | `certify --estimate`: entries that match no node (not used) | entries |
//! | `translations_not_finite` | `certify --estimate`: COLMAP images with NaN translations (not used) | images |
//! | `name_not_format` | a text view graph named like a COLMAP database (`*.db`): read by its content | |
//! | `duplicates_disagree` | view graphs: pairs measured more than once whose measurements disagree by more than 5 deg | pairs |
//! | `estimate_projected` | `certify --nearest-rotations`: the estimate's matrices replaced by their nearest rotations (negated first when all are reflections) | matrices |
//! | `convention_suspected` | `certify`: the estimate transposed costs less than a quarter of the estimate as given | |
//! | `gravity_convention` | `--gravity`: the priors fit the relative rotations far better in another axis convention (named) | |
//! | `gravity_inconsistent` | `--gravity`: the priors disagree with the relative rotations by more than 5 deg in median | |
//! | `gravity_points_up` | `--gravity`: most priors point up the image (`-y` in OpenCV / COLMAP axes) | |
//! | `gravity_imprecise` | `--gravity` held on a graph with information: the priors disagree with the edges by more than 3 of their standard deviations in median | |
//! | `gravity_unmatched` | `--gravity`: entries whose key is no node of the graph (not used) | entries |
//! | `gravity_scales_unused` | `--gravity` without `--gravity-weight`: relative weights given to held priors (not used) | priors |

use serde::{Deserialize, Serialize};
use std::fmt;

/// A warning with its stable `code`, the `message` the text prints, and a count where the
/// warning counts something (lines, edges, geometries).
///
/// ```
/// use rotavg::warning::Warning;
/// let w = Warning::new("skipped_lines", "skipped 2 line(s) with unknown tag `FIX`").with_count(2);
/// assert_eq!(w.to_string(), "skipped 2 line(s) with unknown tag `FIX`");
/// assert_eq!(serde_json::to_value(&w).unwrap()["count"], 2);
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Warning {
    /// Stable identifier of the kind of warning (the table of [`crate::warning`]).
    pub code: String,
    /// What the text output prints.
    pub message: String,
    /// What it counts, if anything.
    pub count: Option<usize>,
}

impl Warning {
    /// A warning without a count.
    pub fn new(code: &str, message: impl Into<String>) -> Self {
        Warning {
            code: code.to_owned(),
            message: message.into(),
            count: None,
        }
    }

    /// The same warning counting `count` things.
    pub fn with_count(mut self, count: usize) -> Self {
        self.count = Some(count);
        self
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}
