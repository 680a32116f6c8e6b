//! The comparison with scalar weights `[A13]`: information matrices that are isotropic to
//! rounding (`--information full` on the many files whose rotation information is `w I`) are
//! certified through the isotropic problem with `w_e = lambda_min(H_e)`, whose certificate takes
//! the cheap scalar path (the scalar comparison `[D13]`, no `3 x 3` anisotropic blocks): issue
//! 35 measured 2.4-2.8x the certify time of the same files read with scalar weights.
//!
//! With `D_e = H_e - w_e I` positive semidefinite, the anisotropic cost is linear in `H`:
//! `f_H = f_{wI} + f_D`, `f_{wI,e} = g_e + w_e (3 - ||R_ij||_F^2)` (`g` the isotropic chordal
//! cost, exactly), and `f_{D,e} >= -4 sqrt(3) ||E_e||_2 ||M_{D_e}||_F` where `R_ij = O + E` with
//! `O` orthogonal (zero for exact rotations: then `f_{D,e} = 4 (1 - cos theta) u^T D u >= 0`).
//! So `min f_H >= LB_g + sum_e w_e (3 - ||R_ij||^2) - sum_e c_e`, every term bounded with its
//! rounding. The gap this costs is `f_D` at the estimate: at most the information's spread
//! times the cost, which is why the rung applies only below [`MAX_SPREAD`].

use super::check::Scope;
use super::dual::{DUAL_SECONDS_PER_EDGE, dual_certificate_with};
use super::multipliers::FirstOrder;
use super::state::{Best, State};
use crate::certify::log::{Point, Prediction, Refusal};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::{Found, Plan, Rung};
use crate::error::Result;
use crate::linalg::UNIT_ROUNDOFF;
use crate::linalg::compensated::Accumulator;
use crate::multiple::anisotropic::Information;
use crate::multiple::{Edge, MultipleProblem};

/// Largest spread `(lambda_max - lambda_min) / lambda_min` of an information matrix for which
/// the comparison runs: its gap, at most the spread times the cost, stays below the tolerance's
/// relative part `1e-6` with room.
pub const MAX_SPREAD: f64 = 1e-9;

/// The error of an eigenvalue of a nearly isotropic information matrix, relative to its largest
/// (`64 u`: the dense eigensolver's backward error with room; `[A12]`'s relative accuracy `1e-7`
/// is that of eigenvalues far below the largest, and rounding by it would cost `2e-7` of the
/// bound, a fifth of the tolerance).
pub const DENSE_ERROR: f64 = 64.0 * UNIT_ROUNDOFF;

/// The comparison with scalar weights as a rung (every mode the dual certificate runs in): at
/// every point once, on anisotropic problems whose every information matrix is isotropic to
/// [`MAX_SPREAD`].
#[derive(Default)]
pub(crate) struct ScalarWeightsRung {
    done_at: Vec<Point>,
    /// The isotropic problem and the sum of the corrections, made once.
    comparison: Option<Comparison>,
}

/// The isotropic problem of an anisotropic one and the constant of `[A13]`.
struct Comparison {
    scalar: MultipleProblem,
    /// A proven lower bound on `sum_e w_e (3 - ||R_ij||^2) - sum_e c_e`.
    constant: f64,
}

impl<'a> Rung<State<'a>> for ScalarWeightsRung {
    fn proof(&self) -> Proof {
        Proof::ScalarWeights
    }

    fn plan(&mut self, cx: &State<'a>) -> Result<Plan> {
        let Some(info) = cx.problem.information() else {
            return Ok(Plan::Done);
        };
        if self.done_at.contains(&cx.current.label) {
            return Ok(Plan::Wait);
        }
        if self.comparison.is_none() {
            let spread = info.iter().map(spread).fold(0.0, f64::max);
            if spread > MAX_SPREAD {
                let reason = format!(
                    "the information matrices are not isotropic to rounding (largest spread \
                     {spread:.1e} > {MAX_SPREAD:.0e})"
                );
                return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
            }
            self.comparison = Some(comparison(cx.problem, info)?);
        }
        let seconds = DUAL_SECONDS_PER_EDGE * cx.problem.num_edges() as f64;
        Ok(Plan::Run(Prediction::new(seconds, 0.0)))
    }

