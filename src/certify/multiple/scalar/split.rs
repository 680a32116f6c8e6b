//! Step 4 of the scalar comparison `[D13]`: the weights `w = delta + zeta` of the pencil, the
//! `zeta` that absorbs the cross terms, and, for a split into parts, each part's charges
//! `c_p = w f_p` and the split's defect `eps` (paid from `zeta`).

use super::analysis::ScalarAnalysis;
use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma};
use crate::multiple::MultipleProblem;

/// Step 4's weights: `w = delta + zeta`, the split's shares and defect, and what `zeta` leaves
/// free for the cross terms.
pub(super) struct PencilWeights {
    /// `w_i = delta_i + zeta`.
    pub weights: Vec<f64>,
    /// Per part of a split, every node's share of its kept weight (empty for one part).
    pub shares: Vec<Vec<f64>>,
    pub zeta: f64,
    /// The split's defect `eps` (0 for one part).
    pub defect: f64,
    /// `zeta - 2u max w - eps`, reduced by `4u`: `x1^T M x1 >= zeta_free |x1|^2`.
    pub zeta_free: f64,
}

/// `kappa = ||w||_2 / sum w` of the weights `delta + zeta`, rounded up.
pub(super) fn kappa(delta: &[f64], zeta: f64) -> f64 {
    let n = delta.len();
    let sum: f64 = delta.iter().map(|d| d + zeta).sum::<f64>() * (1.0 - gamma(n + 2));
    let norm = delta
        .iter()
        .map(|d| (d + zeta) * (d + zeta))
        .sum::<f64>()
        .sqrt()
        * (1.0 + gamma(n + 2));
    (norm / sum) * (1.0 + 4.0 * UNIT_ROUNDOFF)
}

/// The weights of step 4 for the comparison's `target`: a uniform `zeta > 0` buys the positive
/// term `zeta |x1|^2`, which absorbs the cross terms (`x^T M x >= -(rho0 + rho1^2 / zeta)
/// kappa^2 |x|^2`); `zeta` makes that at most `target / 4` (with `kappa` at `zeta = 0`), plus
/// twice a split's defect, which grows with `zeta` (checked again at the final `zeta`), and at
/// least `floor` (a one-region comparison's, `[D13]` "One region": its deflated bound needs a
/// `zeta` of its own size, any `zeta >= 0` keeps the proof). `None` when a split leaves
/// nothing free (or a value is not finite).
pub(super) fn pencil_weights(
    analysis: &ScalarAnalysis,
    problem: &MultipleProblem,
    (reduced, delta): (&[f64], &[f64]),
    (rho1, d_max, floor): (f64, f64, f64),
    target: f64,
) -> Option<PencilWeights> {
    let u = UNIT_ROUNDOFF;
    let k0 = kappa(delta, 0.0);
    let zeta_needed = if target > 0.0 && target.is_finite() {
        (4.0 * rho1 * rho1 * k0 * k0 / target).max(1e-12 * d_max)
    } else {
        0.0
    }
    .max(floor);
    let shares = part_shares(analysis, problem, reduced, delta.len());
    let defect_of = |zeta: f64| -> f64 {
        let w: Vec<f64> = delta.iter().map(|d| d + zeta).collect();
        split_defect(&shares, &w)
    };
    let (zeta, defect) = if shares.len() > 1 {
        let zeta = zeta_needed + 2.0 * defect_of(zeta_needed);
        (zeta, defect_of(zeta))
    } else {
        (zeta_needed, 0.0)
    };
    let weights: Vec<f64> = delta.iter().map(|d| d + zeta).collect();
    // fl(delta_i + zeta) >= delta_i + zeta - u w_i (twice that for safety), less the defect
    let w_max = weights.iter().copied().fold(0.0, f64::max);
    let zeta_free = (zeta - 2.0 * u * w_max - defect) * (1.0 - 4.0 * u);
    (zeta_free.is_finite() && (zeta_free >= 0.0 || shares.len() <= 1)).then_some(PencilWeights {
        weights,
        shares,
        zeta,
        defect,
        zeta_free,
    })
}

/// Per part of a split (none for one part), every node's share `f_p(i)` of its kept weight:
/// part `p`'s kept weight at `i` over the node's, `1 / P` where a node keeps none.
pub(super) fn part_shares(
    analysis: &ScalarAnalysis,
    problem: &MultipleProblem,
    reduced: &[f64],
    n: usize,
) -> Vec<Vec<f64>> {
    let parts = analysis.parts.len();
    if parts <= 1 {
        return Vec::new();
    }
    let edges = problem.edges();
    let mut kept = vec![vec![0.0f64; n]; parts];
    for (part, kept) in analysis.parts.iter().zip(kept.iter_mut()) {
        for &(k, _, _) in &part.edges {
            let w = reduced[k].max(0.0) / analysis.copies[k].max(1) as f64;
            kept[edges[k].i] += w;
            kept[edges[k].j] += w;
        }
    }
    let mut total = vec![0.0f64; n];
    for kept in &kept {
        for (t, k) in total.iter_mut().zip(kept) {
            *t += k;
        }
    }
    kept.into_iter()
        .map(|kept| {
            kept.iter()
                .zip(&total)
                .map(|(&k, &t)| if t > 0.0 { k / t } else { 1.0 / parts as f64 })
                .collect()
        })
        .collect()
}

/// A part's charges `c_p = w f_p`, rounded up by `1 + gamma(P + 4)` so that
/// `sum_p c_p >= w` holds in floating point (the shares `f_p` sum to 1 up to `(P + 2) u`).
/// Step 5 factorises with exactly these numbers and [`split_defect`] bounds their defect.
pub(super) fn part_charges(w: &[f64], f: &[f64], parts: usize) -> Vec<f64> {
    w.iter()
        .zip(f)
        .map(|(w, f)| w * f * (1.0 + gamma(parts + 4)))
        .collect()
}

/// The split's defect `eps >= sum_p ||c_p - s_p w||^2 / 1^T c_p` with `c_p` from
/// [`part_charges`] and `s_p = c_p^T w / w^T w` (any `s_p` is valid; this one minimises the
/// norm), rounded up: every difference's rounding is bounded by `gamma(4)` times the
/// magnitudes.
pub(super) fn split_defect(shares: &[Vec<f64>], w: &[f64]) -> f64 {
    let parts = shares.len();
    let n = w.len();
    let g = gamma(n + 4);
    let ww: f64 = w.iter().map(|x| x * x).sum();
    let mut eps = 0.0f64;
    for f in shares {
        let c = part_charges(w, f, parts);
        let cw: f64 = c.iter().zip(w).map(|(c, w)| c * w).sum();
        let sp = cw / ww;
        let (mut sq, mut mag) = (0.0f64, 0.0f64);
        for (c, w) in c.iter().zip(w) {
            let d = c - sp * w;
            sq += d * d;
            mag += (c.abs() + (sp * w).abs()).powi(2);
        }
        let norm = sq.sqrt() * (1.0 + g) + gamma(4) * mag.sqrt() * (1.0 + g);
        let sum: f64 = c.iter().sum::<f64>() * (1.0 - g);
        if sum <= 0.0 {
            return f64::INFINITY;
        }
        eps += norm * norm / sum;
    }
    eps * (1.0 + gamma(2 * parts + 4))
}
