//! The randomized bound `[D16]`: when no deterministic proof fits the budget (random expander
//! graphs of 10^5 nodes, whose factors fill), a Monte Carlo lower bound from products with the
//! certificate matrix only.
//!
//! The randomized Chebyshev test ([`ChebyshevTest`]) is run on `A = S + (beta / n) Y Y^T`
//! (the gauge directions `Y = [R_1; ...; R_n]` lifted to the middle of the spectrum). A pass
//! says `lambda_min(A) > mu`, hence `x^T S x >= mu ||x||^2` for every `x` orthogonal to `Y`,
//! unless an event of probability at most `p` over the test's random vectors occurred. With
//! the proven gauge terms of `[D15]` (`rho >= ||S Y||`, `Y^T S Y >= -h I`) every `X` in
//! `O(3)^n` has `f(X) >= sum tr(Lambda_i) - (rho^2 / mu + h) 3n / lambda_min(Y^T Y)`.
//! The result is reported beside the `inconclusive` verdict, never as its proof.

use super::check::Check;
use super::multipliers::{GaugeTerms, bound_with_deficit, gauge_column, gauge_terms};
use super::verified::{ComplementEstimate, RandomizedBound};
use crate::certify::budget::PREDICTED_FLOP_RATE;
use crate::certify::log::{Outcome, Prediction};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::RandomizedSettings;
use crate::error::Result;
use crate::linalg::cholesky::gershgorin_upper_bound;
use crate::linalg::compensated::Accumulator;
use crate::linalg::{ChebyshevTest, UNIT_ROUNDOFF, gamma, symmetric_matvec};
use crate::linalg::{Extreme, LanczosSettings};
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use faer::sparse::SparseColMatRef;
use nalgebra::Matrix3;
use std::time::Instant;

/// The randomized test `[D16]` as the last fallback of a verification: when a check was kept
/// out by the budget and nothing was proved, the estimate of `lambda_min(S)` on the complement
/// of the gauge directions and the randomized bound are attached to the unclaimed bound
/// (never a proof: the outcome is `estimated`).
#[derive(Default)]
pub(super) struct RandomizedCheck {
    done: bool,
}

/// Floating-point operations of the complement estimate (its Lanczos run is kept near this).
const COMPLEMENT_FLOPS: f64 = 1e9;

/// The randomized test's predicted seconds.
const RANDOMIZED_SECONDS: f64 = COMPLEMENT_FLOPS / PREDICTED_FLOP_RATE;

impl<'a> Rung<Check<'a>> for RandomizedCheck {
    fn proof(&self) -> Proof {
        Proof::Randomized
    }

    fn plan(&mut self, cx: &Check<'a>) -> Result<Plan> {
        Ok(
            // disabled, the Lanczos estimate the test starts from is not run either: it is
            // never a bound (the rig's rungs, which keep only bounds, spent 2.2 s in it on a
            // 20,000-image coupled graph, 2026-12-02)
            if self.done
                || !cx.settings.dual.randomized.enabled
                || cx.best.is_some()
                || cx.rotations.is_none()
                || cx.cut_by_not_critical(RANDOMIZED_SECONDS).is_some()
            {
                Plan::Done
            } else if cx.unclaimed.is_none() {
                // after Gershgorin's check, and only when it was left unclaimed
                Plan::Wait
            } else {
                Plan::Fallback(Prediction::new(RANDOMIZED_SECONDS, 0.0))
            },
        )
    }

    fn attempt(&mut self, cx: &mut Check<'a>) -> Result<Found> {
        self.done = true;
        let Some(rotations) = cx.rotations else {
            return Ok(Found::failed("the estimate's rotations are not known"));
        };
        let (complement, randomized) = over_budget_estimates(cx, rotations);
        let outcome = match randomized.as_ref().and_then(|r| r.lower_bound) {
            Some(lower_bound) => Outcome::Estimated {
                lower_bound,
                failure_probability: cx.settings.dual.randomized.failure_probability,
            },
            None => Outcome::Failed {
                reason: randomized.as_ref().map_or_else(
                    || "not run (no converged positive estimate to test)".into(),
                    |r| r.to_string(),
                ),
            },
        };
        if let Some(b) = cx.unclaimed.as_mut() {
            b.min_eigenvalue_estimate =
                Some(complement.value.min(complement.gauge_rayleigh_quotient));
            b.estimate_residual = Some(complement.residual);
            b.lanczos_iterations += complement.iterations;
            b.complement_estimate = Some(complement);
            b.randomized = randomized;
        }
        Ok(Found::new(outcome, ""))
    }
}

