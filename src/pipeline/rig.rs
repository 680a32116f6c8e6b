//! A rig of any number of sensors solved and certified (`paper-notes/conjugate.md` `[H19]`):
//! [`solve_rig`], then [`certify_rig`].

use super::loss_choice::JUDGE_AT_ITERATIONS;
use super::{AverageSettings, Averaged, PipelineProblem, PipelineSolution, average};
use crate::certify::{Certification, CertifyMode, CertifySettings, certify_rig};
use crate::error::Result;
use crate::multiple::robust::{OutlierWarning, judges_residuals, suspected_outliers};
use crate::multiple::robust_scale::{DataScale, ScaleRule};
use crate::rig::{RigProblem, RigRobust, RigSettings, RigSolution, solve_rig};
use crate::rig::{solve_rig_judged, solve_rig_robust_given};
use crate::so3::Rotation;
use crate::termination::SolverReport;
use serde::{Deserialize, Serialize};

/// Settings of [`average_rig`].
pub type AverageRigSettings = AverageSettings<RigSettings>;

/// Solve a rig ([`solve_rig`]) and certify the estimate ([`certify_rig`]): with every sensor
/// held, by the frames' view graph; otherwise by the images' view graph without the rig's
/// constraints, tight on noise-free rigs and a stated gap on noisy ones.
///
/// ```
/// use rotavg::pipeline::average_rig;
/// use rotavg::rig::RigScene;
/// let (p, truth) = RigScene { frames: 40, sensors: 4, noise_sigma: 0.01, known: true, ..Default::default() }.generate();
/// let out = average_rig(&p, &Default::default())?;
/// assert!(out.certificate.unwrap().is_certified()); // every sensor known: the frames' graph
/// assert!(rotavg::so3::angle_between(&out.solution.sensors[3], &truth.sensors[3]) < 1e-12);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_rig(
    problem: &RigProblem,
    settings: &AverageRigSettings,
) -> Result<Averaged<RigSolution>> {
    average(problem, settings)
}

impl PipelineSolution for RigSolution {
    fn certified_cost(&self) -> f64 {
        self.cost
    }
    fn report_mut(&mut self) -> &mut SolverReport {
        &mut self.report
    }
}

impl PipelineProblem for RigProblem {
    type Settings = RigSettings;
    type Solution = RigSolution;
    const NAME: &'static str = "rig";
    const MODES: &'static [CertifyMode] =
        &[CertifyMode::Auto, CertifyMode::Dual, CertifyMode::None];
    fn validate(settings: &RigSettings) -> Result<()> {
        settings.validate()
    }
    fn uncertifiable(&self, _mode: CertifyMode) -> Option<String> {
        None
    }
    fn solve(&self, settings: &RigSettings) -> Result<RigSolution> {
        solve_rig(self, settings)
    }
    fn certify(
        &self,
        solution: &RigSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<RigSolution>> {
        certify_rig(self, &solution.frames, &solution.sensors, settings)
    }
}

/// The loss of a rig's solve (`rotavg rig FILE --loss`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RigLoss {
    /// Least squares on every edge ([`average_rig`]).
    Chordal,
    /// The Cauchy loss, then the inlier problem certified ([`crate::rig::solve_rig_robust`], `[H20]`).
    Cauchy,
    /// Least squares, and the Cauchy loss instead when its residuals look like outliers
    /// ([`suspected_outliers`] on the images' view graph, the rule of view graphs).
    #[default]
    Auto,
}

