//! The information of a rig's within-frame pairs, pooled over its frames (`paper-notes/formats.md`
//! `[F18]`).
//!
//! Two images of one frame, taken by sensors `s` and `t`, are related by the rig alone
//! (`X_b X_a^T = S_t S_s^T`): the same relative rotation, and the same small baseline, in every
//! frame. Their information from the correspondences (`[F13]`) is evaluated at each pair's own
//! estimated translation, which such a baseline hardly determines, and the information about the
//! rotation coupled with it follows that estimate: on generated rigs it spread over three orders
//! of magnitude between the frames of one sensor pair, largest where the estimated translation
//! and the rotation's error had turned together, so the information-weighted mean of those
//! pairs was biased by 0.1-0.4 degrees where their plain mean was within 0.02. A rig's
//! within-frame pairs of one sensor pair therefore carry one information: the log-Euclidean
//! median of theirs (the entrywise median of the matrix logarithms, mapped back by the
//! exponential), each expressed in the frame of the first sensor's camera, which is the same
//! camera in every frame.

use crate::multiple::Edge;
use crate::multiple::anisotropic::Information;
use crate::rig::Image;
use crate::{Error, Result};
use nalgebra::Matrix3;
use std::collections::BTreeMap;

/// Eigenvalues below this fraction of a matrix's largest are raised to it before the logarithm
/// (a rank-deficient `H`, whose logarithm is not finite).
const LOG_FLOOR: f64 = 1e-12;

/// `information` with every within-frame edge's matrix (the edges whose images share a frame and
/// not a sensor) replaced by the log-Euclidean median of its sensor pair's (module docs). An
/// edge stored from sensor `t` to `s` (`t > s`) is turned into `s`'s frame for the median and
/// back: `e' = -R e`, so `H' = R H R^T`. Other edges keep theirs. Errors: not one matrix per
/// edge, an edge naming an image beyond `images`, or a pooled matrix the information's checks
/// refuse (not expected: it is positive definite with the inputs' scale).
///
/// ```
/// use nalgebra::{Matrix3, Vector3};
/// use rotavg::io::within_frame::pooled_within_frames;
/// use rotavg::multiple::anisotropic::Information;
/// use rotavg::multiple::Edge;
/// use rotavg::rig::Image;
/// use rotavg::Rotation;
/// // three frames of two sensors; the three within-frame pairs' information about the yaw axis
/// // is 1, 100 and 10000
/// let images: Vec<Image> = (0..6).map(|a| Image { frame: a / 2, sensor: a % 2 }).collect();
/// let edge = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
/// let edges = vec![edge(0, 1), edge(2, 3), edge(4, 5), edge(0, 2)];
/// let h = |y: f64| Information::new(Matrix3::from_diagonal(&Vector3::new(1e4, y, 1e4)));
/// let info = vec![h(1.0)?, h(100.0)?, h(1e4)?, h(7.0)?];
/// let pooled = pooled_within_frames(&images, &edges, &info)?;
/// assert_eq!((pooled.pairs, pooled.sensor_pairs), (3, 1));
/// for k in 0..3 {
///     assert!((pooled.information[k].matrix()[(1, 1)] - 100.0).abs() < 1e-9); // the median
/// }
/// assert_eq!(pooled.information[3], info[3]); // across frames: as it was
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn pooled_within_frames(
    images: &[Image],
    edges: &[Edge],
    information: &[Information],
) -> Result<Pooled> {
    let invalid = |reason: String| Error::InvalidSettings {
        name: "information".into(),
        reason,
    };
    if information.len() != edges.len() {
        let (h, m) = (information.len(), edges.len());
        return Err(invalid(format!("{h} information matrices for {m} edges")));
    }
    let mut groups: BTreeMap<(usize, usize), Vec<usize>> = BTreeMap::new();
    for (k, e) in edges.iter().enumerate() {
        let (Some(a), Some(b)) = (images.get(e.i), images.get(e.j)) else {
            return Err(invalid(format!(
                "edge {k} names an image beyond the {}",
                images.len()
            )));
        };
        if a.frame == b.frame && a.sensor != b.sensor {
            let key = (a.sensor.min(b.sensor), a.sensor.max(b.sensor));
            groups.entry(key).or_default().push(k);
        }
    }
    let mut pooled = information.to_vec();
    let (mut pairs, mut sensor_pairs) = (0, 0);
    for members in groups.values().filter(|m| m.len() > 1) {
        (pairs, sensor_pairs) = (pairs + members.len(), sensor_pairs + 1);
        // each member's H in the first sensor's camera frame, and the turn back
        let turns: Vec<Matrix3<f64>> = members
            .iter()
            .map(
                |&k| match images[edges[k].i].sensor > images[edges[k].j].sensor {
                    true => *edges[k].rotation.matrix(),
                    false => Matrix3::identity(),
                },
            )
            .collect();
        let logs: Vec<Matrix3<f64>> = members
            .iter()
            .zip(&turns)
            .map(|(&k, r)| symmetric_log(&(r * information[k].matrix() * r.transpose())))
            .collect();
        let median = symmetric_exp(&entrywise_median(&logs));
        for (&k, r) in members.iter().zip(&turns) {
            let h = r.transpose() * median * r;
            pooled[k] = Information::new((h + h.transpose()) * 0.5)?;
        }
    }
    Ok(Pooled {
        information: pooled,
        pairs,
        sensor_pairs,
    })
}

