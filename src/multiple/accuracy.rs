//! Accuracy of an estimate against ground truth, after the optimal global alignment.
//!
//! Estimates are defined up to the gauge `R_i -> R_i G`. The alignment `[F9]` (see
//! `paper-notes/formats.md`) is the `G in SO(3)` minimising `sum_i ||R_i G - T_i||_F^2` over the
//! nodes with ground truth `T_i`; expanding, this maximises `tr(G^T M)` with
//! `M = sum_i R_i^T T_i`, whose maximiser over SO(3) is the det-corrected SVD projection of `M`
//! ([`crate::so3::project_to_so3`]). Errors are then `theta(R_i G, T_i)`.

use crate::error::{Error, Result};
use crate::objective::{Loss, Objective};
use crate::single::{SingleProblem, SingleSettings, solve_single};
use crate::so3::{Metric, Rotation, angle_between, project_to_so3};
use crate::validate::quantile_sorted;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Angular errors of an estimate against ground truth after alignment, in degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AccuracyReport {
    /// Mean error (degrees).
    pub mean_deg: f64,
    /// Median error (degrees; the mean of the two middle values for an even count).
    pub median_deg: f64,
    /// Largest error (degrees).
    pub max_deg: f64,
    /// Root mean square error (degrees).
    pub rmse_deg: f64,
    /// Number of nodes that had ground truth and were compared.
    pub num_compared: usize,
    /// The alignment `G` applied to the estimate (`R_i G` is compared with `T_i`).
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub alignment: Rotation,
    /// The same errors after the robust alignment: the rotation `G_1` minimising the sum of
    /// the angular errors `sum theta(R_i G_1, T_i)` (the geodesic L1 mean of `R_i^T T_i`,
    /// Weiszfeld `[S5]`), which outliers do not pull, as robust rotation averaging reports.
    pub robust: RobustAccuracy,
}

/// Accuracy after the robust (L1) alignment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobustAccuracy {
    /// Mean angular error, degrees.
    pub mean_deg: f64,
    /// Median angular error, degrees.
    pub median_deg: f64,
    /// Largest angular error, degrees.
    pub max_deg: f64,
    /// The alignment rotation `G_1`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub alignment: Rotation,
}

impl fmt::Display for AccuracyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "accuracy vs ground truth ({} nodes, after global alignment): mean {:.4} deg, median {:.4} deg, rmse {:.4} deg, max {:.4} deg",
            self.num_compared, self.mean_deg, self.median_deg, self.rmse_deg, self.max_deg
        )?;
        write!(
            f,
            "; after the robust (L1) alignment: mean {:.4} deg, median {:.4} deg, max {:.4} deg",
            self.robust.mean_deg, self.robust.median_deg, self.robust.max_deg
        )
    }
}

/// Align `estimate` to `truth` with the optimal gauge `G` `[F9]` and report angular errors.
/// `truth[k] = None` skips node `k`. Errors: different lengths, no node with ground truth.
///
/// ```
/// use rotavg::multiple::accuracy::align_and_compare;
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// let truth: Vec<_> = (0..4).map(|k| exp(&Vector3::new(0.3 * k as f64, 0.1, -0.2))).collect();
/// let g = exp(&Vector3::new(1.0, 2.0, 0.5)); // an arbitrary gauge
/// let est: Vec<_> = truth.iter().map(|t| t * g).collect();
/// let some: Vec<_> = truth.iter().copied().map(Some).collect();
/// let rep = align_and_compare(&est, &some).unwrap();
/// assert!(rep.max_deg < 1e-9);
/// ```
pub fn align_and_compare(
    estimate: &[Rotation],
    truth: &[Option<Rotation>],
) -> Result<AccuracyReport> {
    if estimate.len() != truth.len() {
        return Err(Error::InvalidSettings {
            name: "ground truth".into(),
            reason: format!(
                "has {} entries, the estimate has {} rotations",
                truth.len(),
                estimate.len()
            ),
        });
    }
    let pairs: Vec<(&Rotation, &Rotation)> = estimate
        .iter()
        .zip(truth)
        .filter_map(|(r, t)| t.as_ref().map(|t| (r, t)))
        .collect();
    if pairs.is_empty() {
        return Err(Error::Empty {
            what: "the ground truth (no node has one)".into(),
        });
    }
    let mut m = Matrix3::zeros();
    for (r, t) in &pairs {
        m += r.matrix().transpose() * t.matrix();
    }
    let g = project_to_so3(&m).ok_or_else(|| Error::NonFinite {
        item: "estimate or ground truth".into(),
    })?;
    let errs = sorted_errors(&pairs, &g);
    let k = errs.len();
    // the robust alignment: geodesic L1 mean of R_i^T T_i, started at the least-squares one
    let differences: Vec<Rotation> = pairs.iter().map(|(r, t)| r.inverse() * *t).collect();
    let l1 = SingleProblem::new(differences, None)?
        .with_objective(Objective::new(Metric::Geodesic, Loss::L1))?;
    let g1 = solve_single(
        &l1,
        &SingleSettings {
            init: Some(g),
            ..Default::default()
        },
    )?
    .estimate;
    let robust_errs = sorted_errors(&pairs, &g1);
    Ok(AccuracyReport {
        mean_deg: errs.iter().sum::<f64>() / k as f64,
        median_deg: quantile_sorted(&errs, 0.5),
        max_deg: errs[k - 1],
        rmse_deg: (errs.iter().map(|e| e * e).sum::<f64>() / k as f64).sqrt(),
        num_compared: k,
        alignment: g,
        robust: RobustAccuracy {
            mean_deg: robust_errs.iter().sum::<f64>() / k as f64,
            median_deg: quantile_sorted(&robust_errs, 0.5),
            max_deg: robust_errs[k - 1],
            alignment: g1,
        },
    })
}