/// When no proof fits the budget: the Lanczos estimate of `lambda_min(S)` on the complement of
/// the gauge directions `[D7]` (its cost kept near 1e9 flops: about `5 m^2 n / 2` for a subspace
/// of `m` vectors with full reorthogonalisation) and the randomized test `[D16]` it plans; both
/// are labelled estimates, never proofs.
pub(super) fn over_budget_estimates(
    cx: &Check<'_>,
    rotations: &[Rotation],
) -> (ComplementEstimate, Option<RandomizedBound>) {
    let n3 = cx.dim();
    let mut lz = cx.settings.dual.lanczos;
    let affordable = (1e9 / n3.max(1) as f64).sqrt() as usize;
    lz.max_iterations = lz.max_iterations.min(n3.max(1)).min(affordable.max(20));
    let c = complement_smallest(cx.s().as_ref(), rotations, cx.norm(), &lz);
    let randomized = randomized_bound(
        cx.problem,
        rotations,
        cx.lambdas,
        cx.s().as_ref(),
        cx.norm(),
        cx.terms,
        &c,
        &cx.settings.dual.randomized,
        cx.deadline.left().map(|l| l.max(0.0)),
    );
    (c, randomized)
}

/// [`ComplementEstimate`]: Lanczos on `P S P` with `P = I - Y Y^T / n` (the gauge directions
/// `Y = [R_1; ...; R_n]`, whose columns are orthogonal with norm `sqrt(n)` for exact rotations;
/// they are orthonormalised here, so nearly orthogonal rotations are fine too).
pub(super) fn complement_smallest(
    s: faer::sparse::SparseColMatRef<'_, usize, f64>,
    rotations: &[Rotation],
    scale: f64,
    settings: &LanczosSettings,
) -> ComplementEstimate {
    let n3 = s.nrows();
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(3);
    let mut ysy = Matrix3::<f64>::zeros();
    let mut sy = vec![0.0f64; n3];
    for a in 0..3 {
        let mut y = gauge_column(rotations, a);
        crate::linalg::cholesky::sparse_matvec(s, &y, &mut sy);
        for b in 0..3 {
            ysy[(b, a)] = rotations
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    (0..3)
                        .map(|row| r.matrix()[(row, b)] * sy[3 * i + row])
                        .sum::<f64>()
                })
                .sum();
        }
        for q in &basis {
            let c: f64 = q.iter().zip(&y).map(|(u, v)| u * v).sum();
            y.iter_mut().zip(q).for_each(|(v, u)| *v -= c * u);
        }
        let norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm > 0.0 {
            y.iter_mut().for_each(|v| *v /= norm);
            basis.push(y);
        }
    }
    let n = rotations.len().max(1) as f64;
    let gauge_rayleigh_quotient = (0.5 * (ysy + ysy.transpose()))
        .symmetric_eigenvalues()
        .min()
        / n;
    let project = |x: &mut [f64]| {
        for q in &basis {
            let c: f64 = q.iter().zip(x.iter()).map(|(u, v)| u * v).sum();
            x.iter_mut().zip(q).for_each(|(v, u)| *v -= c * u);
        }
    };
    let mut px = vec![0.0f64; n3];
    let e = crate::linalg::lanczos(
        n3,
        |x, y| {
            px.copy_from_slice(x);
            project(&mut px);
            crate::linalg::symmetric_matvec(s, &px, y);
            project(y);
        },
        Extreme::Smallest,
        1,
        scale,
        &LanczosSettings {
            block_size: 1,
            ..*settings
        },
        &basis,
        None,
    );
    ComplementEstimate {
        value: e.values.first().copied().unwrap_or(f64::NAN),
        residual: e.residuals.first().copied().unwrap_or(f64::NAN),
        iterations: e.subspace_dim,
        gauge_rayleigh_quotient,
        stop: e.stop,
    }
}

