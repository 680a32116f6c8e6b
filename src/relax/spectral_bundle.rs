//! The model step of a proximal spectral bundle method (Helmberg and Rendl), shared by the
//! searches that raise a smallest eigenvalue over multipliers: the `conv(SO(3))` dual's node
//! shifts (`paper-notes/anisotropic.md` `[A11]` "Node shifts") and the rigs' couplings
//! (`paper-notes/conjugate.md` `[H21]` "The model's dual").
//!
//! Each round maximises the model `g^T y + tau t - rho |y|_M^2 / 2` subject to `C + A(y) - t I`
//! positive semidefinite, where `V` (`n x r`) holds the bundle's orthonormal columns, `C = V^T
//! T V` is the matrix at the bundle's center restricted to them, `A(y) = V^T D(y) V` is the
//! restriction of the matrix's linear change with the variables `y`, `g` the gradient of the
//! objective's linear part and `tau` the weight of `lambda_min` in it (`1` for `lambda_min`
//! alone, `3n` for a bound `sum tr + 3n lambda_min`). `|y|_M^2 = y^T M^{-1} y` with `M`
//! diagonal (the variables' metric: off-diagonal entries of a symmetric variable count twice,
//! so their `M` is `1/2`). Its Lagrangian dual is
//!
//! `min <W, C> + |g + A*(W)|_M^2 / (2 rho)` over `W` positive semidefinite with `tr W = tau`,
//!
//! in the bundle's own dimension (`r (r + 1) / 2` variables: Clarabel, a few milliseconds),
//! and the maximiser is `y = M (g + A*(W)) / rho`, `t = lambda_min(C + A(y))`.

use crate::linalg::dense::symmetric_eigenvalues;
use crate::relax::clarabel::{Cone, csc, solve_quadratic_conic};
use crate::relax::settings::SdpSettings;
use crate::relax::svec::{svec_entry, svec_index, svec_len, svec_weight};
use nalgebra::{DMatrix, DVector};

/// How wide a bundle is and when it stops (each caller states its own, with the runs that
/// chose them).
pub(crate) struct Rules {
    /// Most rounds.
    pub rounds: usize,
    /// Bottom eigenvectors kept at the center, and the candidate's added each round.
    pub widths: (usize, usize),
    /// A stall: `stall.1` rounds raised the objective by less than `stall.0` times the
    /// caller's scale.
    pub stall: (f64, usize),
}

impl Rules {
    /// Whether `history` (the objective at the center after each round, the start first) has
    /// stalled on the caller's `scale`.
    pub(crate) fn stalled(&self, history: &[f64], scale: f64) -> bool {
        let (fraction, rounds) = self.stall;
        let last = history.len().saturating_sub(1);
        last > rounds && history[last] - history[last - rounds] < fraction * scale
    }
}

/// The proximal bundle's step test (Helmberg and Rendl): serious when the objective `gained`
/// at least a tenth of the model's `predicted` gain, and then the proximal weight `rho` is
/// halved (the model is trusted farther), else doubled (a null step only enriches the bundle).
pub(crate) fn serious_step(gained: f64, predicted: f64, rho: &mut f64) -> bool {
    let serious = gained >= 0.1 * predicted;
    *rho *= if serious { 0.5 } else { 2.0 };
    serious
}

/// One round's model: the derivatives and the center's restricted matrix, the objective's
/// linear part and metric.
pub(crate) struct Model<'a> {
    /// `G^T`: a row per variable, a column per `svec` entry `(i, j)` of the bundle's dimension
    /// (`svec_entry`), the derivative of `svec(A(y))`'s entry with its `svec` weight.
    pub derivatives: &'a DMatrix<f64>,
    /// `C = V^T T V` at the center (symmetrised here).
    pub restricted: &'a DMatrix<f64>,
    /// `g`, one entry per variable (`None`: no linear part).
    pub linear: Option<&'a [f64]>,
    /// The diagonal metric `M` per variable (`None`: the identity).
    pub metric: Option<&'a [f64]>,
    /// `tau`, the weight of `lambda_min` in the objective: `tr W`.
    pub weight: f64,
}

/// The model's maximiser: `y`, and `t = lambda_min(C + A(y))` (the model's whole smallest
/// eigenvalue, the center's included).
pub(crate) struct Step {
    pub y: Vec<f64>,
    pub t: f64,
}