/// The angular errors `theta(R_i G, T_i)` in degrees, sorted.
fn sorted_errors(pairs: &[(&Rotation, &Rotation)], g: &Rotation) -> Vec<f64> {
    let mut errs: Vec<f64> = pairs
        .iter()
        .map(|(r, t)| angle_between(&(*r * g), t).to_degrees())
        .collect();
    errs.sort_by(f64::total_cmp);
    errs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3::{perturb, random_rotation};
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// Planted gauge: est_i = T_i G0^T with T_i perturbed by exactly 1 deg on odd nodes, so the
    /// alignment must undo G0 and the errors are 0 on even nodes and ~1 deg on odd ones (the
    /// optimal G moves slightly off G0^-1, hence the loose bound on the mean).
    #[test]
    fn planted_gauge_is_removed() {
        let mut rng = StdRng::seed_from_u64(11);
        let truth: Vec<Rotation> = (0..50).map(|_| random_rotation(&mut rng)).collect();
        let g0 = random_rotation(&mut rng);
        let exact: Vec<Rotation> = truth.iter().map(|t| t * g0.inverse()).collect();
        let t_opt: Vec<Option<Rotation>> = truth.iter().copied().map(Some).collect();
        let rep = align_and_compare(&exact, &t_opt).unwrap();
        assert!(rep.max_deg < 1e-9, "{rep}");
        assert!(angle_between(&rep.alignment, &g0) < 1e-9);
        let noisy: Vec<Rotation> = exact
            .iter()
            .enumerate()
            .map(|(k, r)| {
                if k % 2 == 1 {
                    perturb(r, 1f64.to_radians(), &mut rng)
                } else {
                    *r
                }
            })
            .collect();
        let rep = align_and_compare(&noisy, &t_opt).unwrap();
        assert!(rep.max_deg < 1.5 && rep.max_deg > 0.5, "{rep}");
        assert!((rep.mean_deg - 0.5).abs() < 0.2, "{rep}");
        // missing truth is skipped
        let mut partial = t_opt.clone();
        partial[3] = None;
        assert_eq!(
            align_and_compare(&exact, &partial).unwrap().num_compared,
            49
        );
        assert!(align_and_compare(&exact, &vec![None; 50]).is_err());
        assert!(align_and_compare(&exact[..3], &t_opt).is_err());
    }

    /// With 20 % of the nodes off by 60 degrees, the least-squares alignment is pulled (every
    /// inlier gets an error) and the robust one is not: it recovers the planted gauge, and the
    /// inliers' errors vanish.
    #[test]
    fn robust_alignment_ignores_outliers() {
        let mut rng = StdRng::seed_from_u64(5);
        let truth: Vec<Rotation> = (0..50).map(|_| random_rotation(&mut rng)).collect();
        let g0 = random_rotation(&mut rng);
        let est: Vec<Rotation> = truth
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let r = t * g0.inverse();
                if k % 5 == 0 {
                    perturb(&r, 60f64.to_radians(), &mut rng)
                } else {
                    r
                }
            })
            .collect();
        let t_opt: Vec<Option<Rotation>> = truth.iter().copied().map(Some).collect();
        let rep = align_and_compare(&est, &t_opt).unwrap();
        assert!(rep.median_deg > 0.5, "{rep}");
        assert!(rep.robust.median_deg < 1e-6, "{rep}");
        assert!(angle_between(&rep.robust.alignment, &g0) < 1e-8, "{rep}");
        assert!(rep.robust.max_deg > 50.0, "{rep}");
    }
}
