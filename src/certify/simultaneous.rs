//! Certificates of the simultaneous problem `[H12]` (`paper-notes/conjugate.md`): the hand-eye
//! rotation `S` and the absolutes `R_i` of two view graphs, jointly. One rung: the SDP of
//! [`crate::relax::simultaneous`], predicted from its cliques and refused over the budget, its
//! multipliers verified here by an independent dense eigenvalue computation.
//!
//! For any symmetric `Lambda_a` and any `Gamma_i`, every feasible `X` (`X_aa = I`, the coupling
//! blocks equal, `tr X = 6n`) has
//! `tr(Q X) = tr(M X) + sum_a tr(Lambda_a) >= sum_a tr(Lambda_a) + 6n min(lambda_min(M), 0)`,
//! `M = Q - blkdiag(Lambda) - sum_i E(Gamma_i)` (the coupling terms vanish on feasible `X`), and
//! every joint point `(R, S)` gives such an `X`: the bound holds for the global minimum of `J`.

use super::certificate::{BoundMethod, Certificate, nonnegative_bound_at_most};
use super::certification::{Certification, CertifyDetails, Improvement, ImprovementSource};
use super::certification::{MethodRun, SdpSummary};
use super::ladder::{Attempt, Outcome, Point, Prediction, Refusal, Rung};
use super::settings::{CertifyMode, CertifySettings};
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian_triplets;
use crate::relax::simultaneous::{
    JointRotations, joint_cost, predict_relax_simultaneous, relax_simultaneous,
};
use crate::so3::Rotation;
use nalgebra::{DMatrix, Matrix3, SymmetricEigen};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A lower bound on the global minimum of the joint cost, verified from multipliers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimultaneousBound {
    /// `sum_a tr(Lambda_a) + 6n min(verified_min_eigenvalue, 0) - rounding`.
    pub lower_bound: f64,
    /// `lambda_min(M)` from nalgebra's dense symmetric eigen-decomposition.
    pub min_eigenvalue: f64,
    /// Proven lower bound on `lambda_min` of the exact `M`: `min_eigenvalue` minus
    /// `10 (6n) eps ||(|Q| + |blkdiag Lambda| + sum |E(Gamma_i)|)||_F`, which covers the
    /// rounding of forming `M` (at most four terms per entry) and the eigen solver's backward
    /// error.
    pub verified_min_eigenvalue: f64,
}

/// The dense `M = Q - blkdiag(Lambda) - sum_i E(Gamma_i)` and the entrywise magnitudes of its
/// terms.
fn certificate_matrix(
    right: &MultipleProblem,
    left: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    gammas: &[Matrix3<f64>],
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = right.num_rotations();
    let dim = 6 * n;
    let mut m = DMatrix::zeros(dim, dim);
    let mut mag = DMatrix::zeros(dim, dim);
    let mut add = |r: usize, c: usize, v: f64| {
        m[(r, c)] += v;
        mag[(r, c)] += v.abs();
    };
    for (offset, p) in [(0, right), (3 * n, left)] {
        for t in connection_laplacian_triplets(p) {
            add(offset + t.row, offset + t.col, t.val);
        }
    }
    for (a, l) in lambdas.iter().enumerate() {
        for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
            add(3 * a + r, 3 * a + c, -l[(r, c)]);
        }
    }
    for (k, g) in gammas.iter().enumerate() {
        let i = k + 1;
        for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
            let v = g[(r, c)];
            let (ci, ri, c0) = (3 * (n + i) + r, 3 * i + c, 3 * n + r);
            add(ci, ri, -v);
            add(ri, ci, -v);
            add(c0, c, v);
            add(c, c0, v);
        }
    }
    (m, mag)
}

/// Verify a lower bound on the global minimum of the joint cost from any multipliers (the SDP's,
/// or any other): `None` when they are not finite or do not match the problem's size.
///
/// ```
/// use rotavg::certify::simultaneous::verify_simultaneous_bound;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// use nalgebra::Matrix3;
/// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
/// let p = MultipleProblem::new(3, vec![e(0, 1), e(1, 2)])?;
/// // zero multipliers: the bound is 6n lambda_min(Q) = 0 for a PSD Laplacian
/// let b = verify_simultaneous_bound(&p, &p, &[Matrix3::zeros(); 6], &[Matrix3::zeros(); 2]).unwrap();
/// assert!(b.lower_bound <= 0.0 && b.lower_bound > -1e-9);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn verify_simultaneous_bound(
    right: &MultipleProblem,
    left: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    gammas: &[Matrix3<f64>],
) -> Option<SimultaneousBound> {
    let n = right.num_rotations();
    let finite = |m: &Matrix3<f64>| m.iter().all(|x| x.is_finite());
    if left.num_rotations() != n
        || lambdas.len() != 2 * n
        || gammas.len() + 1 != n
        || !lambdas.iter().chain(gammas).all(finite)
    {
        return None;
    }
    let (m, mag) = certificate_matrix(right, left, lambdas, gammas);
    let lam = SymmetricEigen::new(m).eigenvalues.min();
    let dim = 6.0 * n as f64;
    let eigen_margin = 10.0 * dim * f64::EPSILON * mag.norm();
    let verified = lam - eigen_margin;
    let (mut trace, mut trace_abs) = (0.0, 0.0);
    for l in lambdas {
        trace += l.trace();
        trace_abs += l[(0, 0)].abs() + l[(1, 1)].abs() + l[(2, 2)].abs();
    }
    let lb = trace + dim * verified.min(0.0) - dim * f64::EPSILON * trace_abs;
    lb.is_finite().then_some(SimultaneousBound {
        lower_bound: lb,
        min_eigenvalue: lam,
        verified_min_eigenvalue: verified,
    })
}

