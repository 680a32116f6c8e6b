//! Certificates of the simultaneous problem (`paper-notes/conjugate.md` `[H14]`, `[H15]`): the
//! hand-eye rotation `S` and the absolutes `R_i` of two view graphs, jointly. Two rungs: the
//! dual certificate at the estimate ([`dual`], `[H15]`), then the SDP of
//! [`crate::relax::simultaneous`] (`[H14]`), each predicted from its size and refused over the
//! budget; their multipliers are verified here by an independent dense eigenvalue computation.
//!
//! For any symmetric `Lambda_a` and any numbers `gamma_ij`, every joint point `(R, S)` gives
//! `X_R` (blocks `R_i R_j^T`) and `X_C` (blocks `S R_i R_j^T S^T`) with identity diagonal
//! blocks, equal block traces and `tr X_R = tr X_C = 3n`, so the joint cost
//! `J = tr(Q_R X_R) + tr(Q_C X_C) = sum_a tr(Lambda_a) + tr(Z_R X_R) + tr(Z_C X_C)` is at least
//! `sum_a tr(Lambda_a) + 3n (min(lambda_min(Z_R), 0) + min(lambda_min(Z_C), 0))`, where
//! `Z_R = Q_R - blkdiag(Lambda_R) - sum gamma_ij E_ij` and
//! `Z_C = Q_C - blkdiag(Lambda_C) + sum gamma_ij E_ij` (the coupling terms cancel because the
//! traces are equal): the bound holds for the global minimum of `J`.

pub mod dual;
mod search;

use super::certificate::{BoundMethod, Certificate, nonnegative_bound_at_most};
use super::certification::{Certification, CertifyDetails, Improvement, ImprovementSource};
use super::certification::{MethodRun, SdpSummary};
use super::ladder::{Attempt, Outcome, Point, Prediction, Refusal, Rung};
use super::settings::{CertifyMode, CertifySettings};
use crate::certify::multiple::multipliers::data_defect;
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian_triplets;
use crate::relax::simultaneous::{
    JointRotations, coupling_pairs, joint_cost, predict_relax_simultaneous, relax_simultaneous,
};
use crate::so3::Rotation;
use nalgebra::{DMatrix, Matrix3};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A lower bound on the global minimum of the joint cost, verified from multipliers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimultaneousBound {
    /// `sum_a tr(Lambda_a) + 3n (min(verified lambda_min(Z_R), 0) + min(verified
    /// lambda_min(Z_C), 0)) - rounding - the two graphs' data defects` (`[D4]`: measurements
    /// orthogonal only to the validation tolerance).
    pub lower_bound: f64,
    /// The smaller of `lambda_min(Z_R)` and `lambda_min(Z_C)` from nalgebra's dense symmetric
    /// eigenvalue solver.
    pub min_eigenvalue: f64,
    /// Proven lower bound on that smaller `lambda_min` of the exact matrices: each computed
    /// value minus `10 (3n) eps ||(|Q| + |blkdiag Lambda| + sum |gamma_ij E_ij|)||_F`, which
    /// covers the rounding of forming `Z` (at most three terms per entry) and the eigen
    /// solver's backward error.
    pub verified_min_eigenvalue: f64,
}

/// One side's dense certificate matrix (`Z_R` for the right graph with `sign = -1/2`, `Z_C` for
/// the left with `+1/2`; `lambdas` that side's `n` blocks) and the entrywise magnitudes of its
/// terms.
fn certificate_matrix(
    p: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    couplings: &[f64],
    sign: f64,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = p.num_rotations();
    let dim = 3 * n;
    let mut m = DMatrix::zeros(dim, dim);
    let mut mag = DMatrix::zeros(dim, dim);
    let mut add = |r: usize, c: usize, v: f64| {
        m[(r, c)] += v;
        mag[(r, c)] += v.abs();
    };
    for t in connection_laplacian_triplets(p) {
        add(t.row, t.col, t.val);
    }
    for (a, l) in lambdas.iter().enumerate() {
        for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
            add(3 * a + r, 3 * a + c, -l[(r, c)]);
        }
    }
    for ((i, j), g) in coupling_pairs(n).zip(couplings) {
        for d in 0..3 {
            add(3 * i + d, 3 * j + d, sign * g);
            add(3 * j + d, 3 * i + d, sign * g);
        }
    }
    (m, mag)
}

