//! The sparse joint solver of the simultaneous problem (`paper-notes/conjugate.md`, `[H17]`):
//! block-coordinate descent on `J(R, S)`. With `S` fixed, `J` is the chordal cost of one view
//! graph over the rig frames, the right edges and the left edges turned into frame measurements
//! `S^T L_ij S` (`||S R_j - L_ij S R_i|| = ||R_j - S^T L_ij S R_i||`), solved by the sparse
//! chordal Newton-LM; with `R` fixed, `J` is the conjugate cost of the pairs
//! `(L_ij, R_j R_i^T)` (`||S R_j R_i^T - L_ij S||`), solved by the conjugate solver. Each pass
//! does not increase `J`; no dense `3n x 3n` system is formed.

use super::{SimultaneousProblem, SimultaneousSolution};
use crate::conjugate::{ConjugatePair, ConjugateProblem, ConjugateSettings, solve_conjugate};
use crate::deadline::{Deadline, limit_reached, remaining};
use crate::error::Result;
use crate::multiple::{Initialisation, MultipleSettings, solve_multiple};
use crate::so3::Rotation;
use crate::termination::{SolverReport, Termination};
use std::time::Instant;

/// The relative decrease of `J` in one pass below which the alternation stops.
pub const ALTERNATING_DECREASE_TOLERANCE: f64 = 1e-10;

/// The start: each graph averaged on its own (sparse, gauge `R_0 = L_0 = I`), then `S` from
/// the conjugate problem on the pairs `(L_i, R_i)`, `i >= 1`.
/// Within `max_seconds` from `clock`.
fn start(
    p: &SimultaneousProblem,
    (clock, max_seconds): (Instant, Option<f64>),
) -> Result<(Vec<Rotation>, Rotation)> {
    let (right, left) = p.graphs()?;
    let settings = || MultipleSettings {
        max_seconds: remaining(max_seconds, clock),
        ..Default::default()
    };
    let rs = solve_multiple(&right, &settings())?.rotations;
    let ls = solve_multiple(&left, &settings())?.rotations;
    let pairs = (1..p.num_nodes)
        .map(|i| ConjugatePair::new(ls[i], rs[i]))
        .collect();
    let settings = ConjugateSettings {
        max_seconds: remaining(max_seconds, clock),
        ..Default::default()
    };
    let s = solve_conjugate(&ConjugateProblem::new(pairs)?, &settings)?;
    Ok((rs, s.estimate))
}

/// `S` at fixed frames: the conjugate problem of the pairs `(L_ij, R_j R_i^T)`, from `s`,
/// within `max_seconds`.
fn sensor_step(
    p: &SimultaneousProblem,
    rs: &[Rotation],
    s: &Rotation,
    max_seconds: Option<f64>,
) -> Result<Rotation> {
    let pairs = p
        .left
        .iter()
        .map(|e| ConjugatePair {
            weight: e.weight,
            ..ConjugatePair::new(e.rotation, rs[e.j] * rs[e.i].inverse())
        })
        .collect();
    let settings = ConjugateSettings {
        init: Some(*s),
        max_seconds,
        ..Default::default()
    };
    Ok(solve_conjugate(&ConjugateProblem::new(pairs)?, &settings)?.estimate)
}

/// The frames at fixed `s`: the frames' view graph solved from `rs` within `max_seconds`.
fn frames_at(
    p: &SimultaneousProblem,
    s: &Rotation,
    rs: Vec<Rotation>,
    max_seconds: Option<f64>,
) -> Result<Vec<Rotation>> {
    let settings = MultipleSettings {
        init: Initialisation::Given(rs),
        max_seconds,
        ..Default::default()
    };
    Ok(solve_multiple(&p.frame_graph(s)?, &settings)?.rotations)
}