impl RigLoss {
    /// The loss named `name` (`auto`, `chordal` or `cauchy`) with the Cauchy scale and the
    /// inlier threshold both `threshold_deg` when given (`rotavg rig --loss --loss-threshold`,
    /// Python's `loss=`, `loss_threshold=`); not given, both from the data for `auto`
    /// ([`crate::rig::rig_data_scale`], `[H20]` "The scale") and 5 degrees for `cauchy`, the
    /// rule of view graphs ([`ScaleRule::of`]). Errors: another name (the thresholds are
    /// checked by the solve).
    ///
    /// ```
    /// use rotavg::multiple::robust_scale::ScaleRule;
    /// use rotavg::pipeline::rig::RigLoss;
    /// assert_eq!(RigLoss::named("auto", None)?.1.scale, ScaleRule::FromData);
    /// assert_eq!(RigLoss::named("cauchy", None)?.1.scale, ScaleRule::Given);
    /// assert_eq!(RigLoss::named("auto", Some(2.0))?.1.threshold_deg, 2.0);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn named(name: &str, threshold_deg: Option<f64>) -> Result<(RigLoss, RigRobust)> {
        let loss = match name {
            "auto" => RigLoss::Auto,
            "chordal" => RigLoss::Chordal,
            "cauchy" => RigLoss::Cauchy,
            other => {
                return Err(crate::Error::InvalidSettings {
                    name: "loss".into(),
                    reason: format!(
                        "loss must be \"auto\", \"chordal\" or \"cauchy\", got {other:?}"
                    ),
                });
            }
        };
        let (threshold_deg, rule) = ScaleRule::of(threshold_deg);
        let robust = RigRobust {
            threshold_deg,
            inlier_threshold_deg: threshold_deg,
            scale: match loss {
                RigLoss::Auto => rule,
                _ => ScaleRule::Given,
            },
            ..Default::default()
        };
        Ok((loss, robust))
    }

    /// This loss for a two-sensor rig whose other `sensor_from_rig` is `held` (`rotavg rig
    /// --sensor-from-rig`, Python's `sensor_from_rig=`): the frames are then averaged on one
    /// view graph by least squares (`auto` is `chordal`), so `cauchy` (which estimates the
    /// sensor) is an error.
    pub fn with_sensor_held(self, held: bool) -> Result<Self> {
        if held && self == RigLoss::Auto {
            return Ok(RigLoss::Chordal);
        }
        if held && self == RigLoss::Cauchy {
            return Err(crate::Error::InvalidSettings {
                name: "loss".into(),
                reason: "a rig with its sensor_from_rig held is solved by least squares (on \
                         one view graph); the Cauchy loss estimates the sensor"
                    .into(),
            });
        }
        Ok(self)
    }
}

/// What a robust rig solve did: the loss that ran, why, and the inlier problem certified.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigRobustDetails {
    /// The loss asked for.
    pub requested: RigLoss,
    /// `true` when the Cauchy loss ran (asked for, or chosen by `auto`).
    pub robust: bool,
    /// The outlier diagnosis of the least-squares estimate (`auto`), when it fired.
    pub outliers: Option<crate::multiple::robust::OutlierWarning>,
    /// Reweighted alternations of the Cauchy solve.
    pub reweights: usize,
    /// Inlier edges (residual at the robust estimate within the inlier threshold), of all.
    pub inlier_edges: usize,
    /// Edges in all.
    pub total_edges: usize,
    /// The inlier threshold, degrees.
    pub inlier_threshold_deg: f64,
    /// The Cauchy scale, degrees (0 in records written before it existed).
    #[serde(default)]
    pub scale_deg: f64,
    /// When the scale and inlier threshold came from the data ([`ScaleRule::FromData`]): how
    /// ([`crate::rig::rig_data_scale`]); `None`: as given.
    #[serde(default)]
    pub data_scale: Option<DataScale>,
}

impl RigRobustDetails {
    /// What the robust solve did, in words (the text reports of `rotavg rig`); `anisotropic`:
    /// the rig has information matrices (its alternations ran on unit weights, its inliers are
    /// judged by their Mahalanobis angles).
    pub fn summary(&self, anisotropic: bool) -> String {
        let mut s = format!(
            "Cauchy loss ({} reweighted alternations{}): {} of {} edges inliers ({} <= {} deg); \
             the estimate and certificate are the inlier problem's",
            self.reweights,
            if anisotropic { " on unit weights" } else { "" },
            self.inlier_edges,
            self.total_edges,
            if anisotropic {
                "Mahalanobis angle"
            } else {
                "residual"
            },
            self.inlier_threshold_deg
        );
        if let Some(d) = &self.data_scale {
            s += &format!(
                "; its scale {} deg from the data: {} (`--loss-threshold` sets both), its inlier \
                 threshold {}",
                d.scale_deg,
                d.scale_words(&format!(
                    "the Cauchy estimate after {} reweightings at 5 deg",
                    d.iterations
                )),
                d.threshold_words()
            );
        }
        s
    }
}