/// The randomized bound `[D16]` of `S` (`s`, as stored, with `norm = ||S||_inf` and `terms`
/// rounded operations per entry) at `rotations` with multipliers `lambdas`, from the Lanczos
/// estimate on the complement (the test claims a quarter of it). `None` when the test is
/// disabled or cannot be planned (no positive estimate with a Ritz residual at most half of it,
/// rotations far from orthogonal, more
/// products than `settings.max_matvecs`, or a predicted time over `max_seconds`).
#[allow(clippy::too_many_arguments)]
pub(super) fn randomized_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    s: SparseColMatRef<'_, usize, f64>,
    norm: f64,
    terms: usize,
    estimate: &ComplementEstimate,
    settings: &RandomizedSettings,
    max_seconds: Option<f64>,
) -> Option<RandomizedBound> {
    let est = estimate.value;
    // an estimate whose Ritz residual is not well below it (an unconverged Lanczos run) is no
    // guide to the interval: the test would fail (soundly) after all its products
    if !(settings.enabled && est.is_finite() && est > 0.0 && estimate.residual <= 0.5 * est) {
        return None;
    }
    let start = Instant::now();
    let u = UNIT_ROUNDOFF;
    let n = rotations.len();
    let n3 = s.nrows();
    if n == 0 || n3 != 3 * n {
        return None;
    }
    let y: Vec<Vec<f64>> = (0..3).map(|a| gauge_column(rotations, a)).collect();
    let (g_min, g_max) = gram_bounds(&y)?;
    if !(g_min > 0.5 * n as f64 && g_max.is_finite()) {
        return None;
    }
    // the claim on S_fl, and on the exact S after the forming error [D6](b)
    let claim = 0.25 * est;
    let mu = claim - 2.0 * gamma(terms + 1) * norm;
    if mu.is_nan() || mu <= 0.0 {
        return None;
    }
    let a = Lifted::new(s, &y, norm, g_max, n);
    let test = ChebyshevTest::plan(
        n3,
        0.5 * est,
        a.upper(),
        claim,
        settings.failure_probability,
        a.per_norm(),
        settings.max_matvecs,
    )?;
    // the products' predicted time against the time budget (the flop rate of the
    // factorisations' prediction: about 2 nnz(S) + 100 x 3n flops per product)
    let flops = (2 * s.col_ptr()[n3] + 100 * n3) as f64 * (test.degree * test.vectors) as f64;
    if max_seconds.is_some_and(|limit| flops / PREDICTED_FLOP_RATE > limit) {
        return None;
    }
    crate::progress::phase(crate::progress::Phase::Certify, || {
        format!(
            "randomized Chebyshev test [D16] ({} vectors of degree {})",
            test.vectors, test.degree
        )
    });
    let seed = settings.resolve_seed();
    let outcome = test.run(n3, |x, z| a.apply(x, z), seed);
    let GaugeTerms { rho, h, .. } = gauge_terms(problem, rotations, lambdas);
    let deficit = (rho * rho / mu + h) * (3.0 * n as f64 / g_min) * (1.0 + 8.0 * u);
    let lower_bound = outcome
        .passed
        .then(|| bound_with_deficit(problem, lambdas, deficit))
        .filter(|b| b.is_finite());
    Some(RandomizedBound {
        lower_bound,
        seed,
        complement_bound: mu,
        rho,
        h,
        deficit,
        test,
        outcome,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// `G = Y^T Y` in double-double, and bounds `(lower, upper)` on its extreme eigenvalues.
fn gram_bounds(y: &[Vec<f64>]) -> Option<(f64, f64)> {
    let u = UNIT_ROUNDOFF;
    let mut gm = Matrix3::<f64>::zeros();
    let mut g_error = 0.0f64;
    for a in 0..3 {
        for b in 0..3 {
            let mut acc = Accumulator::default();
            for (p, q) in y.get(a)?.iter().zip(y.get(b)?) {
                acc.add_product(*p, *q);
            }
            gm[(a, b)] = acc.value();
            g_error += acc.bound() * acc.bound();
        }
    }
    let g_slack = (g_error.sqrt() + 16.0 * u * gm.norm()) * (1.0 + 4.0 * u);
    let eig = (0.5 * (gm + gm.transpose())).symmetric_eigenvalues();
    Some((eig.min() - g_slack, eig.max() + g_slack))
}

/// The tested operator `A = S_fl + gb Y Y^T` (`[D16]`) and what bounds its spectrum and the
/// rounding of its products: `lambda_max(S) <= s_upper` (Gershgorin), `lambda_max(Y^T Y) <=
/// g_max`, `|| |S| ||_2 <= s_abs`, `||Y||_F <= y_f`, `gamma(p)` and `gamma(5)`.
struct Lifted<'a> {
    s: SparseColMatRef<'a, usize, f64>,
    y: &'a [Vec<f64>],
    gb: f64,
    s_upper: f64,
    g_max: f64,
    s_abs: f64,
    y_f: f64,
    gp: f64,
    g5: f64,
}

impl<'a> Lifted<'a> {
    /// `A` for `S` of norm `norm` (`||S||_inf`) on `n` nodes and `lambda_max(Y^T Y) <= g_max`,
    /// with the lift `gb = lambda_max(S) / (2n)` (the gauge directions to the middle of the
    /// spectrum).
    fn new(
        s: SparseColMatRef<'a, usize, f64>,
        y: &'a [Vec<f64>],
        norm: f64,
        g_max: f64,
        n: usize,
    ) -> Self {
        let (s_upper, row_nnz) = gershgorin_upper_bound(s);
        // ||Y||_F <= sqrt(3 lambda_max(G)); || |S| ||_2 <= ||S||_inf (computed with gamma(p))
        Lifted {
            s,
            y,
            gb: 0.5 * s_upper / n as f64,
            s_upper,
            g_max,
            s_abs: norm * (1.0 + gamma(row_nnz + 1)),
            y_f: (3.0 * g_max).sqrt() * (1.0 + 2.0 * UNIT_ROUNDOFF),
            gp: gamma(row_nnz + 1),
            g5: gamma(5),
        }
    }

    /// An upper bound on `lambda_max(A)`.
    fn upper(&self) -> f64 {
        (self.s_upper + self.gb * self.g_max) * (1.0 + 1e-12)
    }

    /// The rounding error of a product per unit norm of `x`.
    fn per_norm(&self) -> f64 {
        let (gp, g5, s_abs, gb) = (self.gp, self.g5, self.s_abs, self.gb);
        gp * s_abs + g5 * (s_abs * (1.0 + gp) + gb * self.y_f * self.g_max.sqrt()) + 1e-15 * gb
    }

    /// `z = A x` and a bound on its rounding error: the product rounded (gamma(p)), `Y^T x` in
    /// double-double, the combination `z_i = s_i + sum_a y_ai (gb c_a)` as a 4-term sum with
    /// the rounded `gb c_a`.
    fn apply(&self, x: &[f64], z: &mut [f64]) -> f64 {
        let (y, gb, u) = (self.y, self.gb, UNIT_ROUNDOFF);
        symmetric_matvec(self.s, x, z);
        // the three double-double dot products in one pass over x
        let mut acc = [Accumulator::default(); 3];
        for (i, xi) in x.iter().enumerate() {
            acc[0].add_product(y[0][i], *xi);
            acc[1].add_product(y[1][i], *xi);
            acc[2].add_product(y[2][i], *xi);
        }
        let c = acc.map(|a| a.value());
        let dc: f64 = acc.iter().map(|a| a.bound() * a.bound()).sum();
        let cs = [gb * c[0], gb * c[1], gb * c[2]];
        for (i, zi) in z.iter_mut().enumerate() {
            *zi += y[0][i] * cs[0] + y[1][i] * cs[1] + y[2][i] * cs[2];
        }
        let n3 = x.len();
        let xn = x.iter().map(|v| v * v).sum::<f64>().sqrt() * (1.0 + gamma(n3 + 2));
        let cn = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt() * (1.0 + 4.0 * u);
        let (gp, g5, s_abs, y_f) = (self.gp, self.g5, self.s_abs, self.y_f);
        (gp * s_abs * xn + g5 * (s_abs * xn * (1.0 + gp) + gb * y_f * cn) + gb * y_f * dc.sqrt())
            * (1.0 + 1e-10)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::multiple::multipliers::{certificate_matrix, multipliers};
    use crate::linalg::{LanczosStop, inf_norm};
    use crate::multiple::synthetic::SyntheticGraph;
    use crate::so3::Rotation;
    use nalgebra::{DMatrix, Vector3};

    /// `lambda_min(P S P)` by a dense eigendecomposition, `P` the projector onto the
    /// complement of the gauge directions.
    fn dense_complement_min(s: SparseColMatRef<'_, usize, f64>, rotations: &[Rotation]) -> f64 {
        let n3 = s.nrows();
        let mut m = DMatrix::zeros(n3, n3);
        let (cp, ri, v) = (s.col_ptr(), s.row_idx(), s.val());
        for c in 0..n3 {
            for k in cp[c]..cp[c + 1] {
                m[(ri[k], c)] += v[k];
            }
        }
        let y = DMatrix::from_fn(n3, 3, |r, a| rotations[r / 3].matrix()[(r % 3, a)]);
        let gram = (y.transpose() * &y).try_inverse().unwrap();
        let p = DMatrix::identity(n3, n3) - &y * gram * y.transpose();
        let psp = &p * m * &p;
        // P S P: the spectrum of S on the complement plus three zeros whose eigenvectors lie
        // in span(Y) (dropped: the eigenvectors with the largest part in span(Y))
        let e = psp.symmetric_eigen();
        let mut cols: Vec<(f64, f64)> = (0..n3)
            .map(|k| {
                let v = e.eigenvectors.column(k);
                ((y.transpose() * v).norm(), e.eigenvalues[k])
            })
            .collect();
        cols.sort_by(|a, b| b.0.total_cmp(&a.0));
        cols[3..].iter().map(|c| c.1).fold(f64::INFINITY, f64::min)
    }

    fn instance() -> (crate::multiple::MultipleProblem, Vec<Rotation>) {
        SyntheticGraph {
            num_rotations: 30,
            num_edges: 90,
            noise_sigma: 0.05,
            seed: 5,
            ..Default::default()
        }
        .generate()
    }

    fn estimate(value: f64) -> ComplementEstimate {
        ComplementEstimate {
            value,
            residual: 0.0,
            iterations: 0,
            gauge_rayleigh_quotient: 0.0,
            stop: LanczosStop::Converged {
                residual: 0.0,
                threshold: 0.0,
            },
        }
    }

    /// The test at `rs` told the complement's smallest eigenvalue is about `est` (a value, or
    /// the dense truth when `None`), with `seed`; and the dense truth.
    fn run_at(
        p: &crate::multiple::MultipleProblem,
        rs: &[Rotation],
        est: Option<f64>,
        seed: u64,
    ) -> (Option<RandomizedBound>, f64) {
        let lambdas = multipliers(p, rs).unwrap();
        let s = certificate_matrix(p, &lambdas).unwrap();
        let truth = dense_complement_min(s.as_ref(), rs);
        let settings = RandomizedSettings {
            seed: Some(seed),
            ..Default::default()
        };
        let r = randomized_bound(
            p,
            rs,
            &lambdas,
            s.as_ref(),
            inf_norm(s.as_ref()),
            20,
            &estimate(est.unwrap_or(truth)),
            &settings,
            None,
        );
        (r, truth)
    }

    /// Soundness: at rotations where `S` has a clearly negative eigenvalue on the complement
    /// of the gauge directions (one node turned by 2.5 rad), a test told that the smallest
    /// eigenvalue there is about 1 (an inflated estimate, so that it runs) never passes.
    #[test]
    fn never_passes_on_an_indefinite_certificate_matrix() {
        let (p, gt) = instance();
        let mut rs = gt.clone();
        rs[7] = Rotation::from_scaled_axis(Vector3::new(2.5, 0.0, 0.0)) * rs[7];
        for seed in 0..10 {
            let (r, truth) = run_at(&p, &rs, Some(1.0), seed);
            assert!(truth < -0.1, "the test wants an indefinite S: {truth}");
            let r = r.expect("the test runs");
            // refused by the signal itself (the eigenvector's component grew far past the
            // threshold), not only by rounding or planning
            assert!(
                r.lower_bound.is_none() && !r.outcome.passed && r.outcome.log_margin < -5.0,
                "seed {seed}: {r}"
            );
        }
    }

    /// At a critical point with a clear gap the test passes, claims no more than the dense
    /// smallest eigenvalue on the complement, and its bound lies below the cost.
    #[test]
    fn passes_at_a_critical_point_and_claims_no_more_than_the_truth() {
        let (p, gt) = instance();
        let sol = crate::multiple::solve_multiple(
            &p,
            &crate::multiple::MultipleSettings {
                init: crate::multiple::Initialisation::Given(gt),
                gradient_tolerance: 1e-14,
                ..Default::default()
            },
        )
        .unwrap();
        let rs = sol.rotations;
        let (r, truth) = run_at(&p, &rs, None, 1);
        assert!(truth > 0.1, "{truth}");
        let r = r.expect("the test runs");
        assert!(r.outcome.passed, "{r}");
        assert!(
            r.complement_bound <= truth && r.complement_bound > 0.2 * truth,
            "{r}"
        );
        let cost = p.chordal_cost(&rs);
        let lb = r.lower_bound.unwrap();
        assert!(
            lb <= cost && cost - lb < 1e-9 * cost.max(1.0),
            "{lb} against {cost}"
        );
        assert!(r.outcome.failure_probability <= 1e-12 * (1.0 + 1e-9));
    }
}