/// The Aitken step of `[H17]` (as the rig files' `[H19]`): the passes converge linearly, so when
/// the sensor's move from `before` shrinks by a ratio `rho` in `(0.2, 0.98)` against the last
/// pass's (`previous`), `S` is moved on by `rho / (1 - rho)` times it and the frames solved
/// again, kept only when `J` decreases.
fn aitken(
    p: &SimultaneousProblem,
    (rs, s): (Vec<Rotation>, Rotation),
    before: &Rotation,
    previous: &mut Option<f64>,
    max_seconds: Option<f64>,
) -> Result<(Vec<Rotation>, Rotation)> {
    let step = crate::so3::log(&(before.inverse() * s));
    let ratio = previous.map(|q| step.norm() / q);
    *previous = Some(step.norm());
    let Some(rho) = ratio.filter(|r| (0.2..0.98).contains(r)) else {
        return Ok((rs, s));
    };
    let trial = s * crate::so3::exp(&(rho / (1.0 - rho) * step));
    let trial_rs = frames_at(p, &trial, rs.clone(), max_seconds)?;
    if p.cost(&trial_rs, &trial) < p.cost(&rs, &s) {
        *previous = None;
        return Ok((trial_rs, trial));
    }
    Ok((rs, s))
}

/// Block-coordinate descent on `J` from the separate averages (`[H17]`), at most `max_passes`
/// passes, until a pass decreases `J` by less than [`ALTERNATING_DECREASE_TOLERANCE`] of it.
///
/// ```
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::pipeline::simultaneous::{SyntheticRig, solve_simultaneous, alternating::solve_alternating};
/// let graph = SyntheticGraph { num_rotations: 60, num_edges: 240, noise_sigma: 0.02, ..Default::default() };
/// let (p, _, _) = SyntheticRig { graph }.generate();
/// let sparse = solve_alternating(&p, 100)?;
/// let dense = solve_simultaneous(&p, 100)?;
/// assert!(sparse.report.termination.is_converged());
/// assert!((sparse.cost - dense.cost).abs() <= 1e-6 * dense.cost);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn solve_alternating(
    p: &SimultaneousProblem,
    max_passes: usize,
) -> Result<SimultaneousSolution> {
    solve_within(p, max_passes, None)
}

/// [`solve_alternating`] within `max_seconds` (`None`: no limit): the start, the passes and
/// the solves inside them share one clock, each checked before its next iteration.
pub(crate) fn solve_within(
    p: &SimultaneousProblem,
    max_passes: usize,
    max_seconds: Option<f64>,
) -> Result<SimultaneousSolution> {
    let clock = Instant::now();
    let (mut rs, mut s) = start(p, (clock, max_seconds))?;
    let mut cost = p.cost(&rs, &s);
    let deadline = Deadline::after(remaining(max_seconds, clock));
    let (mut passes, mut decrease) = (0, f64::NAN);
    let mut previous = None;
    let termination = loop {
        let measure = (decrease, ALTERNATING_DECREASE_TOLERANCE);
        if let Some(limit) = limit_reached(passes, max_passes, deadline, measure) {
            break limit;
        }
        passes += 1;
        let before = s;
        rs = frames_at(p, &s, rs, remaining(max_seconds, clock))?;
        s = sensor_step(p, &rs, &s, remaining(max_seconds, clock))?;
        (rs, s) = aitken(
            p,
            (rs, s),
            &before,
            &mut previous,
            remaining(max_seconds, clock),
        )?;
        let next = p.cost(&rs, &s);
        decrease = (cost - next) / cost.abs().max(f64::MIN_POSITIVE);
        cost = next;
        crate::progress::phase(crate::progress::Phase::Solve, || {
            format!(
                "rig alternation pass {passes}: J = {cost:.6e}, relative decrease {decrease:.1e}"
            )
        });
        // a pass the time limit cut short is no evidence of convergence
        if decrease < ALTERNATING_DECREASE_TOLERANCE && !deadline.is_some_and(|d| d.passed()) {
            break Termination::Converged {
                measure: "relative decrease of J in one pass".into(),
                value: decrease.max(0.0),
                threshold: ALTERNATING_DECREASE_TOLERANCE,
            };
        }
    };
    let report = SolverReport {
        name: "simultaneous-alternating (sparse)".into(),
        iterations: passes,
        termination,
        seconds: clock.elapsed().as_secs_f64(),
    };
    Ok(super::on_so3(p, &rs, &s, report))
}