/// A rig solved with `loss` (`rotavg rig FILE`): least squares ([`average_rig`]); or the Cauchy
/// loss, the inlier problem's chordal L2 estimate returned and certified (`[H20]`); `auto` runs
/// least squares and turns robust when [`suspected_outliers`] fires on the images' view graph at
/// its estimate. The diagnosis of a least-squares estimate is in `details.outliers` (as
/// `average_multiple`'s). Returns the result, the problem certified (`problem` itself, or its inlier
/// rig) and, for a robust solve or an `auto` choice, what was done.
pub fn average_rig_with_loss(
    problem: &RigProblem,
    loss: RigLoss,
    robust: &RigRobust,
    settings: &AverageRigSettings,
) -> Result<RigRun> {
    let start = std::time::Instant::now();
    let skip = super::validate(problem, settings)?;
    let (mut outliers, mut least_squares) = (None, None);
    if loss != RigLoss::Cauchy {
        let (ls, diagnosis) = judged_least_squares(problem, loss, &settings.solve)?;
        outliers = diagnosis.map(|mut w| {
            w.suggestion = if loss == RigLoss::Chordal {
                "`--loss cauchy` (or the default `--loss auto`) solves it and certifies the \
                 chordal L2 problem on the inlier edges"
            } else {
                "so the Cauchy loss ran instead (`--loss auto`; `--loss chordal` keeps least \
                 squares)"
            }
            .into();
            w
        });
        if loss == RigLoss::Chordal || outliers.is_none() {
            let mut out = super::certify_solved(problem, ls, settings, skip, start)?;
            out.details.outliers = outliers;
            return Ok((out, problem.clone(), None));
        }
        least_squares = Some(ls);
    }
    let rest = settings.remaining(start);
    let (mut out, inliers, details) =
        robust_from(problem, least_squares, (loss, outliers), robust, &rest)?;
    out.details
        .add_solve_seconds(start.elapsed().as_secs_f64() - out.details.total_seconds);
    Ok((out, inliers, Some(details)))
}

/// The rig's least squares for [`average_rig_with_loss`] and the outlier diagnosis at it
/// ([`suspected_outliers`] on the images' view graph). Under `auto` on a rig with information
/// whose images' residuals can be judged, the solve is judged at the view graphs'
/// [`JUDGE_AT_ITERATIONS`] (`paper-notes/conjugate.md` `[H20]` "Judged least squares"): an
/// estimate whose residuals already show outliers there is returned as it is, with the
/// diagnosis that judged it, since the robust stage of a rig with information starts from unit
/// weights and only the diagnosis reads it. Rigs without information keep the whole solve: it
/// is their robust stage's start.
fn judged_least_squares(
    problem: &RigProblem,
    loss: RigLoss,
    settings: &RigSettings,
) -> Result<(RigSolution, Option<OutlierWarning>)> {
    let graph = problem.image_graph()?;
    let diagnose = |frames: &[Rotation], sensors: &[Rotation]| {
        suspected_outliers(&graph, &problem.image_rotations(frames, sensors))
    };
    if loss != RigLoss::Auto || !problem.is_anisotropic() || !judges_residuals(&graph) {
        let ls = solve_rig(problem, settings)?;
        let diagnosis = diagnose(&ls.frames, &ls.sensors);
        return Ok((ls, diagnosis));
    }
    let mut judged_by = None;
    let mut judge = |frames: &[Rotation], sensors: &[Rotation]| {
        judged_by = diagnose(frames, sensors);
        judged_by.is_some()
    };
    let (ls, judged) = solve_rig_judged(problem, settings, &JUDGE_AT_ITERATIONS, &mut judge)?;
    let diagnosis = match judged {
        true => judged_by,
        false => diagnose(&ls.frames, &ls.sensors),
    };
    Ok((ls, diagnosis))
}

/// The calibration a rig with gravity priors and sensors to estimate runs first (`[G14]`): the
/// rig without the priors solved and certified as [`average_rig_with_loss`] does, its sensors
/// then held.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigCalibration {
    /// The sensors that were estimated (indices).
    pub estimated: Vec<usize>,
    /// Every sensor's `sensor_from_rig` as calibrated (the held ones as held).
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub sensors_from_rig: Vec<crate::so3::Rotation>,
    /// The calibration's cost (its problem's: the rig's, or its inlier rig's).
    pub cost: f64,
    /// Its certificate, about the rig without the priors.
    pub certificate: Option<crate::certify::Certificate>,
    /// A robust calibration's loss and inliers.
    pub robust: Option<RigRobustDetails>,
    /// With soft priors (`--gravity-weight`), the sensors refined by them (`[G15]`): every
    /// sensor's `sensor_from_rig` at the joint estimate of the calibrated problem with its
    /// priors, the one the second run holds; `None` with held priors (the sensors stay at the
    /// calibration) or when the refinement failed.
    #[serde(default, with = "crate::so3::serde_rows::option_rotations")]
    pub refined_sensors_from_rig: Option<Vec<crate::so3::Rotation>>,
    /// The refinement's solve (passes, why it stopped, seconds), when it ran.
    #[serde(default)]
    pub refinement: Option<crate::termination::SolverReport>,
    /// Why the refinement by soft priors failed, when it did (the calibration is then held;
    /// the warning `gravity_refinement_failed`).
    #[serde(default)]
    pub refinement_failed: Option<String>,
}

