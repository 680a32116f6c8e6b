//! The option groups the verbs share (contract section 5, "Common options"), each flattened into the
//! verbs that take it; the parser of the library's named choices; printing a report.

use crate::Outcome;
use clap::Args;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use rotavg::certify::{Budget, CertifyMode, CertifySettings, DualSettings};
use rotavg::io::detect::{GraphFormat, LoadedGraph, ReadOptions, WeightSource};
use rotavg::io::names::Choice;
use rotavg::io::rig::LoadedRig;
use rotavg::io::values::{parse_bytes, parse_seconds, parse_tolerance, parse_vector};
use rotavg::multiple::gravity::GravityPriors;
use rotavg::warning::Warning;
use rotavg::{Result, Rotation};
use serde::Serialize;
use std::fmt::Display;

/// The options of every problem verb (`single`, `multiple`, `conjugate`, `certify`).
#[derive(Args, Debug)]
pub struct Common {
    /// Weights from the file (`file`, default) or all 1 (`unit`).
    #[arg(long, value_parser = choice(WeightSource::choices()), default_value_t = WeightSource::File)]
    pub weights: WeightSource,
    /// Exit with status 3 unless the verdict is `certified`.
    #[arg(long)]
    pub require_certified: bool,
    /// Print nothing on stdout/stderr except errors and `--json` output.
    #[arg(long)]
    pub quiet: bool,
    /// Print one JSON object on stdout (docs/reference/contract.md, section 5) instead of the
    /// readable summary.
    #[arg(long)]
    pub json: bool,
    /// Print the proof's details: every rung of the proof ladder that ran, the tolerance rule,
    /// the whole explanation with the labels of paper-notes/ (e.g. [D15]), long lines unbroken.
    #[arg(long, short = 'v')]
    pub verbose: bool,
    /// Time budget, seconds (`none`: no limit). One clock for the local solve (stopped at it:
    /// `time_limit`, its last iterate) and the certificate (what is left). A
    /// proof step predicted or found to exceed it is not started; the verdict is then
    /// `inconclusive` with the reason.
    #[arg(long, value_name = "SECONDS", default_value = "600", value_parser = parse_seconds)]
    pub max_seconds: f64,
}

impl Common {
    /// The readers' options.
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            weights: self.weights,
            ..Default::default()
        }
    }

    /// The local solve's time limit: `--max-seconds` (`None` for `none`). The certificate gets
    /// what the solve leaves of it (one clock).
    pub fn solve_seconds(&self) -> Option<f64> {
        Some(self.max_seconds).filter(|t| t.is_finite())
    }

    /// The certificate's budget: `--max-seconds` and `max_memory_bytes`.
    fn budget(&self, max_memory_bytes: u64) -> Budget {
        Budget {
            max_memory_bytes,
            max_seconds: self.solve_seconds(),
        }
    }

    /// The certificate's settings in `mode` with the time budget.
    pub fn settings(&self, mode: CertifyMode) -> CertifySettings {
        let budget = self.budget(Budget::default().max_memory_bytes);
        CertifySettings {
            budget,
            ..CertifySettings::with_mode(mode)
        }
    }

    /// Print `report` ([`print`]) and return its verdict.
    pub fn finish<R: Serialize + Display>(&self, report: &R, verdict: Outcome) -> Result<Outcome> {
        print(report, self.json, self.quiet, self.verbose)?;
        Ok(verdict)
    }

    /// Print `rotavg: warning: TEXT` on stderr (in lines of [`TEXT_WIDTH`]) unless `--quiet`.
    pub fn warn(&self, text: &str) {
        if !self.quiet {
            let warning = format!("rotavg: warning: {text}");
            eprintln!("{}", rotavg::report::wrap_lines(&warning, TEXT_WIDTH));
        }
    }
}

/// `--output` of `single` and `conjugate`: the estimate as JSON `{"rotation": R}`.
#[derive(Args, Debug)]
pub struct RotationOutputArgs {
    /// Write the estimate as JSON `{"rotation": R}` (what `--init` and `rotavg certify
    /// --estimate` read); its folder is created before the solve.
    #[arg(long, value_name = "FILE")]
    pub output: Option<String>,
}

impl RotationOutputArgs {
    /// Run `work` (read, solve, certify) and write the estimate `estimate(&result)` to
    /// `--output` when given: its folder is created before `work`, and removed again (when
    /// empty) if `work` or the writing fails.
    pub fn around<R>(
        &self,
        work: impl FnOnce() -> Result<R>,
        estimate: impl FnOnce(&R) -> Rotation,
    ) -> Result<R> {
        use rotavg::io::output::{OutputFormat, prepare_output};
        let plan = match &self.output {
            Some(path) => Some(prepare_output(path, OutputFormat::Json)?),
            None => None,
        };
        let result = work();
        let Some(plan) = &plan else {
            return result;
        };
        match result {
            Ok(r) => {
                plan.write_text(&rotavg::io::json::write_rotation_json(&estimate(&r)))?;
                Ok(r)
            }
            Err(e) => {
                plan.remove_empty_folders();
                Err(e)
            }
        }
    }
}

