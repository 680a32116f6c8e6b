//! The loss follows the data (issue 37; `docs/reference/cli.md`, "The default loss"): multiple
//! averaging under the rule `auto` solves least squares first and keeps it unless its residuals
//! show outliers ([`suspected_outliers`]); then it solves the robust loss instead and certifies
//! the chordal L2 problem on the robust estimate's inlier graph. `paper-notes/certificates.md`
//! `[D17]` states what each verdict is about.

use super::inlier_graph::ViewGraphProblem;
use super::{AverageSettings, MultipleEstimate, certify_solved, validate};
use crate::error::Result;
use crate::multiple::robust::{OutlierWarning, judges_residuals, suspected_outliers};
use crate::multiple::robust_scale::{DataScale, ScaleRule, data_scale};
use crate::multiple::{Initialisation, MultipleSettings};
use crate::objective::Objective;
use crate::termination::Termination;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// How the rule `auto` ([`MultipleSettings::robust_on_outliers`]) chose the loss of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LossChoice {
    /// The rule: `"auto"`.
    pub rule: String,
    /// The objective the returned estimate minimises: chordal L2, or `robust`.
    pub chosen: Objective,
    /// The robust objective the rule switches to when the diagnosis fires.
    pub robust: Objective,
    /// The outlier diagnosis at the least-squares estimate, when it fired (then `chosen` is
    /// `robust`).
    pub diagnosis: Option<OutlierWarning>,
    /// Why, in words.
    pub reason: String,
    /// Chordal cost of the least-squares estimate that was judged.
    pub least_squares_cost: f64,
    /// Time of that least-squares solve, seconds (in the run's `total_seconds`; when the
    /// robust loss was chosen, not in its `solve_seconds`).
    pub least_squares_seconds: f64,
    /// When the robust loss was chosen with its scale from the data
    /// ([`ScaleRule::FromData`], `[D20]`): that scale and how it was found (its L1 solve is in
    /// the run's `total_seconds`, not in its `solve_seconds`). `None`: the scale as given.
    #[serde(default)]
    pub scale: Option<DataScale>,
}

impl LossChoice {
    /// Whether the robust loss was chosen.
    pub fn is_robust(&self) -> bool {
        self.diagnosis.is_some()
    }
}

impl fmt::Display for LossChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.diagnosis {
            Some(w) => {
                write!(
                    f,
                    "loss: {} chose {} (the least-squares residuals show outliers: {} of {} \
                     edges at {:.1} deg or more, median {:.2} deg)",
                    self.rule, self.chosen, w.suspected, w.num_edges, w.threshold_deg, w.median_deg
                )?;
                if let Some(s) = &self.scale {
                    write!(
                        f,
                        "; its scale from the data: {} (`--loss-threshold` sets it), its inlier \
                         threshold {} unless `--inlier-threshold` is given",
                        s.scale_words("the L1 solution"),
                        s.threshold_words(),
                    )?;
                }
                write!(
                    f,
                    "; its inlier graph's chordal L2 problem is the one certified; `--loss \
                     chordal` keeps least squares over all edges"
                )
            }
            None => write!(
                f,
                "loss: {} kept {} ({})",
                self.rule, self.chosen, self.reason
            ),
        }
    }
}