/// A rig with gravity `priors` whose sensors are (some of them) estimated (`[G14]`): calibrated
/// without the priors ([`average_rig_with_loss`]), then solved and certified with every sensor
/// held at the calibration and the priors on its images. Soft priors first refine the sensors
/// (`[G15]`), and, when the calibration was certified, the estimate is then also certified for
/// the joint problem with the sensors free (`[G16]`,
/// [`PipelineDetails::rig_joint`](crate::pipeline::PipelineDetails::rig_joint); the run's
/// certificate when it is certified). Returns the second run (with the problem it certifies
/// and its robust details) and the calibration. Errors: those of [`average_rig_with_loss`] and
/// [`RigProblem::with_gravity`].
pub fn average_rig_calibrated_with_gravity(
    problem: &RigProblem,
    priors: crate::multiple::gravity::GravityPriors,
    (loss, robust): (RigLoss, &RigRobust),
    settings: &AverageRigSettings,
) -> Result<(RigRun, RigCalibration)> {
    let start = std::time::Instant::now();
    let (first, calibrated, first_robust) = average_rig_with_loss(problem, loss, robust, settings)?;
    let refining = std::time::Instant::now();
    let refined = refine_sensors(
        &calibrated,
        &first.solution,
        &priors,
        &settings.remaining(start),
    );
    let refine_seconds = refining.elapsed().as_secs_f64();
    let calibration = RigCalibration {
        estimated: problem.estimated_sensors(),
        sensors_from_rig: first.solution.sensors.clone(),
        cost: first.solution.cost,
        certificate: first.certificate,
        robust: first_robust,
        refined_sensors_from_rig: refined
            .as_ref()
            .and_then(|r| r.as_ref().ok())
            .map(|r| r.sensors.clone()),
        refinement_failed: refined
            .as_ref()
            .and_then(|r| r.as_ref().err())
            .map(|e| e.to_string()),
        refinement: refined.and_then(Result::ok).map(|r| r.report),
    };
    let sensors =
        (calibration.refined_sensors_from_rig.as_ref()).unwrap_or(&calibration.sensors_from_rig);
    let held = problem.with_sensors_held(sensors)?.with_gravity(priors)?;
    let (mut out, certified, robust) =
        average_rig_with_loss(&held, loss, robust, &settings.remaining(start))?;
    // the calibration's solve and certificate, and the refinement by the priors, are the run's
    // (the refinement was left out of the times until 2026-12-02: 5.7 s of a 16.6 s run)
    let first_certify = first.details.certify_seconds;
    out.details
        .add_solve_seconds(first.details.total_seconds - first_certify + refine_seconds);
    out.details.add_certify_seconds(first_certify);
    // the joint problem adds the priors to the calibrated one: tried where that one's
    // certificate proved and the couplings of [H21] can work; not on a rig of the two-graph
    // shape [H22], whose joint bound they leave 77-82 % below (100-1000 frames) or cannot
    // compute (10^4 frames: 31 s of the 41 s run, inconclusive; [G16] "Two view graphs")
    if calibration
        .certificate
        .as_ref()
        .is_some_and(|c| c.is_certified())
        && !crate::certify::rig::is_two_graphs(problem)
    {
        out.details.rig_joint =
            certify_jointly(problem, &certified, &mut out, &settings.remaining(start))?;
    }
    Ok(((out, certified, robust), calibration))
}

