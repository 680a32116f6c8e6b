//! Gravity priors for `average_multiple` / `certify_multiple` (`gravity=`, `world_down=`,
//! `gravity_weight=`: soft priors of that weight instead of constraints): an
//! `(n, 3)` array (a row of NaN: no prior for that image), `(n, 4)` with each prior's relative
//! weight (soft priors weigh `gravity_weight` times it; NaN: 1), or the path of a priors file,
//! read as `rotavg multiple --gravity` reads it.

use crate::convert::gravity_rows;
use pyo3::prelude::*;
use rotavg::io::detect::{ComponentSelection, LoadedGraph};
use rotavg::multiple::gravity::{GravityPriors, GravityProblem};
use rotavg::warning::Warning;

/// The priors as given.
pub enum GravityInput {
    /// One row per input node (NaN directions: none), its relative weight fourth (NaN: 1).
    Rows(Vec<[f64; 4]>),
    /// A file, matched to the nodes by image name or file id.
    Path(String),
}

impl GravityInput {
    /// `gravity` (`None` or Python `None`: no priors).
    pub fn from_py(obj: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Self>> {
        let Some(obj) = obj.filter(|o| !o.is_none()) else {
            return Ok(None);
        };
        if let Some(p) = crate::convert::path_of(obj) {
            return Ok(Some(GravityInput::Path(p)));
        }
        Ok(Some(GravityInput::Rows(gravity_rows(obj, "gravity")?)))
    }

    /// The gravity problem of `graph` (the nodes `selection` kept), soft of weight `weight`
    /// when given, and the warning for file entries no node matches.
    pub fn problem(
        self,
        graph: &LoadedGraph,
        selection: &ComponentSelection,
        world_down: Option<[f64; 3]>,
        weight: Option<f64>,
    ) -> rotavg::Result<(GravityProblem, Vec<Warning>)> {
        let (priors, warnings) = match self {
            GravityInput::Path(p) => {
                let read = rotavg::io::gravity::read_gravity(&p, graph, world_down)?;
                let w = read.warnings(&p, weight);
                (read.priors, w)
            }
            GravityInput::Rows(rows) => {
                let rows = crate::for_kept(rows, selection, "gravity")?;
                let dirs = rows
                    .iter()
                    .map(|g| (!g[..3].iter().any(|x| x.is_nan())).then_some([g[0], g[1], g[2]]))
                    .collect();
                let scales = rows
                    .iter()
                    .map(|g| (!g[3].is_nan()).then_some(g[3]))
                    .collect();
                let priors = GravityPriors::new(dirs)?.with_scales(scales)?;
                let priors = match world_down {
                    Some(w) => priors.with_world_down(w)?,
                    None => priors,
                };
                let read = rotavg::io::gravity::GravityRead {
                    priors,
                    unmatched: 0,
                };
                let w = read.warnings("gravity", weight);
                (read.priors, w)
            }
        };
        let priors = priors.soft_if(weight)?;
        Ok((
            GravityProblem::new(graph.problem.clone(), priors)?,
            warnings,
        ))
    }
}
