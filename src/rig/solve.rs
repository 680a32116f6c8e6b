//! The rig's local solver (`paper-notes/conjugate.md` `[H19]`): from its start, joint
//! Gauss-Newton steps in the frames and the unknown sensors together ([`super::joint`]), and,
//! with gravity priors or where those stall, block-coordinate descent on
//! `J(F, S)`. With the sensors fixed, `J` is the frames' view graph's chordal cost plus a
//! constant ([`RigProblem::frame_graph`]), solved by the sparse chordal Newton-LM; with the
//! frames fixed, `J` is a least-squares problem in the unknown sensors alone (`3K` unknowns for
//! `K` of them), solved by Levenberg-Marquardt on dense `3K x 3K` normal equations. Neither step
//! increases `J`.

use super::joint::{JOINT_DIRECT_VALUES, JOINT_MAX_STEPS, Joint};
use super::problem::RigProblem;
use super::start::start_sensors;
use crate::deadline::{Deadline, limit_reached, remaining};
use crate::error::{Error, Result};
use crate::multiple::{Initialisation, MultipleSettings, solve_multiple};
use crate::so3::{Rotation, exp, hat, nearest_rotation};
use crate::termination::{SolverReport, Termination};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The relative decrease of `J` in one pass below which the alternation stops.
pub const RIG_DECREASE_TOLERANCE: f64 = 1e-10;

/// Settings of [`solve_rig`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RigSettings {
    /// Joint Gauss-Newton steps (at most [`crate::rig::JOINT_MAX_STEPS`] of them), and
    /// alternation passes where those do not apply or stall, at most (default 1000).
    pub max_passes: usize,
    /// Time limit, seconds (`None`, the default: none): the start, the passes and the solves
    /// inside them share one clock, each checked before its next iteration.
    pub max_seconds: Option<f64>,
}

impl Default for RigSettings {
    fn default() -> Self {
        RigSettings {
            max_passes: 1000,
            max_seconds: None,
        }
    }
}

impl RigSettings {
    /// Errors: no passes, a time limit that is not finite and nonnegative.
    pub fn validate(&self) -> Result<()> {
        if self.max_passes == 0 {
            return Err(Error::InvalidSettings {
                name: "max_passes".into(),
                reason: "must be at least 1".into(),
            });
        }
        crate::deadline::validate_max_seconds(self.max_seconds)
    }
}

/// A rig estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigSolution {
    /// The frames `F_f` (rig-from-world), `F_0 = I`.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub frames: Vec<Rotation>,
    /// Every sensor's `sensor_from_rig` `S_s` (the held ones as held).
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub sensors: Vec<Rotation>,
    /// The chordal cost `J(F, S)` (with soft gravity priors, plus their terms).
    pub cost: f64,
    /// Passes, why it stopped, wall time.
    pub report: SolverReport,
}

/// Estimate a rig's frames and unknown sensors (`[H19]`): a start (the held sensors' frames, then
/// each unknown sensor from the edges that place it), then passes of a frame step and a sensor
/// step until one decreases `J` by less than [`RIG_DECREASE_TOLERANCE`] of it, `max_passes` or
/// `max_seconds`. Errors: a sensor no edge places, frames the edges do not join.
///
/// ```
/// use rotavg::rig::{RigScene, RigSettings, solve_rig};
/// let (p, truth) = RigScene { frames: 50, sensors: 3, noise_sigma: 0.0, ..Default::default() }.generate();
/// let s = solve_rig(&p, &RigSettings::default())?;
/// assert!(s.cost < 1e-20);
/// assert!(rotavg::so3::angle_between(&s.sensors[2], &truth.sensors[2]) < 1e-9);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn solve_rig(p: &RigProblem, settings: &RigSettings) -> Result<RigSolution> {
    Ok(solve_rig_judged(p, settings, &[], &mut |_, _| false)?.0)
}

/// [`solve_rig`] judged on the way, as a rule choosing the loss judges a view graph's least
/// squares (`paper-notes/conjugate.md` `[H20]` "Judged least squares"): the start's frames'
/// solve stops at each of `checkpoints` (iterations in all, ascending) in turn, and when it has
/// not converged there and `judge` says its estimate (frames, sensors) shows outliers, that
/// estimate is returned with `true` (the rule discards it for the robust solve); past the last
/// checkpoint the solve is [`solve_rig`]'s from there. Confident wrong pairs make a rig's least
/// squares with information slow: a generated 10^4-image rig of 2 sensors spent 57 s in it
/// before the rule chose Cauchy. Every sensor held: not judged. No checkpoints: [`solve_rig`].
pub(crate) fn solve_rig_judged(
    p: &RigProblem,
    settings: &RigSettings,
    checkpoints: &[usize],
    judge: &mut dyn FnMut(&[Rotation], &[Rotation]) -> bool,
) -> Result<(RigSolution, bool)> {
    settings.validate()?;
    let clock = Instant::now();
    let left = || remaining(settings.max_seconds, clock);
    check_estimated_sensors(p)?;
    let sensors = start_sensors(p, left())?;
    if p.all_held() {
        // nothing to alternate: the frames' problem at the held sensors, solved once (a pass
        // would solve it again: with gravity priors, from its unconstrained start)
        return Ok((held_solution(p, sensors, left(), clock)?, false));
    }
    // the frames from the spectral start of every edge at the start's sensors ([A17] with
    // information): from the held sensors' frames, a 10^4-frame path rig of 3-frame pairs
    // with information ended with J 3.8x its minimum and frames flipped (the joint steps from
    // those frames alone, higher still); rough where the joint steps follow: they finish it
    let rough = Joint::applies(p);
    let (mut frames, mut iterations) = (None, 0);
    for &at in checkpoints {
        let cap = Some(at.saturating_sub(iterations));
        let part = frame_solve_until(p, &sensors, frames.take(), (left(), rough), cap)?;
        iterations += part.report.iterations;
        let stop = part.report.termination;
        if stop.is_converged() {
            let rest = (part.rotations, sensors);
            return Ok((alternate(p, rest, settings, (clock, None))?, false));
        }
        // judged as it would be returned (its sensors projected on SO(3), `rig_solution`)
        let judged = (JUDGED, iterations, stop);
        let candidate = rig_solution(p, (part.rotations, sensors.clone()), judged, clock);
        if judge(&candidate.frames, &candidate.sensors) {
            return Ok((candidate, true));
        }
        frames = Some(candidate.frames);
    }
    let frames = frame_solve(p, &sensors, frames, (left(), rough))?.rotations;
    Ok((
        alternate(p, (frames, sensors), settings, (clock, None))?,
        false,
    ))
}

