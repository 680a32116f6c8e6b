//! Writing estimates to files, as `rotavg multiple --output PATH [--output-format F]` does:
//! [`OutputFormat`] `auto` picks g2o for a `.g2o` path, a COLMAP sparse model for a folder or a
//! path ending in `images.txt`, otherwise JSON `{"node_ids": [...], "rotations": [R, ...]}`
//! (readable by [`crate::io::json::read_estimate`]). [`prepare_output`] resolves the path and
//! creates its folder before the solve; [`EstimateFile::write_planned`] writes outputs that
//! round-trip (a g2o input's vertices and edges kept, a loadable COLMAP model).

use crate::error::{Error, Result};
use crate::io::detect::{GraphFormat, LoadedGraph};
use crate::multiple::MultipleProblem;
use crate::multiple::robust::EdgeResiduals;
use crate::pipeline::MultipleEstimate;
use crate::so3::Rotation;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The format of an estimate file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputFormat {
    /// From the path ([`OutputFormat::for_path`]).
    #[default]
    Auto,
    /// `{"node_ids": [...], "rotations": [R, ...]}`.
    Json,
    /// g2o: the problem's edges and the estimate as vertex lines ([`crate::io::g2o::write_g2o`]).
    G2o,
    /// COLMAP `images.txt` ([`crate::io::colmap::write_images_text`]).
    Colmap,
}

impl OutputFormat {
    /// The format `auto` means for `path`: g2o for `*.g2o`, COLMAP for `*images.txt`, else
    /// JSON; any other value is returned unchanged.
    ///
    /// ```
    /// use rotavg::io::output::OutputFormat;
    /// assert_eq!(OutputFormat::Auto.for_path("sparse/images.txt"), OutputFormat::Colmap);
    /// assert_eq!(OutputFormat::Auto.for_path("est.g2o"), OutputFormat::G2o);
    /// assert_eq!(OutputFormat::Auto.for_path("est.txt"), OutputFormat::Json);
    /// assert_eq!(OutputFormat::Colmap.for_path("est.txt"), OutputFormat::Colmap);
    /// ```
    pub fn for_path(self, path: &str) -> OutputFormat {
        if self != OutputFormat::Auto {
            return self;
        }
        let lower = path.to_ascii_lowercase();
        if lower.ends_with(".g2o") {
            OutputFormat::G2o
        } else if lower.ends_with("images.txt") {
            OutputFormat::Colmap
        } else {
            OutputFormat::Json
        }
    }
}

/// Where an estimate goes, resolved before the solve by [`prepare_output`]: the format and,
/// for a COLMAP sparse model, its folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputPlan {
    /// The path as given.
    pub path: String,
    /// The format (never `auto`).
    pub format: OutputFormat,
    /// COLMAP: the folder that receives `cameras.txt` and `points3D.txt` beside the images
    /// file (`None` for a single images file under another name).
    pub model_dir: Option<PathBuf>,
    /// The file written (for a COLMAP folder, its `images.txt`).
    pub file: PathBuf,
    /// The folders [`prepare_output`] created for it, outermost first (none when they all
    /// existed): [`Self::remove_empty_folders`] takes them back when nothing was written.
    pub created: Vec<PathBuf>,
}

impl OutputPlan {
    /// Remove the folders this plan created that are still empty, innermost first: what a run
    /// that wrote nothing there (it failed, or had nothing to write) leaves behind. Folders
    /// holding anything, and folders that existed before, are kept.
    pub fn remove_empty_folders(&self) {
        for dir in self.created.iter().rev() {
            // fails, harmlessly, on a folder that is not empty
            let _ = std::fs::remove_dir(dir);
        }
    }

    /// `outcome` of writing this plan's output, with [`Self::remove_empty_folders`] when it
    /// failed: what a writer returns so that a failure leaves no folder behind.
    pub fn cleaned(&self, outcome: Result<()>) -> Result<()> {
        if outcome.is_err() {
            self.remove_empty_folders();
        }
        outcome
    }

    /// Write `text` to [`Self::file`] ([`write_text`]), leaving no new folder if it fails.
    pub fn write_text(&self, text: &str) -> Result<()> {
        self.cleaned(write_text(&self.file.display().to_string(), text))
    }
}

