//! Gravity priors for `average_multiple` / `certify_multiple` (`gravity=`, `world_down=`,
//! `gravity_weight=`: soft priors of that weight instead of constraints): an
//! `(n, 3)` array (a row of NaN: no prior for that image), `(n, 4)` with each prior's relative
//! weight (soft priors weigh `gravity_weight` times it; NaN: 1), or the path of a priors file,
//! read as `rotavg multiple --gravity` reads it; for `average_rig_file` / `certify_rig_file`,
//! one row per image of the rig, or a file keyed by image id or name (`[G14]`); for
//! `average_rig` / `certify_rig`, one row per node of the reference graph (its frames).

use crate::convert::gravity_rows;
use pyo3::prelude::*;
use rotavg::io::detect::{ComponentSelection, LoadedGraph};
use rotavg::io::gravity::GravityRead;
use rotavg::io::rig::LoadedRig;
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
        let (priors, warnings) = self.node_priors((graph, selection), world_down, weight)?;
        Ok((
            GravityProblem::new(graph.problem.clone(), priors)?,
            warnings,
        ))
    }

    /// These priors on the nodes of `right` (the nodes `selection` kept), with the reader's
    /// warnings: rows in node order, or a file keyed as `read_gravity` keys the nodes. Also the
    /// frames' priors of two view graphs, `right` the reference graph (`[G14]` "Two view
    /// graphs"; `rig_two_graphs::two_graph_rig`).
    pub fn node_priors(
        self,
        (right, selection): (&LoadedGraph, &ComponentSelection),
        world_down: Option<[f64; 3]>,
        weight: Option<f64>,
    ) -> rotavg::Result<(GravityPriors, Vec<Warning>)> {
        self.priors(
            |p| rotavg::io::gravity::read_gravity(p, right, world_down),
            |rows| crate::for_kept(rows, selection, "gravity"),
            world_down,
            weight,
        )
    }

    /// `rig` with these priors on its images (rows in image order, or a file keyed by image id
    /// or name; `[G14]`), the reader's warnings added to the rig's.
    pub fn apply_to_rig(
        self,
        rig: LoadedRig,
        world_down: Option<[f64; 3]>,
        weight: Option<f64>,
    ) -> rotavg::Result<LoadedRig> {
        let (priors, warnings) = self.priors(
            |p| rotavg::io::gravity::read_rig_gravity(p, &rig, world_down),
            Ok,
            world_down,
            weight,
        )?;
        rig.with_gravity(priors, warnings)
    }

    /// The priors (read by `read` from a path, or the rows as `kept`), soft of `weight`, and
    /// the warnings.
    fn priors(
        self,
        read: impl FnOnce(&str) -> rotavg::Result<GravityRead>,
        kept: impl FnOnce(Vec<[f64; 4]>) -> rotavg::Result<Vec<[f64; 4]>>,
        world_down: Option<[f64; 3]>,
        weight: Option<f64>,
    ) -> rotavg::Result<(GravityPriors, Vec<Warning>)> {
        match self {
            GravityInput::Path(p) => read(&p)?.priors_and_warnings(&p, weight),
            GravityInput::Rows(rows) => {
                let rows = kept(rows)?;
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
                let read = GravityRead {
                    priors,
                    unmatched: 0,
                };
                read.priors_and_warnings("gravity", weight)
            }
        }
    }
}