impl Model<'_> {
    fn g(&self, row: usize) -> f64 {
        self.linear.map_or(0.0, |g| g[row])
    }

    fn m(&self, row: usize) -> f64 {
        self.metric.map_or(1.0, |m| m[row])
    }

    /// The step for proximal weight `rho`, by Clarabel within `seconds`: `None` when the
    /// model's dual did not converge (a `NumericalFailure` at a small `rho`: the caller
    /// doubles it) or its eigenvalues failed.
    pub(crate) fn step(&self, rho: f64, seconds: Option<f64>) -> Option<Step> {
        let gt = self.derivatives;
        let c = self.restricted;
        let r = c.nrows();
        let len = svec_len(r);
        let scaled = self
            .metric
            .map(|_| DMatrix::from_fn(gt.nrows(), len, |row, col| gt[(row, col)] * self.m(row)));
        // the node shifts' numbers (`docs/benchmarks.md`) were measured with nalgebra's product for
        // the scaled case; faer's rounds differently, and the bundle's stall rule then stops
        // elsewhere (300 nodes, seed 4: a relative gap of 0.60 against 0.57)
        let gram = match &scaled {
            Some(scaled) => gt.tr_mul(scaled) / rho,
            None => gram(gt, 1.0 / rho),
        };
        let q: Vec<f64> = (0..len)
            .map(|col| {
                let (i, j) = svec_entry(col);
                let linear: f64 = self.linear.map_or(0.0, |g| {
                    let column = scaled.as_ref().unwrap_or(gt).column(col);
                    g.iter().zip(column.iter()).map(|(a, b)| a * b).sum()
                });
                svec_weight(i, j) * 0.5 * (c[(i, j)] + c[(j, i)]) + linear / rho
            })
            .collect();
        let w = self.dual(&gram, &q, seconds)?;
        let y: Vec<f64> = (gt * w)
            .iter()
            .enumerate()
            .map(|(row, x)| (self.g(row) + x) * self.m(row) / rho)
            .collect();
        let ay = gt.tr_mul(&DVector::from_column_slice(&y));
        let model = DMatrix::from_fn(r, r, |i, j| {
            0.5 * (c[(i, j)] + c[(j, i)]) + ay[svec_index(i, j)] / svec_weight(i, j)
        });
        let t = symmetric_eigenvalues(&model)?[0];
        Some(Step { y, t })
    }

    /// The dual's `W` (`svec`) minimising `q^T w + w^T gram w / 2` over `W >= 0`, `tr W =
    /// tau`; solved for `W / tau` (unit trace) with the objective over its largest coefficient:
    /// Clarabel's `NumericalFailure` otherwise at small `rho` (the node shifts on graphs of
    /// 8-12 nodes, `[A11]`).
    fn dual(&self, gram: &DMatrix<f64>, q: &[f64], seconds: Option<f64>) -> Option<DVector<f64>> {
        let len = q.len();
        let r = self.restricted.nrows();
        let tau = self.weight;
        let largest = (gram.amax() * tau * tau)
            .max(q.iter().fold(0.0_f64, |m, x| m.max(x.abs())) * tau)
            .max(f64::MIN_POSITIVE);
        let (quadratic, linear) = (tau * tau / largest, tau / largest);
        let upper = (0..len).flat_map(|b| (0..=b).map(move |a| (a, b)));
        let p = csc(
            len,
            len,
            upper
                .map(|(a, b)| (a, b, quadratic * gram[(a, b)]))
                .collect(),
        );
        let q: Vec<f64> = q.iter().map(|x| linear * x).collect();
        // `1 - tr W = 0`, then `0 - (-w)` in the PSD cone
        let mut triplets: Vec<(usize, usize, f64)> =
            (0..r).map(|i| (0, svec_index(i, i), 1.0)).collect();
        triplets.extend((0..len).map(|row| (1 + row, row, -1.0)));
        let mut b = vec![0.0; 1 + len];
        b[0] = 1.0;
        let settings = SdpSettings {
            chordal_decomposition: false,
            time_limit_seconds: seconds.map(|s| s.max(0.0)),
            ..SdpSettings::default()
        };
        let cones = [Cone::Zero(1), Cone::Psd(r)];
        let a = csc(1 + len, len, triplets);
        let solution = solve_quadratic_conic((&p, &q), a, &b, &cones, &settings, "none").ok()?;
        solution
            .status
            .converged()
            .then(|| DVector::from_column_slice(&solution.x) * tau)
    }
}

/// `alpha G G^T` for `gt` = `G^T`, by a blocked product over its transposed view (no copy of
/// `G`: 0.7 GB at 10^4 frames and 6 sensors, `[H21]`).
fn gram(gt: &DMatrix<f64>, alpha: f64) -> DMatrix<f64> {
    let (rows, cols) = gt.shape();
    let g = faer::MatRef::from_column_major_slice(gt.as_slice(), rows, cols);
    let mut m = faer::Mat::<f64>::zeros(cols, cols);
    faer::linalg::matmul::matmul(
        m.as_mut(),
        faer::Accum::Replace,
        g.transpose(),
        g,
        alpha,
        faer::Par::Seq,
    );
    DMatrix::from_fn(cols, cols, |r, c| m[(r, c)])
}

#[cfg(test)]
mod tests {
    use super::Rules;

    /// A stall is `stall.1` rounds that gained less than `stall.0` of the scale, counted from
    /// the start: never before that many rounds, not while the objective still climbs.
    #[test]
    fn a_stall_is_too_little_gain_over_the_last_rounds() {
        let rules = Rules {
            rounds: 50,
            widths: (8, 3),
            stall: (1e-2, 3),
        };
        // the start, then rounds: flat from the start, but only three rounds done
        assert!(!rules.stalled(&[1.0, 1.0, 1.0, 1.0], 1.0));
        assert!(rules.stalled(&[1.0, 1.0, 1.0, 1.0, 1.0], 1.0));
        // a gain of 2e-2 over the last three rounds on a scale of 1: not stalled; of 1 on 1e3: stalled
        assert!(!rules.stalled(&[0.0, 0.5, 0.98, 0.99, 1.0], 1.0));
        assert!(rules.stalled(&[0.0, 0.5, 0.98, 0.99, 1.0], 1e3));
        assert!(!rules.stalled(&[], 1.0));
    }

    /// A step is serious from a tenth of its predicted gain on (the weight halved), null
    /// below it (doubled).
    #[test]
    fn a_serious_step_gains_a_tenth_of_its_prediction() {
        let mut rho = 1.0;
        assert!(super::serious_step(0.1, 1.0, &mut rho));
        assert_eq!(rho, 0.5);
        assert!(!super::serious_step(0.099, 1.0, &mut rho));
        assert_eq!(rho, 1.0);
        assert!(!super::serious_step(-1.0, 1.0, &mut rho));
        assert_eq!(rho, 2.0);
    }
}