/// The folders `create_dir_all(dir)` would create, outermost first.
fn missing_folders(dir: &Path) -> Vec<PathBuf> {
    let mut missing: Vec<PathBuf> = dir
        .ancestors()
        .take_while(|d| !d.as_os_str().is_empty() && !d.exists())
        .map(Path::to_path_buf)
        .collect();
    missing.reverse();
    missing
}

/// Resolve an output path and create its folder, **before** any work is done: a path ending
/// in `/` or naming an existing folder is a COLMAP sparse model folder (created when missing;
/// `auto` and `colmap` only), a path ending in `images.txt` a COLMAP model in its parent folder
/// (`cameras.txt`, `images.txt`, `points3D.txt`), another path with `--output-format colmap` a
/// lone images file; g2o and JSON are one file. Missing parent folders are created; an error
/// (naming the path) when a folder cannot be created or a file would replace a folder.
///
/// ```
/// use rotavg::io::output::{prepare_output, OutputFormat};
/// let base = std::env::temp_dir().join(format!("rotavg-doc-prepare-{}", std::process::id()));
/// let dir = format!("{}/sparse/0/", base.display());
/// let plan = prepare_output(&dir, OutputFormat::Auto)?;
/// assert_eq!(plan.format, OutputFormat::Colmap);
/// assert!(plan.file.ends_with("images.txt") && std::path::Path::new(&dir).is_dir());
/// let json = prepare_output(&format!("{}/out/est.json", base.display()), OutputFormat::Auto)?;
/// assert!(json.model_dir.is_none() && base.join("out").is_dir());
/// assert!(prepare_output(&dir, OutputFormat::Json).is_err()); // a folder is not a JSON file
/// std::fs::remove_dir_all(&base).unwrap();
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn prepare_output(path: &str, format: OutputFormat) -> Result<OutputPlan> {
    let p = Path::new(path);
    let folder = path.ends_with('/') || path.ends_with(std::path::MAIN_SEPARATOR) || p.is_dir();
    let io = |message: String| Error::Io {
        path: path.into(),
        message,
    };
    let mkdir = |d: &Path| -> Result<()> {
        if d.as_os_str().is_empty() || d.is_dir() {
            return Ok(());
        }
        std::fs::create_dir_all(d).map_err(|e| Error::Io {
            path: d.display().to_string(),
            message: format!("cannot create the output folder: {e}"),
        })
    };
    if folder {
        return match format {
            OutputFormat::Auto | OutputFormat::Colmap => {
                let created = missing_folders(p);
                mkdir(p)?;
                Ok(OutputPlan {
                    path: path.into(),
                    format: OutputFormat::Colmap,
                    model_dir: Some(p.to_path_buf()),
                    file: p.join("images.txt"),
                    created,
                })
            }
            f => Err(io(format!(
                "a folder, but --output-format {} writes one file: give a file name",
                crate::io::names::Choice::name(&f)
            ))),
        };
    }
    let format = format.for_path(path);
    let parent = p.parent().unwrap_or(Path::new(""));
    let created = missing_folders(parent);
    mkdir(parent)?;
    let model_dir = (format == OutputFormat::Colmap
        && path.to_ascii_lowercase().ends_with("images.txt"))
    .then(|| parent.to_path_buf());
    Ok(OutputPlan {
        path: path.into(),
        format,
        model_dir,
        file: p.to_path_buf(),
        created,
    })
}

/// Where the problem came from, for outputs that keep what the input had: a g2o input's
/// vertices and edges, a COLMAP database's cameras.
#[derive(Debug, Clone, Copy)]
pub struct OutputSource<'a> {
    /// The input path as given (`-` for standard input).
    pub input: &'a str,
    /// The input's format.
    pub format: GraphFormat,
}