/// The name of a judged solve's report ([`solve_rig_judged`]).
const JUDGED: &str = "rig: the start's frames, judged (their residuals show outliers)";

/// [`solve_rig`] with every sensor held: one solve of the frames' problem from its spectral
/// start, its iterations and termination reported as the rig's.
fn held_solution(
    p: &RigProblem,
    sensors: Vec<Rotation>,
    max_seconds: Option<f64>,
    clock: Instant,
) -> Result<RigSolution> {
    let solved = frame_solve(p, &sensors, None, (max_seconds, false))?;
    Ok(RigSolution {
        cost: p.cost(&solved.rotations, &sensors),
        frames: solved.rotations,
        sensors,
        report: SolverReport {
            name: format!("rig frames, every sensor held: {}", solved.report.name),
            iterations: solved.report.iterations,
            termination: solved.report.termination,
            seconds: clock.elapsed().as_secs_f64(),
        },
    })
}

/// [`solve_rig`]'s passes from a given estimate (`frames`, `sensors`: one rotation each, each
/// replaced by its nearest rotation; the held sensors set to their held rotations): for
/// many-start searches and for polishing another tool's estimate. Errors: estimates of the
/// wrong length, invalid settings.
///
/// ```
/// use rotavg::rig::{RigScene, RigSettings, solve_rig, solve_rig_from};
/// let (p, truth) = RigScene { frames: 30, sensors: 3, noise_sigma: 0.02, ..Default::default() }.generate();
/// let from_truth = solve_rig_from(&p, &truth.frames, &truth.sensors, &RigSettings::default())?;
/// let own = solve_rig(&p, &RigSettings::default())?;
/// assert!((from_truth.cost - own.cost).abs() < 1e-6 * own.cost);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn solve_rig_from(
    p: &RigProblem,
    frames: &[Rotation],
    sensors: &[Rotation],
    settings: &RigSettings,
) -> Result<RigSolution> {
    solve_rig_from_joint(p, (frames, sensors), settings, None)
}

/// [`solve_rig_from`] with the joint steps `joint` of `p` ([`Joint::reweighted`]: a robust
/// solve's reweighting), made here when `None`.
pub(super) fn solve_rig_from_joint(
    p: &RigProblem,
    (frames, sensors): (&[Rotation], &[Rotation]),
    settings: &RigSettings,
    joint: Option<Joint<'_>>,
) -> Result<RigSolution> {
    settings.validate()?;
    check_estimated_sensors(p)?;
    if frames.len() != p.num_frames() || sensors.len() != p.sensors().len() {
        return Err(Error::InvalidSettings {
            name: "start".into(),
            reason: format!(
                "{} frames and {} sensors for a rig of {} frames and {} sensors",
                frames.len(),
                sensors.len(),
                p.num_frames(),
                p.sensors().len()
            ),
        });
    }
    let frames = frames.iter().map(nearest_rotation).collect();
    let sensors = sensors
        .iter()
        .zip(p.held())
        .map(|(s, held)| held.unwrap_or_else(|| nearest_rotation(s)))
        .collect();
    alternate(p, (frames, sensors), settings, (Instant::now(), joint))
}