/// The joint certificate of `[G16]` at `out`'s estimate: `certified` (the held rig with soft
/// priors, or its inlier rig) with `problem`'s sensors estimated again; it becomes `out`'s
/// certificate when it is certified. `None` with held priors or when `out` has no certificate.
fn certify_jointly(
    problem: &RigProblem,
    certified: &RigProblem,
    out: &mut Averaged<RigSolution>,
    settings: &AverageRigSettings,
) -> Result<Option<crate::certify::Certificate>> {
    let Some(priors) = certified.gravity().filter(|g| g.weight().is_some()) else {
        return Ok(None);
    };
    if out.certificate.is_none() {
        return Ok(None);
    }
    let joint = (problem.with_edges(certified.edges().to_vec())?).with_gravity(priors.clone())?;
    let s = &out.solution;
    // only a certificate serves here: no images' bound (`[H19]` item 2) whose gap the run drops
    let c = crate::certify::rig::certify_rig_without_images_bound(
        &joint,
        &s.frames,
        &s.sensors,
        &settings.certify,
    )?;
    out.details.add_certify_seconds(c.details.seconds);
    let mut certificate = c.certificate;
    if let Some(better) = c.improvement {
        // the coupled bound's polish reached a lower joint cost, which the bound covers: the
        // estimate when that certifies it
        let improved = certificate.with_upper_bound(better.cost);
        if improved.is_certified() {
            out.details.improved_by = c.details.improvement.map(|i| i.source);
            out.solution = out.solution.clone().adopt(better);
            certificate = improved;
        }
    }
    if certificate.is_certified() {
        out.certificate = Some(certificate.clone());
    }
    Ok(Some(certificate))
}

/// Alternation passes of the refinement by soft priors at most (`[G15]`): on generated rigs
/// (1000 frames and 4 sensors, 10^4 frames and 6 sensors) the sensors after 4 passes were as
/// accurate as after convergence (11 passes, 15 s at 10^4 frames and 6 sensors, against 5.4 s):
/// the passes after them move the sensors by less than their error.
pub const REFINE_MAX_PASSES: usize = 4;

/// The joint solve that refines the sensors by soft `priors` (`[G15]`): the calibrated problem
/// (the rig, or its inlier rig) with the priors, from the calibration; `None` with held priors,
/// its error when it fails (the calibration is then held, as before, and the report warns).
fn refine_sensors(
    calibrated: &RigProblem,
    calibration: &RigSolution,
    priors: &crate::multiple::gravity::GravityPriors,
    settings: &AverageRigSettings,
) -> Option<Result<RigSolution>> {
    priors.weight()?;
    let (frames, sensors) = (&calibration.frames, &calibration.sensors);
    let solve = crate::rig::RigSettings {
        max_passes: settings.solve.max_passes.min(REFINE_MAX_PASSES),
        ..settings.solve
    };
    Some(
        (calibrated.clone().with_gravity(priors.clone()))
            .and_then(|joint| crate::rig::solve_rig_from(&joint, frames, sensors, &solve)),
    )
}

/// What [`average_rig_with_loss`] returns: the result, the problem certified, a robust solve's
/// details.
pub type RigRun = (Averaged<RigSolution>, RigProblem, Option<RigRobustDetails>);

/// The robust part of [`average_rig_with_loss`] from the least-squares estimate `ls` of
/// `problem` when the caller solved it (whose clock the settings' budgets already count: `rotavg
/// rig RIGHT LEFT` judges its own joint least squares; `None`: solved here if needed, and never
/// with information, whose robust stage starts from unit weights, `[H24]`): the Cauchy solve,
/// the inlier problem certified, and what was done (`requested` loss, the diagnosis
/// `outliers` that chose it). Its times and budgets start when it is called
/// (`AverageSettings::remaining` gives the budgets the caller has left;
/// [`crate::pipeline::PipelineDetails::add_solve_seconds`] the times).
pub(crate) fn robust_from(
    problem: &RigProblem,
    ls: Option<RigSolution>,
    (requested, outliers): (RigLoss, Option<crate::multiple::robust::OutlierWarning>),
    robust: &RigRobust,
    settings: &AverageRigSettings,
) -> Result<(Averaged<RigSolution>, RigProblem, RigRobustDetails)> {
    let start = std::time::Instant::now();
    let skip = super::validate(problem, settings)?;
    let solve = RigSettings {
        max_seconds: crate::deadline::remaining(settings.solve.max_seconds, start),
        ..settings.solve
    };
    let rr = solve_rig_robust_given(problem, ls, robust, &solve)?;
    let details = RigRobustDetails {
        requested,
        robust: true,
        outliers,
        reweights: rr.reweights,
        inlier_edges: rr.inliers.iter().filter(|k| **k).count(),
        total_edges: problem.edges().len(),
        inlier_threshold_deg: rr.applied.inlier_threshold_deg,
        scale_deg: rr.applied.threshold_deg,
        data_scale: rr.scale.clone(),
    };
    let mut certify = settings.certify.clone();
    certify.budget = certify.budget.after(start);
    let inner = AverageSettings { solve, certify };
    let mut out =
        super::certify_solved(&rr.inlier_problem, rr.inlier_solution, &inner, skip, start)?;
    out.details.solve_seconds = start.elapsed().as_secs_f64() - out.details.certify_seconds;
    out.details.outliers = details.outliers.clone();
    Ok((out, rr.inlier_problem, details))
}