/// Verify a lower bound on the global minimum of the joint cost from any multipliers (the SDP's,
/// or any other): `None` when they are not finite or do not match the problem's size
/// (`2n` matrices `Lambda_a`, `n (n - 1) / 2` couplings in the order of
/// [`coupling_pairs`]).
///
/// ```
/// use rotavg::certify::simultaneous::verify_simultaneous_bound;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// use nalgebra::Matrix3;
/// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
/// let p = MultipleProblem::new(3, vec![e(0, 1), e(1, 2)])?;
/// // zero multipliers: the bound is 3n (lambda_min(Q_R) + lambda_min(Q_C)) = 0 for PSD Laplacians
/// let b = verify_simultaneous_bound(&p, &p, &[Matrix3::zeros(); 6], &[0.0; 3]).unwrap();
/// assert!(b.lower_bound <= 0.0 && b.lower_bound > -1e-9);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn verify_simultaneous_bound(
    right: &MultipleProblem,
    left: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    couplings: &[f64],
) -> Option<SimultaneousBound> {
    let n = right.num_rotations();
    let finite = |m: &Matrix3<f64>| m.iter().all(|x| x.is_finite());
    if left.num_rotations() != n
        || lambdas.len() != 2 * n
        || couplings.len() != n * (n - 1) / 2
        || !lambdas.iter().all(finite)
        || !couplings.iter().all(|g| g.is_finite())
    {
        return None;
    }
    let dim = 3.0 * n as f64;
    let (mut lam, mut verified, mut slack) = (f64::INFINITY, f64::INFINITY, 0.0);
    // one side at a time (two dense matrices alive, not four); eigenvalues only
    for (p, side, sign) in [(right, &lambdas[..n], -0.5), (left, &lambdas[n..], 0.5)] {
        let (m, mag) = certificate_matrix(p, side, couplings, sign);
        let l = m.symmetric_eigenvalues().min();
        let v = l - 10.0 * dim * f64::EPSILON * mag.norm();
        lam = lam.min(l);
        verified = verified.min(v);
        slack += v.min(0.0);
    }
    let (mut trace, mut trace_abs) = (0.0, 0.0);
    for l in lambdas {
        trace += l.trace();
        trace_abs += l[(0, 0)].abs() + l[(1, 1)].abs() + l[(2, 2)].abs();
    }
    // the joint cost is tr(Q_R X_R) + tr(Q_C X_C) minus each graph's data defect
    // sum w (3 - ||R_ij||_F^2) (measurements orthogonal only to the validation tolerance, [D4])
    let defect = data_defect(right) + data_defect(left);
    let lb = trace + dim * slack - 2.0 * dim * f64::EPSILON * trace_abs - defect;
    lb.is_finite().then_some(SimultaneousBound {
        lower_bound: lb,
        min_eigenvalue: lam,
        verified_min_eigenvalue: verified,
    })
}

/// One rung that ran: its verified bound (`None`: nothing proved) and how it is reported.
struct Run {
    rung: Rung,
    method: BoundMethod,
    predicted: Prediction,
    bound: Option<SimultaneousBound>,
    seconds: f64,
    note: String,
}

/// The best verified bound of a rung so far, and its note.
struct Best {
    lower_bound: f64,
    method: BoundMethod,
    verified_min_eigenvalue: f64,
    note: String,
}

/// The climb of [`certify_simultaneous`]: the estimate's cost, the tolerance's gap at it, and
/// the best bound proved.
struct Climbed {
    cost: f64,
    allowed_gap: f64,
    best: Option<Best>,
}

impl Climbed {
    fn sufficient(&self, lb: f64) -> bool {
        self.cost - lb <= self.allowed_gap
    }

    fn certified(&self) -> bool {
        self.best
            .as_ref()
            .is_some_and(|b| self.sufficient(b.lower_bound))
    }

    /// Record a rung in `details` and keep its bound when it is the best.
    fn record(&mut self, details: &mut CertifyDetails, run: Run) {
        let lb = run
            .bound
            .map(|b| nonnegative_bound_at_most(b.lower_bound, self.cost));
        details.record_rung(
            MethodRun {
                method: run.method,
                lower_bound: lb,
                seconds: run.seconds,
                note: run.note.clone(),
            },
            run.rung,
            Some(run.predicted),
            lb.is_some_and(|l| self.sufficient(l)),
        );
        if let (Some(lb), Some(b)) = (lb, run.bound)
            && self.best.as_ref().is_none_or(|x| lb > x.lower_bound)
        {
            self.best = Some(Best {
                lower_bound: lb,
                method: run.method,
                verified_min_eigenvalue: b.verified_min_eigenvalue,
                note: run.note,
            });
        }
    }
}