impl OutputSource<'_> {
    /// An error, before the solve, for outputs this source cannot give: g2o output of a g2o
    /// problem read from standard input (its vertices and edges cannot be read again).
    pub fn check(&self, plan: &OutputPlan) -> Result<()> {
        if plan.format == OutputFormat::G2o && self.format == GraphFormat::G2o && self.input == "-"
        {
            return Err(Error::InvalidSettings {
                name: "--output".into(),
                reason: format!(
                    "{}: g2o output keeps the input's vertices and edges, which cannot be read \
                     again from standard input: give the input as a file, or write JSON",
                    plan.path
                ),
            });
        }
        Ok(())
    }
}

/// What an estimate file holds: the problem, the estimate and the file's node ids and names.
#[derive(Debug, Clone, Copy)]
pub struct EstimateFile<'a> {
    /// The problem solved (its edges go into g2o files).
    pub problem: &'a MultipleProblem,
    /// The estimate, one rotation per node.
    pub rotations: &'a [Rotation],
    /// The file id of each node.
    pub node_ids: &'a [u64],
    /// The name of each node, or empty (COLMAP files then use the ids as names).
    pub node_names: &'a [String],
}

impl EstimateFile<'_> {
    /// The text of the file in `format` (resolved for `path` when `auto`).
    ///
    /// ```
    /// use rotavg::io::output::{EstimateFile, OutputFormat};
    /// use rotavg::multiple::{Edge, MultipleProblem};
    /// use rotavg::Rotation;
    /// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
    /// let rs = vec![Rotation::identity(); 2];
    /// let names = vec!["a.jpg".to_string(), "b.jpg".to_string()];
    /// let file = EstimateFile { problem: &p, rotations: &rs, node_ids: &[1, 2], node_names: &names };
    /// assert!(file.text("out/images.txt", OutputFormat::Auto)?.contains("\n2 1 0 0 0 0 0 0 1 b.jpg\n"));
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn text(&self, path: &str, format: OutputFormat) -> Result<String> {
        match format.for_path(path) {
            OutputFormat::Colmap => {
                crate::io::colmap::write_images_text(self.rotations, self.node_ids, self.node_names)
            }
            OutputFormat::G2o => Ok(crate::io::g2o::write_g2o(
                self.problem,
                Some(self.rotations),
            )),
            OutputFormat::Json | OutputFormat::Auto => {
                let mut s = serde_json::to_string(&EstimateWithIds {
                    node_ids: self.node_ids,
                    rotations: self.rotations,
                })
                .unwrap_or_default();
                s.push('\n');
                Ok(s)
            }
        }
    }

    /// Write [`Self::text`] to `path`; I/O errors name the path.
    pub fn write(&self, path: &str, format: OutputFormat) -> Result<()> {
        write_text(path, &self.text(path, format)?)
    }

    /// Write the estimate as `plan` says ([`prepare_output`]), keeping what `source` had:
    /// * g2o from a g2o file: the input's lines with each vertex's rotation replaced
    ///   ([`crate::io::g2o::write_g2o_like`]: translations, edges and other lines as read), the
    ///   estimate turned by the global rotation that best aligns it with the input's vertex
    ///   rotations (the same estimate: rotation averaging fixes rotations up to one global
    ///   rotation, and the kept translations are in the input's frame); from other inputs, the
    ///   problem's edges and the vertices with zero translations, under the file's node ids;
    /// * COLMAP: a sparse model (`images.txt`, `cameras.txt`, empty `points3D.txt`;
    ///   [`crate::io::colmap::write_sparse_model`]), with the cameras of a COLMAP database input,
    ///   else a documented placeholder camera; a lone images file when `plan` has no folder;
    /// * JSON: [`Self::text`].
    pub fn write_planned(&self, plan: &OutputPlan, source: &OutputSource<'_>) -> Result<()> {
        source.check(plan)?;
        let path = plan.file.display().to_string();
        match plan.format {
            OutputFormat::G2o if source.format == GraphFormat::G2o => {
                let estimate = self.aligned_to_vertices(source.input)?;
                let mut lines = crate::io::text::TextStream::open(source.input)?.into_lines();
                write_text(
                    &path,
                    &crate::io::g2o::write_g2o_like(&mut lines, &estimate)?,
                )
            }
            OutputFormat::G2o => write_text(
                &path,
                &crate::io::g2o::write_g2o_with_ids(
                    self.problem,
                    Some(self.rotations),
                    self.node_ids,
                ),
            ),
            OutputFormat::Colmap => match &plan.model_dir {
                Some(dir) => self.write_model(dir, &plan.file, source),
                None => write_text(&path, &self.text(&path, OutputFormat::Colmap)?),
            },
            OutputFormat::Json | OutputFormat::Auto => {
                write_text(&path, &self.text(&path, OutputFormat::Json)?)
            }
        }
    }

    /// The estimate by file id, turned by the global rotation `G` that best aligns it with the
    /// vertex rotations of the g2o file `input` (`G` minimises `sum ||R_k G - V_k||_F` over the
    /// nodes with a vertex; the identity when there are none).
    fn aligned_to_vertices(&self, input: &str) -> Result<BTreeMap<u64, Rotation>> {
        // the input's vertex rotations (none: no alignment), streamed
        let input_vertices = crate::io::g2o::read_g2o_vertices_lines(
            &mut crate::io::text::TextStream::open(input)?.into_lines(),
            &Default::default(),
        )
        .unwrap_or_default();
        let by_id: BTreeMap<u64, Rotation> =
            input_vertices.iter().map(|v| (v.id, v.rotation)).collect();
        let mut m = nalgebra::Matrix3::<f64>::zeros();
        for (k, r) in self.rotations.iter().enumerate() {
            if let Some(v) = self.node_ids.get(k).and_then(|id| by_id.get(id)) {
                m += r.matrix().transpose() * v.matrix();
            }
        }
        let g = if m == nalgebra::Matrix3::zeros() {
            Rotation::identity()
        } else {
            crate::so3::project_to_so3(&m).unwrap_or_else(Rotation::identity)
        };
        Ok(self
            .node_ids
            .iter()
            .zip(self.rotations)
            .map(|(&id, r)| (id, r * g))
            .collect())
    }

    /// A COLMAP sparse model in `dir` (images file `file`), with the cameras of the COLMAP
    /// database `source` reads, if any.
    fn write_model(&self, dir: &Path, file: &Path, source: &OutputSource<'_>) -> Result<()> {
        let database = (source.format == GraphFormat::Colmap)
            .then(|| crate::io::colmap::find_database(Path::new(source.input)))
            .flatten();
        let cameras = match database {
            Some(db) => {
                let (cameras, of_image) = crate::io::colmap::read_database_cameras(&db)?;
                let camera_ids: Vec<u32> = self
                    .node_ids
                    .iter()
                    .map(|id| of_image.get(id).copied().unwrap_or(1))
                    .collect();
                Some((cameras, camera_ids))
            }
            None => None,
        };
        crate::io::colmap::write_sparse_model(
            dir,
            file,
            self.rotations,
            self.node_ids,
            self.node_names,
            cameras
                .as_ref()
                .map(|(c, ids)| (c.as_slice(), ids.as_slice())),
        )
    }
}