/// What a rig's gravity priors were (`rotavg rig FILE --gravity`, `paper-notes/gravity.md`
/// `[G14]`): the images' priors and their check against the edges between images (`[G6]`), and
/// how they combined on the frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigGravityDetails {
    /// The images' priors, weight and convention check, as `multiple`'s.
    pub images: super::gravity::GravityDetails,
    /// Frames with at least one prior, and in all.
    pub frames_with_prior: usize,
    /// Frames in all.
    pub num_frames: usize,
    /// Frames with several priors, combined into one (`[G14]`).
    pub combined_frames: usize,
    /// The largest angle between a frame's combined direction and one of its images' priors
    /// brought to the frame by its `sensor_from_rig`, degrees.
    pub max_disagreement_deg: f64,
}

/// Above this angle between the priors of one frame (degrees) a warning says so: priors of
/// 2 degrees disagree by a few degrees; a wrong `sensor_from_rig` or convention by tens.
pub const RIG_GRAVITY_DISAGREEMENT_DEG: f64 = 10.0;

impl RigGravityDetails {
    /// The priors of `problem` (`None`: it has none). Errors: those of
    /// [`RigProblem::frame_gravity`].
    pub fn of(problem: &RigProblem) -> Result<Option<Self>> {
        let Some(priors) = problem.gravity() else {
            return Ok(None);
        };
        let held: Vec<_> = problem.held().iter().flatten().copied().collect();
        let Some(fg) = problem.frame_gravity(&held)? else {
            return Ok(None);
        };
        let images =
            crate::multiple::gravity::GravityProblem::new(problem.image_graph()?, priors.clone())?;
        Ok(Some(RigGravityDetails {
            images: super::gravity::GravityDetails::of(&images),
            frames_with_prior: fg.problem.priors().num_known(),
            num_frames: problem.num_frames(),
            combined_frames: fg.combined,
            max_disagreement_deg: fg.max_disagreement_deg,
        }))
    }

    /// The images' check's warnings, and `gravity_frame_disagreement` when one frame's priors
    /// disagree by more than [`RIG_GRAVITY_DISAGREEMENT_DEG`].
    pub fn warnings(&self) -> Vec<crate::warning::Warning> {
        let mut out = self.images.warnings();
        if self.max_disagreement_deg > RIG_GRAVITY_DISAGREEMENT_DEG {
            out.push(crate::warning::Warning::new(
                "gravity_frame_disagreement",
                format!(
                    "the gravity priors of one frame's images, brought to the frame by their \
                     sensor_from_rig, disagree by up to {:.2} degrees: is a sensor_from_rig \
                     wrong or inverted (rotavg reads S = sensor_from_rig, X = S F), or are some \
                     priors in another convention?",
                    self.max_disagreement_deg
                ),
            ));
        }
        out
    }
}

impl std::fmt::Display for RigGravityDetails {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let g = &self.images;
        let w = g.world_down;
        let how = match g.weight {
            Some(weight) => format!("as soft terms of weight {weight} [G10]"),
            None => "held as constraints".into(),
        };
        write!(
            f,
            "gravity: {} of {} images with a prior, {how}, world down ({}, {}, {}); on the \
             frames [G14]: {} of {} with a prior ({} combining several, up to {:.3} deg apart)",
            g.num_with_prior,
            g.num_images,
            w[0],
            w[1],
            w[2],
            self.frames_with_prior,
            self.num_frames,
            self.combined_frames,
            self.max_disagreement_deg
        )?;
        if let Some(c) = &g.check {
            write!(
                f,
                "; R_ij g_i vs g_j over {} edges between images: median {:.3} deg, 90th \
                 percentile {:.3} deg",
                c.edges_checked, c.median_deg, c.p90_deg
            )?;
        }
        Ok(())
    }
}