/// The pipeline under the rule `auto` for a chordal L2 `problem` (multiple averaging, with or
/// without gravity priors): solve it; when [`suspected_outliers`] fires at its estimate, return
/// the pipeline of the same problem
/// with the objective `robust` (exactly what that loss gives on its own: the robust estimate,
/// and unless the mode is `none` the certificate of its inlier graph), else certify the
/// least-squares estimate. `details.loss_choice` records the choice and the diagnosis (not a
/// warning: the rule acted on it; `details.outliers` stays empty).
pub(super) fn average_by_residuals<P: ViewGraphProblem>(
    problem: &P,
    settings: &AverageSettings<MultipleSettings>,
    robust: Objective,
) -> Result<MultipleEstimate> {
    let start = Instant::now();
    let skip = validate(problem, settings)?;
    let least_squares = judged_least_squares(problem, &settings.solve)?;
    let graph = problem.graph();
    let mut choice = LossChoice {
        rule: "auto".into(),
        chosen: graph.objective(),
        robust,
        diagnosis: None,
        reason: if judges_residuals(graph) {
            "the least-squares residuals show no outliers".into()
        } else {
            "fewer than two edges per node: residuals cannot reveal outliers".into()
        },
        least_squares_cost: least_squares.chordal_cost,
        least_squares_seconds: least_squares.report.seconds,
        scale: None,
    };
    let Some(mut diagnosis) = suspected_outliers(graph, &least_squares.rotations) else {
        let mut out = certify_solved(problem, least_squares, settings, skip, start)?;
        out.details.loss_choice = Some(choice);
        return Ok(out);
    };
    diagnosis.suggestion = format!(
        "solved with the {} loss instead (the default `--loss auto`; `--loss chordal` keeps \
         least squares over all edges)",
        robust.loss.name()
    );
    choice.reason = "the least-squares residuals show outliers".into();
    choice.diagnosis = Some(diagnosis);
    let (robust, robust_settings) = robust_run(graph, robust, settings, start, &mut choice)?;
    let robust_problem = problem.with_objective(robust)?;
    let mut out = robust_problem.average_all(&robust_settings)?;
    choice.chosen = robust;
    out.details.loss_choice = Some(choice);
    out.details.total_seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// The objective and settings of the rule's robust run: the scale of `robust` from the data
/// ([`data_scale`], `[D20]`; recorded in `choice.scale`) unless the settings give it, with its
/// inlier threshold unless the settings give one, and the L1 solution found for it handed over
/// as the run's L1 start (unless a start is given); the clock's remainder after it (`start` the
/// run's).
fn robust_run(
    graph: &crate::multiple::MultipleProblem,
    robust: Objective,
    settings: &AverageSettings<MultipleSettings>,
    start: Instant,
    choice: &mut LossChoice,
) -> Result<(Objective, AverageSettings<MultipleSettings>)> {
    let run = || {
        let mut run = settings.remaining(start);
        run.solve.robust_on_outliers = None;
        run
    };
    if settings.solve.robust_scale == ScaleRule::Given || robust.loss.threshold_deg().is_none() {
        return Ok((robust, run()));
    }
    let (scale, l1) = data_scale(graph, robust.metric, &run().solve)?;
    let mut after = run();
    if !matches!(after.solve.init, Initialisation::Given(_)) {
        after.solve.init = Initialisation::L1Start(l1);
    }
    if after.solve.inlier_threshold_deg.is_none() {
        after.solve.inlier_threshold_deg = Some(scale.inlier_threshold_deg);
    }
    let scaled = scale.applied_to(robust);
    choice.scale = Some(scale);
    Ok((scaled, after))
}

/// Newton iterations of the least-squares solve at which the rule may judge an unconverged
/// estimate (`[D17]` "When it judges"): after 5 (the judged SLAM graphs of the shared data
/// converge in 2-4) and after 30.
pub const JUDGE_AT_ITERATIONS: [usize; 2] = [5, 30];

/// The last of [`JUDGE_AT_ITERATIONS`]: past it the solve runs to its own stopping test.
pub const JUDGE_AFTER_ITERATIONS: usize = JUDGE_AT_ITERATIONS[1];

/// The least-squares solve the rule judges. It runs to each of [`JUDGE_AT_ITERATIONS`] in
/// turn; when it has not converged by one and its residuals there already show outliers, that
/// estimate is judged (the rule discards it for the robust solve); past the last the solve goes
/// on to its own stopping test (iterations and time summed; one clock for
/// [`MultipleSettings::max_seconds`], and a part stopped by it is judged as it is). Confident
/// wrong pairs make least squares slow: a generated 10^4-image scene with `--information full`
/// ran 100 Newton iterations (7.1 s) without converging before the rule chose Cauchy.
fn judged_least_squares<P: ViewGraphProblem>(
    problem: &P,
    settings: &MultipleSettings,
) -> Result<crate::multiple::MultipleSolution> {
    // a graph whose residuals cannot be judged (`judges_residuals`) is solved in one piece
    if !judges_residuals(problem.graph()) {
        return problem.solve(settings);
    }
    let start = Instant::now();
    let mut so_far: Option<crate::multiple::MultipleSolution> = None;
    let checkpoints = JUDGE_AT_ITERATIONS.iter().copied();
    for at in checkpoints.filter(|&at| at < settings.max_iterations) {
        let part = solve_part(problem, settings, so_far.as_ref(), at, start)?;
        let part = joined(so_far, part);
        let timed_out = matches!(part.report.termination, Termination::TimeLimit { .. });
        if part.report.termination.is_converged()
            || timed_out
            || suspected_outliers(problem.graph(), &part.rotations).is_some()
        {
            return Ok(part);
        }
        so_far = Some(part);
    }
    let rest = solve_part(
        problem,
        settings,
        so_far.as_ref(),
        settings.max_iterations,
        start,
    )?;
    Ok(joined(so_far, rest))
}

/// The least-squares solve from `so_far`'s estimate (from the settings' start when `None`) up
/// to `until` iterations in all, within what is left of the budget started at `start`.
fn solve_part<P: ViewGraphProblem>(
    problem: &P,
    settings: &MultipleSettings,
    so_far: Option<&crate::multiple::MultipleSolution>,
    until: usize,
    start: Instant,
) -> Result<crate::multiple::MultipleSolution> {
    let part = match so_far {
        None => MultipleSettings {
            max_iterations: until,
            ..settings.clone()
        },
        Some(s) => MultipleSettings {
            init: Initialisation::Given(s.rotations.clone()),
            max_iterations: until.saturating_sub(s.report.iterations).max(1),
            ..settings.remaining(start)
        },
    };
    problem.solve(&part)
}

/// `next` continued from `so_far` (its iterations and seconds added, the first start's cost).
fn joined(
    so_far: Option<crate::multiple::MultipleSolution>,
    mut next: crate::multiple::MultipleSolution,
) -> crate::multiple::MultipleSolution {
    if let Some(s) = so_far {
        next.report.iterations += s.report.iterations;
        next.report.seconds += s.report.seconds;
        next.init_cost = s.init_cost;
    }
    next
}