/// Certify a joint estimate `(R, S)` of the simultaneous problem (right graph `right`, left
/// graph `left`, the same `n` nodes). Two rungs, each predicted and refused over the budget:
/// the dual certificate at the estimate `[H15]` (modes `auto` and `dual`; cheap, dense
/// `3n x 3n`), then, when it is not sufficient, the SDP `[H14]` (modes `auto` and `sdp`); any
/// other mode is refused as not applicable and the verdict is `inconclusive`. The verdict uses
/// the best verified bound. The estimate is never changed; a cheaper rounding of the SDP is
/// returned as the improvement (not polished: the joint local solver lives in
/// [`crate::pipeline::simultaneous`], which polishes it).
pub fn certify_simultaneous(
    right: &MultipleProblem,
    left: &MultipleProblem,
    rotations: &[Rotation],
    s: &Rotation,
    settings: &CertifySettings,
) -> Result<Certification<JointRotations>> {
    settings.validate()?;
    let start = Instant::now();
    let n = right.num_rotations();
    if rotations.len() != n || left.num_rotations() != n {
        return Err(Error::InvalidSettings {
            name: "estimate".into(),
            reason: format!(
                "{} rotations for two view graphs of {} and {} nodes",
                rotations.len(),
                n,
                left.num_rotations()
            ),
        });
    }
    let cost = joint_cost(right, left, rotations, s);
    let tolerance = settings
        .tolerance
        .resolve(right.min_weight().min(left.min_weight()));
    let mut details = CertifyDetails {
        mode: settings.mode,
        ..Default::default()
    };
    let refuse = |details: &mut CertifyDetails, rung, predicted, refusal: Refusal| {
        let why = refusal.to_string();
        details.skipped_reason = Some(why.clone());
        details.ladder.push(Attempt {
            rung,
            point: Point::Given,
            predicted,
            outcome: Outcome::Refused(refusal),
            seconds: start.elapsed().as_secs_f64(),
        });
        why
    };
    let mut climb = Climbed {
        cost,
        allowed_gap: tolerance.allowed_gap(cost),
        best: None,
    };
    // the explanation when no rung proves a bound: the last refusal or failure
    let mut why = String::new();
    let mut improvement = None;
    let (dual, sdp) = match settings.mode {
        CertifyMode::Auto => (true, true),
        CertifyMode::Dual => (true, false),
        CertifyMode::Sdp => (false, true),
        other => {
            why = refuse(
                &mut details,
                Rung::Sdp,
                None,
                Refusal::NotApplicable {
                    reason: format!(
                        "the simultaneous problem is certified by its dual certificate and its SDP (modes auto, dual and sdp), not {}",
                        other.name()
                    ),
                },
            );
            (false, false)
        }
    };
    if dual {
        let predicted = dual::predict_multipliers_at_estimate(n);
        match settings.budget.prediction_fits(&predicted, 0.0) {
            Err(reason) => {
                why = refuse(
                    &mut details,
                    Rung::SimultaneousDual,
                    Some(predicted),
                    Refusal::OverBudget {
                        reason: format!("dual certificate not run: {reason}"),
                    },
                );
            }
            Ok(()) => {
                let t = Instant::now();
                let at = dual::EstimateMultipliers::new(right, left, rotations, s);
                let mut bound = at.as_ref().and_then(|at| {
                    let g = at.least_norm.clone();
                    verify_simultaneous_bound(right, left, &at.lambdas(&g), &g)
                });
                let mut note = match bound {
                    Some(b) => format!(
                        "multipliers at the estimate (couplings of least norm) verified, lambda_min(Z) >= {:.3e}",
                        b.verified_min_eigenvalue
                    ),
                    None => "multipliers at the estimate not finite (singular coupling system)"
                        .to_string(),
                };
                if let Some(at) = &at
                    && !bound.is_some_and(|b| climb.sufficient(b.lower_bound))
                {
                    // other couplings complementary slackness allows [H15]: a cutting-plane
                    // search, its rounds within half the time left, its cuts within the memory
                    // the rung's prediction leaves
                    let target = 0.25 * climb.allowed_gap / (3 * n) as f64;
                    let seconds = settings
                        .budget
                        .max_seconds
                        .map(|m| 0.5 * (m - start.elapsed().as_secs_f64()));
                    let cut_bytes =
                        (settings.budget.max_memory_bytes as f64 - predicted.bytes).max(0.0);
                    match search::search_couplings(right, left, at, target, seconds, cut_bytes) {
                        None => {
                            note = format!(
                                "{note}; no search over the couplings: one round is predicted past half the time left"
                            );
                        }
                        Some(found) => {
                            let searched = verify_simultaneous_bound(
                                right,
                                left,
                                &found.lambdas,
                                &found.couplings,
                            );
                            if let Some(b) = searched
                                && bound.is_none_or(|x| b.lower_bound > x.lower_bound)
                            {
                                note = format!(
                                    "multipliers at the estimate, couplings from a search ({} rounds, {} cuts) from the least-norm ones, verified, lambda_min(Z) >= {:.3e}",
                                    found.rounds, found.cuts, b.verified_min_eigenvalue
                                );
                                bound = Some(b);
                            } else {
                                note = format!(
                                    "{note}; a search over the couplings ({} rounds, {} cuts) found no better bound",
                                    found.rounds, found.cuts
                                );
                            }
                        }
                    }
                }
                why = note.clone();
                climb.record(
                    &mut details,
                    Run {
                        rung: Rung::SimultaneousDual,
                        method: BoundMethod::Dual,
                        predicted,
                        bound,
                        seconds: t.elapsed().as_secs_f64(),
                        note,
                    },
                );
            }
        }
    }
    if sdp && !climb.certified() {
        let p = predict_relax_simultaneous(n);
        let predicted = Prediction {
            seconds: p.seconds,
            bytes: p.bytes,
        };
        let elapsed = start.elapsed().as_secs_f64();
        if let Err(reason) = settings.budget.prediction_fits(&predicted, elapsed) {
            why = refuse(
                &mut details,
                Rung::Sdp,
                Some(predicted),
                Refusal::OverBudget {
                    reason: format!("SDP not run: {reason} (two dense cones of size {})", 3 * n),
                },
            );
        } else {
            let relaxation = relax_simultaneous(right, left, &settings.sdp_within_budget(elapsed))?;
            let bound =
                verify_simultaneous_bound(right, left, &relaxation.lambdas, &relaxation.couplings);
            let top = &relaxation.x_top_eigenvalues;
            details.sdp = Some(SdpSummary {
                status: relaxation.status,
                iterations: relaxation.iterations,
                seconds: relaxation.seconds,
                eigenvalue_ratio: match (top.get(2), top.get(3)) {
                    (Some(&l3), Some(&l4)) if l3 > 0.0 => l4.max(0.0) / l3,
                    _ => f64::NAN,
                },
                rounded_cost: Some(relaxation.rounded.cost),
                polished_cost: None,
            });
            let note = match bound {
                Some(b) => format!(
                    "SDP of two cones of size {} ({:?}, {} iterations): multipliers verified, lambda_min(Z) >= {:.3e}",
                    3 * n,
                    relaxation.status,
                    relaxation.iterations,
                    b.verified_min_eigenvalue
                ),
                None => format!("SDP ({:?}): multipliers not finite", relaxation.status),
            };
            let seconds = relaxation.seconds;
            improvement = (relaxation.rounded.cost < cost).then_some(relaxation.rounded);
            if let Some(r) = &improvement {
                details.improvement = Some(Improvement {
                    source: ImprovementSource::SdpRounding,
                    cost: r.cost,
                });
            }
            why = note.clone();
            climb.record(
                &mut details,
                Run {
                    rung: Rung::Sdp,
                    method: BoundMethod::Sdp,
                    predicted,
                    bound,
                    seconds,
                    note,
                },
            );
        }
    }
    let (lb, method, lam) = match climb.best {
        Some(b) => {
            why = b.note;
            (
                Some(b.lower_bound),
                b.method,
                Some(b.verified_min_eigenvalue),
            )
        }
        None => (None, BoundMethod::Sdp, None),
    };
    let mut certificate = Certificate::from_bounds(
        cost,
        lb,
        method,
        lam,
        tolerance,
        why,
        start.elapsed().as_secs_f64(),
    );
    certificate.verified_min_eigenvalue = lam;
    details.seconds = start.elapsed().as_secs_f64();
    Ok(Certification {
        certificate,
        details,
        improvement,
    })
}