/// The files of a multiple averaging besides its report (`rotavg multiple`'s `--output`,
/// `--inlier-output` and `--edges-output`): planned before the solve ([`Self::prepare`]:
/// folders created or refused, formats resolved) and written from its result
/// ([`Self::write`]).
#[derive(Debug, Clone, Default)]
pub struct MultipleOutputs {
    /// The estimate.
    pub estimate: Option<OutputPlan>,
    /// The inlier graph's refined estimate (robust losses).
    pub inlier_estimate: Option<OutputPlan>,
    /// The per-edge residuals (robust losses; [`edges_file_text`]).
    pub edges: Option<String>,
    /// The per-edge residuals' plan (its folder).
    pub edges_plan: Option<OutputPlan>,
}

impl MultipleOutputs {
    /// Plan the outputs ([`prepare_output`]; both estimates in `format`).
    pub fn prepare(
        estimate: Option<&str>,
        inlier_estimate: Option<&str>,
        edges: Option<&str>,
        format: OutputFormat,
    ) -> Result<Self> {
        let plan = |path: Option<&str>, format| path.map(|p| prepare_output(p, format)).transpose();
        Ok(MultipleOutputs {
            estimate: plan(estimate, format)?,
            inlier_estimate: plan(inlier_estimate, format)?,
            edges: edges.map(str::to_owned),
            edges_plan: plan(edges, OutputFormat::Json)?,
        })
    }