/// `--init` (`single`, `multiple`, `conjugate`).
#[derive(Args, Debug)]
pub struct InitArgs {
    /// Start the local solver from this estimate (JSON; `multiple`: every estimate format of
    /// `rotavg certify --estimate`, matched by id or image name).
    #[arg(long, value_name = "FILE")]
    pub init: Option<String>,
}

impl InitArgs {
    /// The rotation of a single or conjugate problem's `--init` file, if given.
    pub fn rotation(&self, options: &ReadOptions) -> Result<Option<Rotation>> {
        let init = self.init.as_ref();
        init.map(|p| rotavg::io::input::load_estimate(p, options)?.into_rotation())
            .transpose()
    }
}

/// `--gravity` (`multiple`, `certify`, `rig FILE`): gravity priors, held as constraints or (with
/// `--gravity-weight`) as soft terms.
#[derive(Args, Debug)]
pub struct GravityArgs {
    /// Gravity priors, held as hard constraints (or soft terms: `--gravity-weight`): per image
    /// `g_i`, the world's down direction in
    /// the camera's frame (`R_i world_down = g_i`; docs/guides/gravity.md). JSON `{"gravity":
    /// [g | null, ...]}` in node order (or an object keyed by image name or file id), text lines
    /// `KEY gx gy gz`, or a COLMAP database's `pose_priors.gravity`; a fourth number after `g`
    /// is that prior's relative weight (soft priors weigh `W` times it).
    #[arg(long, value_name = "FILE")]
    pub gravity: Option<String>,
    /// The world's down direction the priors refer to, `X,Y,Z` (default: the file's; else
    /// `0,0,1`; COLMAP databases `0,1,0`).
    #[arg(long, value_name = "X,Y,Z", requires = "gravity", value_parser = parse_vector)]
    pub world_down: Option<[f64; 3]>,
    /// The priors as soft terms of this weight instead of constraints: each adds
    /// `2 W ||R_i world_down - g_i||^2` to the chordal cost, like an edge of weight `W` for a
    /// tilt error (`W = 1 / sigma^2` for priors of `sigma` radians per axis on edges weighted
    /// `1 / sigma_ij^2`); certified with the view graph by the multiple-averaging ladder.
    #[arg(
        long,
        value_name = "W",
        requires = "gravity",
        allow_negative_numbers = true
    )]
    pub gravity_weight: Option<f64>,
}

impl GravityArgs {
    /// The priors of `--gravity` for `graph`, with the warning for entries no node matches.
    pub fn read(&self, graph: &LoadedGraph) -> Result<Option<(GravityPriors, Vec<Warning>)>> {
        let Some(path) = &self.gravity else {
            return Ok(None);
        };
        let read = rotavg::io::gravity::read_gravity(path, graph, self.world_down)?;
        read.priors_and_warnings(path, self.gravity_weight)
            .map(Some)
    }

    /// `rig` with the priors of `--gravity` on its images (`rotavg rig FILE`, `certify
    /// --rig`; `[G14]`).
    pub fn apply_to_rig(&self, rig: LoadedRig) -> Result<LoadedRig> {
        let Some(path) = &self.gravity else {
            return Ok(rig);
        };
        let read = rotavg::io::gravity::read_rig_gravity(path, &rig, self.world_down)?;
        let (priors, warnings) = read.priors_and_warnings(path, self.gravity_weight)?;
        rig.with_gravity(priors, warnings)
    }
}