/// Certify a joint estimate `(R, S)` of the simultaneous problem (right graph `right`, left
/// graph `left`, the same `n` nodes): the SDP rung of modes `auto` and `sdp` (any other mode is
/// refused as not applicable and the verdict is `inconclusive`). The estimate is never changed;
/// a cheaper rounding of the SDP is returned as the improvement (not polished: the joint local
/// solver lives in [`crate::pipeline::simultaneous`], which polishes it).
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
    let refused = |details: &mut CertifyDetails, predicted, refusal: Refusal| {
        let why = refusal.to_string();
        details.skipped_reason = Some(why.clone());
        details.ladder.push(Attempt {
            rung: Rung::Sdp,
            point: Point::Given,
            predicted,
            outcome: Outcome::Refused(refusal),
            seconds: start.elapsed().as_secs_f64(),
        });
        why
    };
    let finish = |details: CertifyDetails, lb, lam, why: String, improvement| {
        let mut certificate = Certificate::from_bounds(
            cost,
            lb,
            BoundMethod::Sdp,
            lam,
            tolerance,
            why,
            start.elapsed().as_secs_f64(),
        );
        certificate.verified_min_eigenvalue = lam;
        let mut details = details;
        details.seconds = start.elapsed().as_secs_f64();
        Certification {
            certificate,
            details,
            improvement,
        }
    };
    if !matches!(settings.mode, CertifyMode::Auto | CertifyMode::Sdp) {
        let why = refused(
            &mut details,
            None,
            Refusal::NotApplicable {
                reason: format!(
                    "the simultaneous problem is certified by its SDP (modes auto and sdp), not {}",
                    settings.mode.name()
                ),
            },
        );
        return Ok(finish(details, None, None, why, None));
    }
    let p = predict_relax_simultaneous(right, left)?;
    let predicted = Prediction {
        seconds: p.seconds,
        bytes: p.bytes,
    };
    if let Err(reason) = settings.budget.prediction_fits(&predicted, 0.0) {
        let reason = format!(
            "SDP not run: {reason} (predicted from {} cliques of up to {} nodes)",
            p.cliques, p.largest_clique
        );
        let why = refused(
            &mut details,
            Some(predicted),
            Refusal::OverBudget { reason },
        );
        return Ok(finish(details, None, None, why, None));
    }
    let mut sdp_settings = settings.sdp.clone();
    if let Some(limit) = settings.budget.max_seconds {
        let t = sdp_settings.time_limit_seconds.unwrap_or(limit).min(limit);
        sdp_settings.time_limit_seconds = Some(t.max(1e-3));
    }
    let relaxation = relax_simultaneous(right, left, &sdp_settings)?;
    let bound = verify_simultaneous_bound(right, left, &relaxation.lambdas, &relaxation.gammas);
    let lb = bound.map(|b| nonnegative_bound_at_most(b.lower_bound, cost));
    let lam = bound.map(|b| b.verified_min_eigenvalue);
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
            "SDP of size {} ({:?}, {} iterations): multipliers verified, lambda_min(M) >= {:.3e}",
            6 * n,
            relaxation.status,
            relaxation.iterations,
            b.verified_min_eigenvalue
        ),
        None => format!("SDP ({:?}): multipliers not finite", relaxation.status),
    };
    let improvement = (relaxation.rounded.cost < cost).then(|| relaxation.rounded.clone());
    if let Some(r) = &improvement {
        details.improvement = Some(Improvement {
            source: ImprovementSource::SdpRounding,
            cost: r.cost,
        });
    }
    let sufficient = lb.is_some_and(|l| cost - l <= tolerance.allowed_gap(cost));
    details.record(
        MethodRun {
            method: BoundMethod::Sdp,
            lower_bound: lb,
            seconds: relaxation.seconds,
            note: note.clone(),
        },
        sufficient,
    );
    Ok(finish(details, lb, lam, note, improvement))
}