/// The passes from `(frames, sensors)`, on the clock started at `clock`, by the joint steps
/// `joint` where given (else made here where they apply).
fn alternate(
    p: &RigProblem,
    (mut frames, mut sensors): (Vec<Rotation>, Vec<Rotation>),
    settings: &RigSettings,
    (clock, joint): (Instant, Option<Joint<'_>>),
) -> Result<RigSolution> {
    let left = || remaining(settings.max_seconds, clock);
    let deadline = Deadline::after(left());
    let (mut passes, mut name) = (0, ALTERNATING);
    let joint = match joint {
        Some(joint) => Some(joint),
        None => Joint::new(p, &sensors, JOINT_DIRECT_VALUES)?,
    };
    if let Some(joint) = joint {
        let steps = settings.max_passes.min(JOINT_MAX_STEPS);
        let (f, s, taken, stop) = joint.run((frames, sensors), (steps, false), deadline);
        (frames, sensors, passes) = (f, s, taken);
        if !matches!(stop, Termination::Stalled { .. }) {
            return Ok(rig_solution(
                p,
                (frames, sensors),
                (JOINT, passes, stop),
                clock,
            ));
        }
        name = "rig: joint Gauss-Newton, then alternating passes (the steps stalled)";
    }
    let mut cost = p.cost(&frames, &sensors);
    let mut decrease = f64::NAN;
    let mut run = Passes::default();
    let termination = loop {
        let measure = (decrease, RIG_DECREASE_TOLERANCE);
        if let Some(limit) = limit_reached(passes, settings.max_passes, deadline, measure) {
            break limit;
        }
        passes += 1;
        (frames, sensors) = run.pass(p, (frames, sensors), left())?;
        let next = p.cost(&frames, &sensors);
        decrease = (cost - next) / cost.abs().max(f64::MIN_POSITIVE);
        cost = next;
        crate::progress::phase(crate::progress::Phase::Solve, || {
            format!("rig pass {passes}: J = {cost:.6e}, relative decrease {decrease:.1e}")
        });
        if decrease < RIG_DECREASE_TOLERANCE && !deadline.is_some_and(|d| d.passed()) {
            break Termination::Converged {
                measure: "relative decrease of J in one pass".into(),
                value: decrease.max(0.0),
                threshold: RIG_DECREASE_TOLERANCE,
            };
        }
    };
    Ok(rig_solution(
        p,
        (frames, sensors),
        (name, passes, termination),
        clock,
    ))
}

/// The solver's name in its report: joint steps alone, or alternation passes.
const JOINT: &str =
    "rig: joint Gauss-Newton (frames and sensors; conjugate gradients, or the frames' factor)";
const ALTERNATING: &str = "rig-alternating (sparse frames, dense sensors)";

/// The solution at `(frames, sensors)` (the sensors projected on `SO(3)`), after `iterations`
/// (joint steps, then alternation passes) of the solver `name` and why they stopped.
fn rig_solution(
    p: &RigProblem,
    (frames, sensors): (Vec<Rotation>, Vec<Rotation>),
    (name, iterations, termination): (&str, usize, Termination),
    clock: Instant,
) -> RigSolution {
    let sensors: Vec<Rotation> = sensors.iter().map(nearest_rotation).collect();
    RigSolution {
        cost: p.cost(&frames, &sensors),
        frames,
        sensors,
        report: SolverReport {
            name: name.into(),
            iterations,
            termination,
            seconds: clock.elapsed().as_secs_f64(),
        },
    }
}

/// The polish before a certificate that needs the sensors' gradient far below what an
/// alternation's stopping rule leaves (`paper-notes/conjugate.md` `[H21]`): joint Gauss-Newton
/// steps ([`Joint`], at most `passes`) to their convergence; where they do not apply (gravity
/// priors), stall, or take none (their model predicts no decrease of `J` while the sensors'
/// gradient is still above what the couplings need: measured on a generated rig with pooled
/// within-frame information, `[H21]` "Polish"), at most `passes` alternation passes
/// ([`Passes`]), until one leaves the sensors where they were. Stops early at `max_seconds`;
/// the joint steps' factor and preconditioner are held within a quarter of `max_bytes`.
/// The point and the steps and passes taken (none: it was stationary to the cost's rounding
/// already).
pub(crate) fn polish_passes(
    p: &RigProblem,
    (mut frames, mut sensors): (Vec<Rotation>, Vec<Rotation>),
    passes: usize,
    (max_seconds, max_bytes): (Option<f64>, u64),
) -> Result<(Vec<Rotation>, Vec<Rotation>, usize)> {
    let clock = Instant::now();
    let left = || remaining(max_seconds, clock);
    let mut taken = 0;
    let max_values = usize::try_from(max_bytes / 4 / 8).unwrap_or(usize::MAX);
    if let Some(joint) = Joint::new(p, &sensors, max_values)? {
        let limits = (passes, true);
        let (f, s, steps, stop) = joint.run((frames, sensors), limits, Deadline::after(left()));
        (frames, sensors, taken) = (f, s, steps);
        if steps > 0 && !matches!(stop, Termination::Stalled { .. }) {
            return Ok((
                frames,
                sensors.iter().map(nearest_rotation).collect(),
                taken,
            ));
        }
    }
    let mut run = Passes::default();
    for _ in 0..passes {
        if left().is_some_and(|l| l <= 0.0) {
            break;
        }
        let before = sensors.clone();
        (frames, sensors) = run.pass(p, (frames, sensors), left())?;
        if sensors == before {
            break; // stationary to the sensor step's rounding
        }
        taken += 1;
    }
    let sensors = sensors.iter().map(nearest_rotation).collect();
    Ok((frames, sensors, taken))
}

/// Alternation passes with an Aitken step on the sensors. The passes converge linearly (a ratio
/// `rho` of about 0.7 per pass on the generated rigs), so after two passes whose sensor moves
/// shrink by `rho` in `(0.2, 0.98)` the sensors are extrapolated by `rho / (1 - rho)` times the
/// last move and the frames solved again, kept only when `J` decreases (`[H21]`).
#[derive(Default)]
struct Passes {
    /// The size of the last pass's sensor move (none after an extrapolation).
    previous: Option<f64>,
}

impl Passes {
    /// One pass (the sensor step, the frame step) and, when the moves call for it, the Aitken
    /// step; neither raises `J` (beyond [`SENSOR_COST_ROUNDING`]).
    fn pass(
        &mut self,
        p: &RigProblem,
        (frames, before): (Vec<Rotation>, Vec<Rotation>),
        seconds: Option<f64>,
    ) -> Result<(Vec<Rotation>, Vec<Rotation>)> {
        let sensors = sensor_step(p, &frames, before.clone(), Deadline::after(seconds));
        let frames = frame_step(p, &sensors, Some(frames), seconds)?;
        let moves: Vec<Vector3<f64>> = before
            .iter()
            .zip(&sensors)
            .map(|(a, b)| crate::so3::log(&(a.inverse() * b)))
            .collect();
        let size = moves.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt();
        let ratio = self.previous.map(|q| size / q);
        self.previous = Some(size);
        let Some(rho) = ratio.filter(|r| (0.2..0.98).contains(r)) else {
            return Ok((frames, sensors));
        };
        let factor = rho / (1.0 - rho);
        let trial: Vec<Rotation> = sensors
            .iter()
            .zip(&moves)
            .map(|(s, v)| s * exp(&(factor * v)))
            .collect();
        let trial_frames = frame_step(p, &trial, Some(frames.clone()), seconds)?;
        if p.cost(&trial_frames, &trial) < p.cost(&frames, &sensors) {
            self.previous = None;
            return Ok((trial_frames, trial));
        }
        Ok((frames, sensors))
    }
}

/// The most sensors the solver estimates: its sensor step factors dense `3K x 3K` normal
/// equations (300: 7 MB, about 0.1 s per factorisation), many times per pass.
pub const MAX_ESTIMATED_SENSORS: usize = 300;

/// Errors: more than [`MAX_ESTIMATED_SENSORS`] sensors to estimate.
fn check_estimated_sensors(p: &RigProblem) -> Result<()> {
    let unknown = p.held().iter().filter(|h| h.is_none()).count();
    if unknown > MAX_ESTIMATED_SENSORS {
        return Err(Error::InvalidSettings {
            name: "rig".into(),
            reason: format!(
                "{unknown} sensors to estimate, more than the {MAX_ESTIMATED_SENSORS} the sensor \
                 step's dense normal equations take; give the known sensors' sensor_from_rig"
            ),
        });
    }
    Ok(())
}

/// The frames at fixed sensors: the frames' view graph solved from `frames` (the spectral start
/// when `None`), gauge `F_0 = I`; with gravity priors, the frames' gravity problem (`[G14]`,
/// the gravity problem's gauge).
fn frame_step(
    p: &RigProblem,
    sensors: &[Rotation],
    frames: Option<Vec<Rotation>>,
    max_seconds: Option<f64>,
) -> Result<Vec<Rotation>> {
    Ok(frame_solve(p, sensors, frames, (max_seconds, false))?.rotations)
}

/// [`frame_step`]'s solve, with its report; `rough`: to the start's tolerances
/// ([`START_DECREASE_TOLERANCE`]), before the joint steps.
fn frame_solve(
    p: &RigProblem,
    sensors: &[Rotation],
    frames: Option<Vec<Rotation>>,
    (max_seconds, rough): (Option<f64>, bool),
) -> Result<crate::multiple::MultipleSolution> {
    frame_solve_until(p, sensors, frames, (max_seconds, rough), None)
}

/// [`frame_solve`] stopped after `max_iterations` when given.
fn frame_solve_until(
    p: &RigProblem,
    sensors: &[Rotation],
    frames: Option<Vec<Rotation>>,
    (max_seconds, rough): (Option<f64>, bool),
    max_iterations: Option<usize>,
) -> Result<crate::multiple::MultipleSolution> {
    let mut settings = MultipleSettings {
        init: frames.map(Initialisation::Given).unwrap_or_default(),
        max_seconds,
        ..Default::default()
    };
    if let Some(n) = max_iterations {
        settings.max_iterations = n.max(1);
    }
    if rough {
        settings.decrease_tolerance = START_DECREASE_TOLERANCE;
        settings.gradient_tolerance = START_GRADIENT_TOLERANCE;
    }
    // with gravity priors (every sensor held, `[G14]`): the frames' gravity problem
    if let Some(fg) = p.frame_gravity(sensors)? {
        return crate::multiple::gravity::solve_gravity(&fg.problem, &settings);
    }
    let (graph, _) = p.frame_graph_for_solve(sensors)?;
    solve_multiple(&graph, &settings)
}

/// The start's frame step before the joint steps stops at this relative predicted decrease
/// (and [`START_GRADIENT_TOLERANCE`]) instead of the multiple solver's `1e-12` (and `1e-8`):
/// the joint steps converge from there to the same minimum (`J` the same to 10 digits on
/// random and path rigs of 10^3-10^4 frames), and the last Newton-LM iterations of the frames'
/// problem cost 0.7-1.4 s of a 10^4-frame, 6-sensor solve with information (`[H19]` "Starts").
const START_DECREASE_TOLERANCE: f64 = 1e-6;

/// The start's frame step's relative gradient tolerance before the joint steps.
const START_GRADIENT_TOLERANCE: f64 = 1e-5;

/// Levenberg-Marquardt iterations of the sensor step at most.
const SENSOR_MAX_ITERATIONS: usize = 50;

/// The relative rounding of `J`'s sum within which a sensor step may raise it when it halves
/// the gradient: at `10^4` frames and 6 sensors (`J ~ 1e6`, `10^5` terms) the steps near the
/// minimum decrease `J` by less than its rounding, and rejecting them left the couplings'
/// charge at 3.4 (the threshold 0.26) for 120 alternation passes.
const SENSOR_COST_ROUNDING: f64 = 1e-12;

/// The unknown sensors at fixed frames: Levenberg-Marquardt on `J` over `S_s exp([d_s]x)` from
/// `sensors`, each step accepted only when it does not increase `J` (or raises it by at most
/// [`SENSOR_COST_ROUNDING`] and halves the gradient); stops when a step changes `J` by less
/// than 1e-15 of it or within that rounding does not halve the gradient, after
/// [`SENSOR_MAX_ITERATIONS`], or at `deadline`.
fn sensor_step(
    p: &RigProblem,
    frames: &[Rotation],
    mut sensors: Vec<Rotation>,
    deadline: Option<Deadline>,
) -> Vec<Rotation> {
    let unknown = p.estimated_sensors();
    if unknown.is_empty() {
        return sensors;
    }
    let mut column = vec![None; sensors.len()];
    for (k, &s) in unknown.iter().enumerate() {
        column[s] = Some(3 * k);
    }
    let terms = SensorTerms::new(p, frames, &column);
    let size = 3 * unknown.len();
    let (mut cost, mut damping) = (terms.cost(&sensors), 1e-8);
    let mut equations = terms.normal_equations(&sensors, size);
    for _ in 0..SENSOR_MAX_ITERATIONS {
        if deadline.is_some_and(|d| d.passed()) {
            break;
        }
        let (h, g) = &equations;
        // a floor for directions an information matrix leaves unweighted (`[H24]`)
        let floor = 1e-12 * h.diagonal().amax().max(f64::MIN_POSITIVE);
        let mut improved = false;
        while damping < 1e12 {
            let mut a = h.clone();
            for k in 0..a.nrows() {
                a[(k, k)] += damping * h[(k, k)].max(floor);
            }
            let Some(step) = a.cholesky().map(|c| c.solve(&(-g))) else {
                damping *= 10.0;
                continue;
            };
            let trial = stepped(&sensors, &unknown, &step);
            let next = terms.cost(&trial);
            if next <= cost {
                let change = (cost - next) / cost.max(f64::MIN_POSITIVE);
                improved = change > 1e-15;
                (sensors, cost, damping) = (trial, next, damping * 0.1);
                equations = terms.normal_equations(&sensors, size);
                break;
            }
            // near the minimum the decrease is below the sum's rounding: a step within it
            // that halves the gradient is taken, and one that does not ends the step (a
            // smaller one would not do better)
            if next <= cost * (1.0 + SENSOR_COST_ROUNDING) {
                let at = terms.normal_equations(&trial, size);
                if at.1.norm() <= 0.5 * g.norm() {
                    (sensors, cost, damping, improved) = (trial, next, damping * 0.1, true);
                    equations = at;
                }
                break;
            }
            damping *= 10.0;
        }
        if !improved {
            break;
        }
    }
    sensors
}

/// `sensors` with each unknown one `S_s exp([d_s]x)`.
fn stepped(sensors: &[Rotation], unknown: &[usize], step: &DVector<f64>) -> Vec<Rotation> {
    let mut out = sensors.to_vec();
    for (k, &s) in unknown.iter().enumerate() {
        let d = Vector3::new(step[3 * k], step[3 * k + 1], step[3 * k + 2]);
        out[s] = nearest_rotation(&(sensors[s] * exp(&d)));
    }
    out
}

/// One edge of [`SensorTerms`] with an unknown sensor.
struct SensorTerm {
    /// The sensors of its images `a` and `b`.
    sa: usize,
    sb: usize,
    weight: f64,
    /// `R_ab`.
    r: Matrix3<f64>,
    /// `A = F_b F_a^T`, computed once per step.
    rel: Matrix3<f64>,
}

/// The edges of the sensor step at fixed frames, each with an unknown sensor, and the
/// unknowns' columns. Their cost `sum w ||S_b A - R S_a||_F^2` (with information
/// `sum 4 (tr M - <R M, S_b A S_a^T>)`) is `J` less the edges between held sensors (equal to
/// `J_e` for rotations `F_a`: `||(S_b A - R S_a) F_a|| = ||S_b F_b - R S_a F_a||`, and
/// `S_b A S_a^T = X_b X_a^T`).
struct SensorTerms {
    edges: Vec<SensorTerm>,
    /// With information (`[H24]`), each edge's `H` and `R M`, `M = tr(H)/2 I - H`; empty
    /// without (kept apart so that the isotropic terms stay small: the step sweeps them a few
    /// times per iteration).
    informed: Vec<(Matrix3<f64>, Matrix3<f64>)>,
    /// The soft gravity priors on images of unknown sensors, `c ||S_s b - g||^2`: the sensor,
    /// `c = 2 w_a`, `b = F_f d` and `g` (`[G15]`).
    priors: Vec<(usize, f64, Vector3<f64>, Vector3<f64>)>,
    column: Vec<Option<usize>>,
}

impl SensorTerms {
    fn new(p: &RigProblem, frames: &[Rotation], column: &[Option<usize>]) -> Self {
        let (mut edges, mut informed) = (Vec::new(), Vec::new());
        let information = p.information();
        for (k, e) in p.edges().iter().enumerate() {
            let (a, b) = (p.images()[e.i], p.images()[e.j]);
            if column[a.sensor].is_none() && column[b.sensor].is_none() {
                continue;
            }
            let r = *e.rotation.matrix();
            edges.push(SensorTerm {
                sa: a.sensor,
                sb: b.sensor,
                weight: e.weight,
                r,
                rel: (frames[b.frame] * frames[a.frame].inverse()).into_inner(),
            });
            if let Some(info) = information {
                informed.push((*info[k].matrix(), r * info[k].chordal_matrix()));
            }
        }
        SensorTerms {
            edges,
            informed,
            priors: sensor_priors(p, frames, column),
            column: column.to_vec(),
        }
    }

    fn cost(&self, sensors: &[Rotation]) -> f64 {
        let matrices = |t: &SensorTerm| (sensors[t.sa].matrix(), sensors[t.sb].matrix());
        let edges: f64 = if self.informed.is_empty() {
            (self.edges.iter())
                .map(|t| {
                    let (ma, mb) = matrices(t);
                    t.weight * (mb * t.rel - t.r * ma).norm_squared()
                })
                .sum()
        } else {
            (self.edges.iter().zip(&self.informed))
                .map(|(t, (h, _))| {
                    let (ma, mb) = matrices(t);
                    informed_term(h, &(t.r.transpose() * mb * t.rel * ma.transpose()))
                })
                .sum()
        };
        let priors: f64 = (self.priors.iter())
            .map(|(s, c, b, g)| c * (sensors[*s] * b - g).norm_squared())
            .sum();
        edges + priors
    }

    /// The Gauss-Newton normal equations `(J^T J, J^T r)` in the unknown sensors' tangent steps:
    /// each residual `E = S_b A - R S_a` has derivatives `S_b [e_k]x A` in `d_b` and
    /// `-R S_a [e_k]x` in `d_a`. With information, half the exact gradient and half the
    /// Gauss-Newton Hessian `4 J^T H J` of `2 e^T H e` ([`Self::informed`]).
    fn normal_equations(&self, sensors: &[Rotation], size: usize) -> (DMatrix<f64>, DVector<f64>) {
        let (mut h, mut g) = (DMatrix::zeros(size, size), DVector::zeros(size));
        let basis = [Vector3::x(), Vector3::y(), Vector3::z()].map(|v| hat(&v));
        let mut derivatives = [(0usize, Matrix3::zeros()); 6];
        for (k, t) in self.edges.iter().enumerate() {
            if let Some(info) = self.informed.get(k) {
                self.informed(t, info, sensors, &basis, (&mut h, &mut g));
                continue;
            }
            let (ma, mb) = (sensors[t.sa].matrix(), sensors[t.sb].matrix());
            let residual = mb * t.rel - t.r * ma;
            let mut n = 0;
            if let Some(c) = self.column[t.sb] {
                for (k, e) in basis.iter().enumerate() {
                    derivatives[n] = (c + k, mb * e * t.rel);
                    n += 1;
                }
            }
            if let Some(c) = self.column[t.sa] {
                for (k, e) in basis.iter().enumerate() {
                    derivatives[n] = (c + k, -(t.r * ma * e));
                    n += 1;
                }
            }
            for (u, du) in &derivatives[..n] {
                g[*u] += t.weight * du.dot(&residual);
                for (v, dv) in &derivatives[..n] {
                    h[(*u, *v)] += t.weight * du.dot(dv);
                }
            }
        }
        // a prior's residual `S_s b - g` has the derivative `S_s [e_k]x b` in `d_s`
        for (s, c, b, target) in &self.priors {
            let Some(col) = self.column[*s] else { continue };
            let m = sensors[*s].matrix();
            let residual = m * b - target;
            let du: [Vector3<f64>; 3] = std::array::from_fn(|k| m * (basis[k] * b));
            for k in 0..3 {
                g[col + k] += c * du[k].dot(&residual);
                for l in 0..3 {
                    h[(col + k, col + l)] += c * du[k].dot(&du[l]);
                }
            }
        }
        (h, g)
    }

    /// One anisotropic term's share of [`Self::normal_equations`] (`[H24]`): with
    /// `P = S_b A S_a^T = X_b X_a^T` and `E = R^T P`, the term `4 tr M - 4 <R M, P>` has
    /// derivatives `-4 <R M, S_b [e_k]x A S_a^T>` in `d_b` and `4 <R M, S_b A [e_k]x S_a^T>` in
    /// `d_a` (half of each added to `g`); `e = log E` moves by `R^T S_b d_b` and `-E S_a d_a`
    /// to first order, and `2 J^T H J` (half the Gauss-Newton Hessian of `2 e^T H e`) is added to
    /// `h`.
    fn informed(
        &self,
        t: &SensorTerm,
        (info, rm): &(Matrix3<f64>, Matrix3<f64>),
        sensors: &[Rotation],
        basis: &[Matrix3<f64>; 3],
        (h, g): (&mut DMatrix<f64>, &mut DVector<f64>),
    ) {
        let (ma, mb) = (sensors[t.sa].matrix(), sensors[t.sb].matrix());
        let e = t.r.transpose() * mb * t.rel * ma.transpose();
        let mut jac: [(usize, Matrix3<f64>); 2] = [(usize::MAX, Matrix3::zeros()); 2];
        if let Some(c) = self.column[t.sb] {
            for (k, b) in basis.iter().enumerate() {
                g[c + k] -= 2.0 * rm.dot(&(mb * b * t.rel * ma.transpose()));
            }
            jac[0] = (c, t.r.transpose() * mb);
        }
        if let Some(c) = self.column[t.sa] {
            for (k, b) in basis.iter().enumerate() {
                g[c + k] += 2.0 * rm.dot(&(mb * t.rel * b * ma.transpose()));
            }
            jac[1] = (c, -(e * ma));
        }
        for (u, ju) in jac.iter().filter(|(c, _)| *c != usize::MAX) {
            for (v, jv) in jac.iter().filter(|(c, _)| *c != usize::MAX) {
                let block = 2.0 * ju.transpose() * info * jv;
                for (k, l) in (0..3).flat_map(|k| (0..3).map(move |l| (k, l))) {
                    h[(u + k, v + l)] += block[(k, l)];
                }
            }
        }
    }
}

/// The anisotropic chordal term `4 (tr M - tr(M E))` of the residual rotation `E` (`[A1]`) in
/// its closed form `8 sin^2(theta / 2) / theta^2 e^T H e`, `e = log E`: its rounding is about
/// `u` relative to the term, where the trace form loses `u tr(H)` to cancellation (the sensor
/// step's line search would stall at a relative cost change of about 1e-9, short of the
/// stationarity `[H21]`'s couplings need).
fn informed_term(h: &Matrix3<f64>, e: &Matrix3<f64>) -> f64 {
    let e = crate::so3::log(&Rotation::from_matrix_unchecked(*e));
    let theta = e.norm();
    let factor = if theta < 1e-4 {
        2.0 * (1.0 - theta * theta / 12.0)
    } else {
        let s = (0.5 * theta).sin();
        8.0 * s * s / (theta * theta)
    };
    factor * e.dot(&(h * e))
}

/// The soft gravity priors of the images of unknown sensors at fixed frames (`[G15]`): `(s, 2
/// w_a, F_f d, g_a)`; none without priors or with held ones (the sensor step of a rig with held
/// priors has every sensor held, `[G14]`).
fn sensor_priors(
    p: &RigProblem,
    frames: &[Rotation],
    column: &[Option<usize>],
) -> Vec<(usize, f64, Vector3<f64>, Vector3<f64>)> {
    let Some(priors) = p.gravity() else {
        return Vec::new();
    };
    let down = priors.world_down();
    (p.images().iter().enumerate())
        .filter(|(_, im)| column[im.sensor].is_some())
        .filter_map(|(a, im)| {
            let (g, w) = (priors.direction(a)?, priors.prior_weight(a)?);
            Some((im.sensor, 2.0 * w, frames[im.frame] * down, g))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::{RigScene, RigTruth};
    use crate::so3::perturb;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// A generated rig of 3 sensors (the first held) with `frames` frames.
    fn three_sensors(frames: usize, noise_sigma: f64, seed: u64) -> (RigProblem, RigTruth) {
        RigScene {
            frames,
            sensors: 3,
            noise_sigma,
            seed,
            ..Default::default()
        }
        .generate()
    }

    /// The judged solve: a judge that always sees outliers gets the start's frames after at most
    /// the first checkpoint's iterations (not converged, the report saying so); one that never
    /// does gets [`solve_rig`]'s minimum (`J` within `1e-9` of it); a rig of held sensors is
    /// solved whole and not judged.
    #[test]
    fn a_judged_solve_stops_at_its_first_checkpoint_or_runs_whole() {
        let (p, _) = RigScene {
            frames: 80,
            sensors: 3,
            noise_sigma: 0.05,
            anisotropy: 9.0,
            outlier_fraction: 0.2,
            seed: 3,
            ..Default::default()
        }
        .generate();
        let settings = RigSettings::default();
        let whole = solve_rig(&p, &settings).unwrap();
        let (judged, yes) = solve_rig_judged(&p, &settings, &[2, 30], &mut |_, _| true).unwrap();
        assert!(yes && judged.report.name == JUDGED);
        assert!(
            judged.report.iterations <= 2,
            "{}",
            judged.report.iterations
        );
        assert!(!judged.report.termination.is_converged());
        assert!(
            judged.cost > whole.cost * (1.0 + 1e-6),
            "{} against {}",
            judged.cost,
            whole.cost
        );
        let (free, no) = solve_rig_judged(&p, &settings, &[2, 30], &mut |_, _| false).unwrap();
        assert!(!no && free.report.name != JUDGED);
        assert!(
            (free.cost - whole.cost).abs() <= 1e-9 * whole.cost,
            "{} against {}",
            free.cost,
            whole.cost
        );
        let (held, _) = RigScene {
            frames: 30,
            sensors: 2,
            known: true,
            anisotropy: 9.0,
            seed: 3,
            ..Default::default()
        }
        .generate();
        let (_, judged) = solve_rig_judged(&held, &settings, &[2, 30], &mut |_, _| true).unwrap();
        assert!(!judged);
    }

    /// The joint steps ([`Joint`], what [`solve_rig`] runs) reach the minimum the alternation
    /// converges to (400 passes from the planted rig) on rigs of 60 frames and 4 sensors with
    /// scalar weights and with information: `J` as low (within `1e-9` of it) and the sensors
    /// within `1e-6` rad, in a few steps where the passes take hundreds.
    #[test]
    fn joint_steps_reach_the_alternation_s_minimum() {
        for anisotropy in [1.0, 9.0] {
            let (p, truth) = RigScene {
                frames: 60,
                sensors: 4,
                noise_sigma: 0.05,
                anisotropy,
                seed: 5,
                ..Default::default()
            }
            .generate();
            let joint = solve_rig(&p, &RigSettings::default()).unwrap();
            assert!(joint.report.iterations <= 20, "{:?}", joint.report);
            let mut run = Passes::default();
            let mut x = (truth.frames.clone(), truth.sensors.clone());
            for _ in 0..400 {
                x = run.pass(&p, x, None).unwrap();
            }
            let alternated = p.cost(&x.0, &x.1);
            assert!(
                joint.cost <= alternated * (1.0 + 1e-9),
                "{} {alternated}",
                joint.cost
            );
            assert!(
                joint.cost >= alternated * (1.0 - 1e-9),
                "{} {alternated}",
                joint.cost
            );
            for (a, b) in joint.sensors.iter().zip(&x.1) {
                assert!(crate::so3::angle_between(a, b) <= 1e-6);
            }
        }
    }

    /// The sensor step near its minimum, where a step lowers `J` by less than the rounding of
    /// its sum: from the step's own minimum turned by `1e-8` rad it still brings the gradient
    /// down by three orders ([`SENSOR_COST_ROUNDING`]), at 16 turned points, with and without
    /// information matrices. Fails when only steps that do not raise the rounded `J` are taken
    /// (checked: at 5 of the 32 turned points the gradient then falls by less than 400x).
    #[test]
    fn the_sensor_step_passes_below_the_rounding_of_the_cost() {
        let mut stuck = Vec::new();
        for anisotropy in [1.0, 9.0] {
            let (p, truth) = RigScene {
                frames: 400,
                sensors: 3,
                noise_sigma: 0.05,
                seed: 4,
                anisotropy,
                ..Default::default()
            }
            .generate();
            let unknown = p.estimated_sensors();
            let mut column = vec![None; truth.sensors.len()];
            unknown
                .iter()
                .enumerate()
                .for_each(|(k, &s)| column[s] = Some(3 * k));
            let terms = SensorTerms::new(&p, &truth.frames, &column);
            let gradient = |s: &[Rotation]| terms.normal_equations(s, 3 * unknown.len()).1.norm();
            let best = sensor_step(&p, &truth.frames, truth.sensors.clone(), None);
            let mut rng = StdRng::seed_from_u64(3);
            for k in 0..16 {
                let turned: Vec<Rotation> = (best.iter().enumerate())
                    .map(|(s, r)| match column[s] {
                        Some(_) => perturb(r, 1e-8, &mut rng),
                        None => *r,
                    })
                    .collect();
                let before = gradient(&turned);
                let after = gradient(&sensor_step(&p, &truth.frames, turned, None));
                if after > 1e-3 * before {
                    stuck.push((anisotropy, k, before, after));
                }
            }
        }
        assert!(stuck.is_empty(), "the gradient stayed: {stuck:?}");
    }

    /// The passes with the Aitken step never raise `J`, take at least one extrapolation on a
    /// noisy rig, and end no higher than the same number of plain alternations.
    #[test]
    fn aitken_passes_never_raise_the_cost() {
        let (p, truth) = three_sensors(60, 0.02, 9);
        let mut rng = StdRng::seed_from_u64(1);
        let mut sensors: Vec<Rotation> = truth.sensors.clone();
        for s in sensors.iter_mut().skip(1) {
            *s = perturb(s, 0.2, &mut rng);
        }
        let start = frame_step(&p, &sensors, Some(truth.frames.clone()), None).unwrap();
        let (mut frames, mut plain) = (start.clone(), (start, sensors.clone()));
        let mut run = Passes::default();
        let mut cost = p.cost(&frames, &sensors);
        let mut extrapolated = 0;
        for _ in 0..12 {
            (frames, sensors) = run.pass(&p, (frames, sensors), None).unwrap();
            extrapolated += usize::from(run.previous.is_none());
            let next = p.cost(&frames, &sensors);
            assert!(next <= cost * (1.0 + 1e-14), "{cost} -> {next}");
            cost = next;
            plain.1 = sensor_step(&p, &plain.0, plain.1, None);
            plain.0 = frame_step(&p, &plain.1, Some(plain.0), None).unwrap();
        }
        assert!(extrapolated > 0);
        assert!(cost <= p.cost(&plain.0, &plain.1) * (1.0 + 1e-12));
    }

    /// The sensor step's normal equations with soft gravity priors (`[G15]`): `J^T r` is half
    /// the derivative of the step's cost (edges and priors) along each sensor's tangent
    /// directions, by central differences; and a pass never raises `J + P`.
    /// `[H24]`: with information, the sensor step's `g` is half the gradient of its cost
    /// (central differences along `S_s exp([t e_k]x)`), and its `h` is positive semidefinite.
    #[test]
    fn anisotropic_sensor_terms_have_half_the_cost_s_gradient() {
        let scene = RigScene {
            frames: 12,
            sensors: 3,
            noise_sigma: 0.05,
            anisotropy: 9.0,
            seed: 4,
            ..Default::default()
        };
        let (p, truth) = scene.generate();
        let column = vec![None, Some(0), Some(3)];
        let terms = SensorTerms::new(&p, &truth.frames, &column);
        let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(9);
        let sensors: Vec<Rotation> = (truth.sensors.iter())
            .map(|s| crate::so3::perturb_gaussian(s, 0.1, &mut rng))
            .collect();
        let (h, g) = terms.normal_equations(&sensors, 6);
        let t = 1e-6;
        for (s, c) in [(1, 0), (2, 3)] {
            for k in 0..3 {
                let mut d = Vector3::zeros();
                d[k] = t;
                let moved = |sign: f64| {
                    let mut x = sensors.clone();
                    x[s] = sensors[s] * exp(&(sign * d));
                    terms.cost(&x)
                };
                let numeric = (moved(1.0) - moved(-1.0)) / (2.0 * t);
                let scale = numeric.abs().max(1.0);
                assert!(
                    (2.0 * g[c + k] - numeric).abs() < 1e-5 * scale,
                    "sensor {s} axis {k}: {} against {numeric}",
                    2.0 * g[c + k]
                );
            }
        }
        let least = h.clone().symmetric_eigen().eigenvalues.min();
        assert!(least >= -1e-9 * h.norm(), "h has eigenvalue {least}");
        // the cost is the rig's less the edges between held sensors: equal differences
        let moved = {
            let mut x = sensors.clone();
            x[1] = sensors[1] * exp(&Vector3::new(0.01, -0.02, 0.03));
            x
        };
        let rig = p.cost(&truth.frames, &moved) - p.cost(&truth.frames, &sensors);
        let step = terms.cost(&moved) - terms.cost(&sensors);
        assert!(
            (rig - step).abs() < 1e-6 * rig.abs().max(1.0),
            "{rig} against {step}"
        );
    }

    #[test]
    fn sensor_terms_with_priors_have_the_cost_s_gradient() {
        use crate::multiple::gravity::GravityPriors;
        let (p, truth) = three_sensors(20, 0.05, 4);
        let dirs = truth.gravity(&p, 0.02, 3, 5);
        let priors = GravityPriors::new(dirs).unwrap().with_weight(7.0).unwrap();
        let p = p.with_gravity(priors).unwrap();
        let mut rng = StdRng::seed_from_u64(2);
        let sensors: Vec<Rotation> = (truth.sensors.iter())
            .zip(p.held())
            .map(|(s, h)| h.unwrap_or_else(|| perturb(s, 0.1, &mut rng)))
            .collect();
        let frames: Vec<Rotation> = truth
            .frames
            .iter()
            .map(|f| perturb(f, 0.05, &mut rng))
            .collect();
        let unknown = p.estimated_sensors();
        let mut column = vec![None; sensors.len()];
        for (k, &s) in unknown.iter().enumerate() {
            column[s] = Some(3 * k);
        }
        let terms = SensorTerms::new(&p, &frames, &column);
        assert!(!terms.priors.is_empty());
        let (_, g) = terms.normal_equations(&sensors, 3 * unknown.len());
        let eps = 1e-6;
        for (k, &s) in unknown.iter().enumerate() {
            for axis in 0..3 {
                let mut d = Vector3::zeros();
                d[axis] = eps;
                let moved = |sign: f64| {
                    let mut x = sensors.clone();
                    x[s] = sensors[s] * exp(&(d * sign));
                    terms.cost(&x)
                };
                let numeric = (moved(1.0) - moved(-1.0)) / (2.0 * eps);
                let analytic = 2.0 * g[3 * k + axis];
                assert!(
                    (numeric - analytic).abs() <= 1e-5 * (1.0 + analytic.abs()),
                    "sensor {s} axis {axis}: {numeric} vs {analytic}"
                );
            }
        }
        let before = p.cost(&frames, &sensors);
        let (f, s) = Passes::default().pass(&p, (frames, sensors), None).unwrap();
        assert!(p.cost(&f, &s) <= before, "{} > {before}", p.cost(&f, &s));
    }
}