/// The options of view graphs (`multiple`, `certify`): how one is read and certified.
#[derive(Args, Debug)]
pub struct GraphArgs {
    /// Input format (view graphs).
    #[arg(long, value_parser = choice(GraphFormat::choices()), default_value_t = GraphFormat::Auto)]
    pub format: GraphFormat,
    /// Tolerance on ||R^T R - I||_F and |det R - 1| of every matrix a view graph, an estimate,
    /// `--init` or `--ground-truth` gives as a rotation; beyond it, an error naming the file
    /// and line.
    #[arg(long, value_name = "TOL", default_value_t = rotavg::so3::DEFAULT_ROTATION_TOLERANCE, value_parser = parse_tolerance)]
    pub rotation_tolerance: f64,
    /// g2o / TORO edges with an information matrix: SE-Sync's scalar `kappa` (`auto`, `kappa`)
    /// or their full 3x3 rotation information, which makes the problem anisotropic (`full`;
    /// docs/guides/anisotropic.md). COLMAP databases: each pair's rotation information from
    /// its inlier correspondences and cameras (`full`; `auto` too where the database gives it,
    /// else weights 1 with the warning `database_without_information`; rigs: weights 1), or
    /// weights 1 (`kappa`).
    #[arg(long, value_name = "auto|kappa|full", default_value = "auto", value_parser = ["auto", "kappa", "full"])]
    pub information: String,
    /// Certification (`rotavg certify`: of view graphs; `none` there is `dual`).
    #[arg(long, value_parser = choice(graph_certify_modes()), default_value_t = CertifyMode::Auto)]
    pub certify: CertifyMode,
    /// Memory budget of one factorisation of the certificate: bytes, or with a suffix K, M, G,
    /// T (powers of 1024), e.g. `8G`. A proof whose factor would not fit is not started.
    #[arg(long, value_name = "SIZE", default_value = "4G", value_parser = parse_bytes)]
    pub max_memory: u64,
    /// Seed of the randomized Chebyshev test [D16] (run when no proof fits the budget; its
    /// Monte Carlo bound is reported beside the `inconclusive` verdict). Default: a fresh seed
    /// per run, printed with the result.
    #[arg(long, value_name = "N")]
    pub randomized_seed: Option<u64>,
    /// Do not run the randomized Chebyshev test [D16] (nor the Lanczos estimate it starts
    /// from).
    #[arg(long, conflicts_with = "randomized_seed")]
    pub no_randomized: bool,
}

/// The certify modes of view graphs.
fn graph_certify_modes() -> Vec<CertifyMode> {
    use CertifyMode::*;
    vec![Auto, Dual, Sdp, Staircase, None]
}

impl GraphArgs {
    /// The readers' options.
    pub fn read_options(&self, common: &Common) -> ReadOptions {
        ReadOptions {
            full_information: rotavg::io::detect::information_choice(&self.information)
                .unwrap_or_default(), // clap's value parser allows only the three names
            rotation_tolerance: self.rotation_tolerance,
            ..common.read_options()
        }
    }

    /// The certificate's settings with the budgets; with `--plot`, the smallest eigenvalues of
    /// the certificate matrix for the figure.
    pub fn settings(&self, common: &Common, plot: &PlotArgs) -> CertifySettings {
        let mut dual = DualSettings::default();
        dual.randomized.seed = self.randomized_seed;
        dual.randomized.enabled = !self.no_randomized;
        CertifySettings {
            mode: self.certify,
            spectrum: plot.plot.as_ref().map(|_| Default::default()),
            budget: common.budget(self.max_memory),
            dual,
            ..Default::default()
        }
    }
}

impl GraphArgs {
    /// [`Self::settings`] for `rotavg certify`, where `--certify none` is the dual certificate.
    pub fn certify_settings(&self, common: &Common, plot: &PlotArgs) -> CertifySettings {
        let mut settings = self.settings(common, plot);
        if settings.mode == CertifyMode::None {
            settings.mode = CertifyMode::Dual;
        }
        settings
    }
}

/// `--plot` (`multiple`, `conjugate`, `certify`).
#[derive(Args, Debug, Default)]
pub struct PlotArgs {
    /// Write an SVG figure: histogram of the residual angles (degrees), the certificate, and
    /// the smallest eigenvalues of the certificate matrix (estimates) with the proven bound.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
}

impl PlotArgs {
    /// `--plot` needs the `plot` feature (on by default): without it, fail before any work.
    pub fn check(&self) -> Result<()> {
        match &self.plot {
            Some(_) if !cfg!(feature = "plot") => Err(rotavg::report::certify::no_plot_feature()),
            _ => Ok(()),
        }
    }
}

pub use rotavg::report::TEXT_WIDTH;

/// Print a report ([`rotavg::report::render`]): its JSON when `json`, else unless `quiet` its
/// text.
pub fn print<R: Serialize + Display>(
    report: &R,
    json: bool,
    quiet: bool,
    verbose: bool,
) -> Result<()> {
    crate::progress::finish();
    if json || !quiet {
        println!("{}", rotavg::report::render(report, json, verbose)?);
    }
    Ok(())
}

/// A parser of the named values `values` of a library choice (help lists their names and
/// descriptions; other names are a usage error).
pub fn choice<T: Choice>(values: Vec<T>) -> impl TypedValueParser<Value = T> {
    let possible: Vec<PossibleValue> = values
        .iter()
        .map(|v| PossibleValue::new(v.name()).help(v.help()))
        .collect();
    PossibleValuesParser::new(possible)
        .try_map(|name| T::from_name(&name).ok_or_else(|| format!("unknown value `{name}`")))
}