    /// Remove the folders the plans created that are still empty
    /// ([`OutputPlan::remove_empty_folders`]): after a failed run, or for outputs a run had
    /// nothing to write (`--loss auto` keeping least squares).
    pub fn remove_empty_folders(&self) {
        let plans = [&self.estimate, &self.inlier_estimate, &self.edges_plan];
        for plan in plans.into_iter().flatten() {
            plan.remove_empty_folders();
        }
    }

    /// An error, before the solve, for an estimate file `source` cannot give
    /// ([`OutputSource::check`]).
    pub fn check(&self, source: &OutputSource<'_>) -> Result<()> {
        for plan in self.estimate.iter().chain(&self.inlier_estimate) {
            source.check(plan)?;
        }
        Ok(())
    }

    /// Write the files from `result`, a solution of `graph`'s problem read from `source`
    /// ([`EstimateFile::write_planned`]); the path of the inlier graph's estimate when it was
    /// written (there is an inlier graph only when a robust estimate was certified).
    pub fn write(
        &self,
        graph: &LoadedGraph,
        result: &MultipleEstimate,
        source: &OutputSource<'_>,
    ) -> Result<Option<String>> {
        let file = |rotations| EstimateFile {
            problem: &graph.problem,
            rotations,
            node_ids: &graph.node_ids,
            node_names: &graph.node_names,
        };
        if let Some(plan) = &self.estimate {
            file(&result.solution.rotations).write_planned(plan, source)?;
        }
        if let (Some(path), Some(r)) = (&self.edges, &result.solution.residuals) {
            write_text(
                path,
                &edges_file_text(path, &graph.problem, r, &graph.node_ids),
            )?;
        }
        match (&self.inlier_estimate, &result.details.inlier_graph) {
            (Some(plan), Some(g)) => {
                file(&g.estimate).write_planned(plan, source)?;
                Ok(Some(plan.path.clone()))
            }
            _ => Ok(None),
        }
    }
}

#[derive(Serialize)]
struct EstimateWithIds<'a> {
    node_ids: &'a [u64],
    #[serde(with = "crate::so3::serde_rows::rotations")]
    rotations: &'a [Rotation],
}

/// The text of an estimate file for `path`: g2o ([`crate::io::g2o::write_g2o`]: the problem's
/// edges and the estimate as vertex lines) when `path` ends in `.g2o`, otherwise one JSON line
/// `{"node_ids": [...], "rotations": [R, ...]}` (`node_ids[k]` is the file id of node `k`).
/// (No names, no COLMAP: see [`EstimateFile`] for those.)
///
/// ```
/// use rotavg::io::output::estimate_file_text;
/// use rotavg::io::json::read_estimate;
/// use rotavg::io::detect::ReadOptions;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
/// let rs = vec![Rotation::identity(); 2];
/// let json = estimate_file_text("est.json", &p, &rs, &[10, 20]);
/// assert!(json.starts_with(r#"{"node_ids":[10,20],"rotations":"#));
/// assert!(read_estimate(&json, "est.json", &ReadOptions::default()).is_ok());
/// assert!(estimate_file_text("est.g2o", &p, &rs, &[10, 20]).starts_with("VERTEX_SE3:QUAT 0 "));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn estimate_file_text(
    path: &str,
    problem: &MultipleProblem,
    rotations: &[Rotation],
    node_ids: &[u64],
) -> String {
    if path.to_ascii_lowercase().ends_with(".g2o") {
        crate::io::g2o::write_g2o(problem, Some(rotations))
    } else {
        let mut s = serde_json::to_string(&EstimateWithIds {
            node_ids,
            rotations,
        })
        .unwrap_or_default();
        s.push('\n');
        s
    }
}

/// Write [`estimate_file_text`] to `path`; I/O errors name the path.
///
/// ```
/// use rotavg::io::output::write_estimate_file;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
/// let err = write_estimate_file("no/such/dir/est.json", &p, &[Rotation::identity(); 2], &[0, 1]);
/// assert!(err.unwrap_err().to_string().contains("no/such/dir/est.json"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_estimate_file(
    path: &str,
    problem: &MultipleProblem,
    rotations: &[Rotation],
    node_ids: &[u64],
) -> Result<()> {
    write_text(
        path,
        &estimate_file_text(path, problem, rotations, node_ids),
    )
}