/// What [`pooled_within_frames`] returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Pooled {
    /// One matrix per edge, in edge order.
    pub information: Vec<Information>,
    /// The within-frame edges given their sensor pair's pooled matrix.
    pub pairs: usize,
    /// The sensor pairs pooled (with two or more within-frame edges).
    pub sensor_pairs: usize,
}

/// The logarithm of a symmetric positive semidefinite matrix, its eigenvalues floored at
/// [`LOG_FLOOR`] of the largest.
fn symmetric_log(h: &Matrix3<f64>) -> Matrix3<f64> {
    let eig = h.symmetric_eigen();
    let floor = eig.eigenvalues.max() * LOG_FLOOR;
    let logs = eig.eigenvalues.map(|l| l.max(floor).ln());
    eig.eigenvectors * Matrix3::from_diagonal(&logs) * eig.eigenvectors.transpose()
}

/// The exponential of a symmetric matrix.
fn symmetric_exp(l: &Matrix3<f64>) -> Matrix3<f64> {
    let eig = ((l + l.transpose()) * 0.5).symmetric_eigen();
    let exps = eig.eigenvalues.map(f64::exp);
    eig.eigenvectors * Matrix3::from_diagonal(&exps) * eig.eigenvectors.transpose()
}

/// The entrywise median (the mean of the two middle values for an even count).
fn entrywise_median(ms: &[Matrix3<f64>]) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| {
        let mut v: Vec<f64> = ms.iter().map(|m| m[(r, c)]).collect();
        v.sort_unstable_by(f64::total_cmp);
        let n = v.len();
        match n % 2 {
            1 => v[n / 2],
            _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rotation;
    use nalgebra::Vector3;

    /// An edge stored from the second sensor to the first is turned into the first's camera
    /// and back: two pairs whose information is the same matrix there keep theirs exactly (to
    /// rounding), whichever way they are stored; and the counts are checked.
    #[test]
    fn a_reversed_edge_is_turned_and_back() {
        let images: Vec<Image> = (0..4)
            .map(|a| Image {
                frame: a / 2,
                sensor: a % 2,
            })
            .collect();
        let r = crate::so3::exp(&Vector3::new(0.1, 0.5, -0.2));
        let canonical = Matrix3::new(9.0, 1.0, 0.5, 1.0, 4.0, 0.2, 0.5, 0.2, 1.0);
        let edge = |i, j, rotation: Rotation| Edge {
            i,
            j,
            rotation,
            weight: 1.0,
        };
        let edges = vec![edge(0, 1, r), edge(3, 2, r.inverse())];
        let back = r.matrix() * canonical * r.matrix().transpose(); // R_ts^T H R_ts, R_ts = r^T
        let info = vec![
            Information::new(canonical).unwrap(),
            Information::new((back + back.transpose()) * 0.5).unwrap(),
        ];
        let pooled = pooled_within_frames(&images, &edges, &info)
            .unwrap()
            .information;
        for k in 0..2 {
            let (got, want) = (pooled[k].matrix(), info[k].matrix());
            assert!(
                (got - want).norm() <= 1e-12 * want.norm(),
                "edge {k}: {got} {want}"
            );
        }
        assert!(pooled_within_frames(&images, &edges, &info[..1]).is_err());
        assert!(pooled_within_frames(&images[..3], &edges, &info).is_err());
    }
}
