//! Gravity priors for `average_multiple` / `certify_multiple` (`gravity=`, `world_down=`,
//! `gravity_weight=`: soft priors of that weight instead of constraints): an
//! `(n, 3)` array (a row of NaN: no prior for that image) or the path of a priors file, read
//! as `rotavg multiple --gravity` reads it.

use crate::convert::rows3;
use pyo3::prelude::*;
use rotavg::io::detect::{ComponentSelection, LoadedGraph};
use rotavg::multiple::gravity::{GravityPriors, GravityProblem};
use rotavg::warning::Warning;

/// The priors as given.
pub enum GravityInput {
    /// One row per input node (NaN rows: none).
    Rows(Vec<[f64; 3]>),
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
        Ok(Some(GravityInput::Rows(rows3(obj, "gravity")?)))
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
                let w = read.unmatched_warning(&p);
                (read.priors, w.into_iter().collect())
            }
            GravityInput::Rows(rows) => {
                let rows = crate::for_kept(rows, selection, "gravity")?;
                let dirs = rows
                    .into_iter()
                    .map(|g| (!g.iter().any(|x| x.is_nan())).then_some(g))
                    .collect();
                let priors = GravityPriors::new(dirs)?;
                let priors = match world_down {
                    Some(w) => priors.with_world_down(w)?,
                    None => priors,
                };
                (priors, Vec::new())
            }
        };
        let priors = priors.soft_if(weight)?;
        Ok((
            GravityProblem::new(graph.problem.clone(), priors)?,
            warnings,
        ))
    }
}