/// Write `text` to the file at `path`; I/O errors name the path.
///
/// ```
/// let err = rotavg::io::output::write_text("no/such/dir/x.txt", "x").unwrap_err();
/// assert!(matches!(err, rotavg::Error::Io { .. }));
/// ```
pub fn write_text(path: &str, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::Io {
        path: path.into(),
        message: e.to_string(),
    })
}

#[derive(Serialize)]
struct EdgeRow {
    i: u64,
    j: u64,
    residual_deg: f64,
    weight: f64,
    inlier: bool,
}

#[derive(Serialize)]
struct EdgesJson {
    inlier_threshold_deg: f64,
    edges: Vec<EdgeRow>,
}

/// The text of a per-edge residual file (`rotavg multiple --edges-output FILE`), one row per
/// edge in the input's edge order, nodes named by their file ids (`node_ids[k]` names node `k`):
/// JSON `{"inlier_threshold_deg": t, "edges": [{"i", "j", "residual_deg", "weight",
/// "inlier"}, ...]}` when `path` ends in `.json`, otherwise CSV with the header
/// `i,j,residual_deg,weight,inlier` (`inlier` 1 or 0). `residual_deg`: the residual angle at the
/// estimate; `weight`: the final IRLS weight relative to the edge's own weight, in `(0, 1]`;
/// `inlier`: `residual_deg <= inlier_threshold_deg` ([`EdgeResiduals`]).
///
/// ```
/// use rotavg::io::output::edges_file_text;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::multiple::robust::edge_residuals;
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::so3::exp;
/// use rotavg::{Metric, Rotation};
/// let turn = exp(&nalgebra::Vector3::new(0.0, 0.0, 10f64.to_radians()));
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: turn, weight: 1.0 }])?
///     .with_objective(Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 5.0 }))?;
/// let r = edge_residuals(&p, &[Rotation::identity(); 2], 5.0);
/// let csv = edges_file_text("edges.csv", &p, &r, &[7, 9]);
/// assert_eq!(csv.lines().next(), Some("i,j,residual_deg,weight,inlier"));
/// let row: Vec<f64> = csv.lines().nth(1).unwrap().split(',').map(|x| x.parse().unwrap()).collect();
/// assert_eq!((row[0], row[1], row[4]), (7.0, 9.0, 0.0)); // file ids; an outlier
/// assert!((row[2] - 10.0).abs() < 1e-9 && (row[3] - 0.5).abs() < 1e-9); // Huber weight c / theta
/// let json = edges_file_text("edges.json", &p, &r, &[7, 9]);
/// assert!(json.contains(r#""i":7,"j":9"#) && json.contains(r#""inlier":false"#));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn edges_file_text(
    path: &str,
    problem: &MultipleProblem,
    residuals: &EdgeResiduals,
    node_ids: &[u64],
) -> String {
    let id = |k: usize| node_ids.get(k).copied().unwrap_or(k as u64);
    let rows = problem
        .edges()
        .iter()
        .zip(&residuals.residual_deg)
        .zip(&residuals.weight)
        .zip(&residuals.inlier)
        .map(|(((e, &residual_deg), &weight), &inlier)| EdgeRow {
            i: id(e.i),
            j: id(e.j),
            residual_deg,
            weight,
            inlier,
        });
    if path.to_ascii_lowercase().ends_with(".json") {
        let mut s = serde_json::to_string(&EdgesJson {
            inlier_threshold_deg: residuals.summary.inlier_threshold_deg,
            edges: rows.collect(),
        })
        .unwrap_or_default();
        s.push('\n');
        s
    } else {
        let mut s = String::from("i,j,residual_deg,weight,inlier\n");
        for r in rows {
            s.push_str(&format!(
                "{},{},{},{},{}\n",
                r.i,
                r.j,
                r.residual_deg,
                r.weight,
                u8::from(r.inlier)
            ));
        }
        s
    }
}