    fn attempt(&mut self, cx: &mut State<'a>) -> Result<Found> {
        let label = cx.current.label;
        self.done_at.push(label);
        let Some(c) = &self.comparison else {
            return Ok(Found::failed("no comparison"));
        };
        let rotations = cx.current.rotations.clone();
        let first = FirstOrder::at(&c.scalar, &rotations)?;
        let scope = Scope {
            point: label,
            within: Proof::ScalarWeights,
            deadline: cx.deadline,
            refinement_follows: None,
        };
        let cost = c.scalar.chordal_cost(&rotations);
        let d = dual_certificate_with(&c.scalar, &rotations, cost, &first, cx.settings, scope)?;
        cx.log.extend(d.bound.ladder.iter().cloned());
        if d.bound.budget_exceeded.is_some() && d.bound.verification == Proof::Gershgorin {
            return Ok(Found::failed(
                "no check of the isotropic problem fitted the budget",
            ));
        }
        let lower_bound = d.bound.lower_bound + c.constant;
        let note = format!(
            "comparison with scalar weights lambda_min(H_e) at {label} [A13]: the isotropic \
             problem's bound {:.9e} ({}) plus {:.3e}",
            d.bound.lower_bound, d.proof, c.constant
        );
        cx.offer(Best {
            lower_bound,
            method: BoundMethod::Dual,
            point: label,
            min_eigenvalue: d.certificate.min_eigenvalue,
            explanation: note.clone(),
            verified_min_eigenvalue: d.bound.verified_min_eigenvalue,
            shift: None,
            lambdas: None,
        });
        Ok(Found::proved(lower_bound, cx.certifies(lower_bound), note))
    }
}

/// `(lambda_max - lambda_min) / lambda_min` of `h` (infinite when singular).
fn spread(h: &Information) -> f64 {
    let [lo, _, hi] = h.eigenvalues();
    if lo > 0.0 {
        (hi - lo) / lo
    } else {
        f64::INFINITY
    }
}

/// The isotropic problem with `w_e = lambda_min(H_e)` rounded down (so that `H_e - w_e I` is
/// positive semidefinite) and the proven constant of `[A13]`. Below [`MAX_SPREAD`] every
/// eigenvalue is resolved by the dense solver, whose error is at most [`DENSE_ERROR`]
/// `lambda_max` (a backward-stable symmetric eigensolver: `c u ||H||_2` with a small `c`).
fn comparison(problem: &MultipleProblem, info: &[Information]) -> Result<Comparison> {
    let mut edges = Vec::with_capacity(info.len());
    let mut defect = Accumulator::default();
    let mut correction = 0.0;
    for (e, h) in problem.edges().iter().zip(info) {
        let [lo, _, hi] = h.eigenvalues();
        let w = lo - DENSE_ERROR * hi;
        edges.push(Edge {
            weight: w,
            ..e.clone()
        });
        // w (3 - ||R_ij||_F^2) in double-double
        defect.add_product(w, 3.0);
        for v in e.rotation.matrix().iter() {
            defect.add_triple(-w, *v, *v);
        }
        // c_e = 4 sqrt(3) ||E||_2 ||M_D||_F <= 30 ||R^T R - I||_F (lambda_max - w)
        let r = e.rotation.matrix();
        let orth =
            (r.transpose() * r - nalgebra::Matrix3::identity()).norm() + 32.0 * UNIT_ROUNDOFF;
        let spread = hi * (1.0 + DENSE_ERROR) - w;
        correction += 30.0 * orth * spread;
    }
    let scalar = MultipleProblem::new(problem.num_rotations(), edges)?;
    let constant = (defect.value() - defect.bound()) - correction * (1.0 + 1e-6);
    Ok(Comparison { scalar, constant })
}
