//! Anisotropic measurements: a 3x3 information matrix `H` per edge (contract section 1,
//! `paper-notes/anisotropic.md` `[A1]`-`[A4]`, `[A9]`).
//!
//! An edge `(i, j)` with information `H` (symmetric positive semidefinite, not zero) measures
//! `R_ij` with residual `e` defined by `R_j R_i^T = R_ij exp([e]x)`. With `M = tr(H)/2 I - H`:
//!
//! - anisotropic chordal cost `f_e = 4 (tr M - <R_ij M, R_j R_i^T>)` `[A1]`, which equals
//!   `4 (1 - cos theta) u^T H u` for `e = theta u` and `2 e^T H e` to second order;
//!   `H = w I` gives exactly the isotropic `w ||R_j - R_ij R_i||_F^2` (for exact rotations);
//! - anisotropic geodesic cost `e^T H e` `[A8]`, and the robust losses applied to the
//!   Mahalanobis angle `theta_H = sqrt(e^T H e / wbar)`, `wbar = tr(H)/3` (`[A10]`, minimised by
//!   `multiple::geodesic`'s Gauss-Newton / IRLS iteration with 3x3 blocks).
//!
//! The chordal cost is linear in the Gram block `R_j R_i^T`, so the connection Laplacian keeps
//! its shape with 3x3 blocks (`[A2]`: `Q_ii += 2M`, `Q_jj += 2M`, `Q_ij = -2 M R_ij^T`) and the
//! dual certificate, the SDP and the local Newton solver carry over with `B_e = R_i^T M R_ij^T
//! R_j` in place of the isotropic `(w / 2) A_e^T` (`[A4]`).
//!
//! ```
//! use rotavg::multiple::anisotropic::{Information, chordal_term, geodesic_term};
//! use rotavg::so3::exp;
//! use nalgebra::{Matrix3, Vector3};
//! let h = Information::new(Matrix3::from_diagonal(&Vector3::new(1.0, 4.0, 100.0))).unwrap();
//! let (r_ij, r_i) = (exp(&Vector3::new(0.3, -0.2, 0.1)), exp(&Vector3::new(0.0, 0.5, 0.0)));
//! let e = Vector3::new(0.01, 0.0, 0.002); // R_j R_i^T = R_ij exp([e]x)
//! let r_j = r_ij * exp(&e) * r_i;
//! let f = chordal_term(&h, &r_ij, &r_i, &r_j);
//! let theta = e.norm();
//! let closed = 4.0 * (1.0 - theta.cos()) * (e / theta).dot(&(h.matrix() * (e / theta)));
//! assert!((f - closed).abs() < 1e-9 * closed); // the trace form loses digits to cancellation
//! assert!((geodesic_term(&h, &r_ij, &r_i, &r_j) - e.dot(&(h.matrix() * e))).abs() < 1e-12);
//! ```

use crate::error::{Error, Result};
use crate::so3::{Rotation, log, right_jacobian_inverse};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// Relative tolerance on negative eigenvalues: `lambda_min >= -1e-12 lambda_max` is accepted (a
/// singular matrix rounded in floating point, e.g. numpy's `J.T @ W @ J` of a rank-deficient
/// `J`), anything more negative is an error. The eigenvalues are those of the matrix as given,
/// computed to high relative accuracy ([`crate::linalg::symmetric3`], `[A12]`); an accepted
/// negative part is **carried**, not rounded away: the cost is that of `H` as given, and every
/// lower bound of the certificates holds for any symmetric `H` (`[A12]`).
pub const PSD_TOLERANCE: f64 = 1e-12;

/// The asymmetry an information matrix may have, relative to its largest entry: `max |H -
/// H^T| <= 1e-12 max |H|` is rounding (numpy's `J.T @ W @ J` is asymmetric by ~1e-16
/// relative), and the symmetric part `(H + H^T) / 2` is used (the quadratic form `e^T H e` is
/// the same); anything larger is an error (contract section 1).
pub const SYMMETRY_TOLERANCE: f64 = 1e-12;

/// A validated 3x3 information matrix `H` of one edge: finite, exactly symmetric, positive
/// semidefinite (to [`PSD_TOLERANCE`], eigenvalues from [`crate::linalg::symmetric3`]), with
/// `tr(H)` in the weight window [`crate::validate::MIN_WEIGHT`]..[`crate::validate::MAX_WEIGHT`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "[[f64; 3]; 3]", into = "[[f64; 3]; 3]")]
pub struct Information {
    h: Matrix3<f64>,
    /// The eigenvalues of `h`, ascending, to [`crate::linalg::symmetric3::RELATIVE_ACCURACY`].
    eigenvalues: [f64; 3],
    /// `max |H - H^T| / max |H|` of the matrix as given (0: exactly symmetric; `h` is then its
    /// symmetric part).
    asymmetry: f64,
}

impl Information {
    /// Validate `h`. Errors ([`Error::InvalidInformation`]): a non-finite entry, an asymmetric
    /// matrix beyond rounding (`max |H - H^T| > 1e-12 max |H|`, [`SYMMETRY_TOLERANCE`]: pass
    /// `(H + H^T) / 2` if that is what is meant; within it the symmetric part is used and the
    /// asymmetry kept in [`Self::asymmetry`] for the readers to report), a negative eigenvalue
    /// below `-1e-12 lambda_max`, or a trace outside the weight window (`H = 0` carries no
    /// information).
    ///
    /// ```
    /// use rotavg::multiple::anisotropic::Information;
    /// use nalgebra::Matrix3;
    /// assert!(Information::new(Matrix3::identity() * 2.0).is_ok());
    /// let mut h = Matrix3::identity();
    /// h[(0, 1)] = 0.5; // not symmetric
    /// assert!(Information::new(h).is_err());
    /// h[(0, 1)] = 1e-17; // asymmetric by rounding: its symmetric part
    /// let rounded = Information::new(h)?;
    /// assert_eq!(rounded.matrix()[(0, 1)], 5e-18);
    /// assert_eq!(rounded.asymmetry(), 1e-17);
    /// assert!(Information::new(-Matrix3::identity()).is_err()); // not PSD
    /// assert!(Information::new(Matrix3::zeros()).is_err()); // no information
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn new(h: Matrix3<f64>) -> Result<Self> {
        Self::check(h).map_err(|reason| Error::InvalidInformation {
            item: "information matrix".into(),
            reason,
        })
    }

    fn check(h: Matrix3<f64>) -> std::result::Result<Self, String> {
        if !h.iter().all(|x| x.is_finite()) {
            return Err("contains NaN or infinity".into());
        }
        let asym = (h - h.transpose()).amax();
        let asymmetry = if asym == 0.0 { 0.0 } else { asym / h.amax() };
        if asymmetry > SYMMETRY_TOLERANCE {
            return Err(format!(
                "is not symmetric (largest |H - H^T| entry {asym:.3e}, {asymmetry:.1e} of the \
                 largest entry; rounding is up to {SYMMETRY_TOLERANCE:.0e}); pass (H + H^T) / 2 \
                 if that is the information meant"
            ));
        }
        let h = if asym == 0.0 {
            h
        } else {
            (h + h.transpose()) * 0.5
        };
        let eig = crate::linalg::symmetric3::eigenvalues(&h)?;
        let (lo, hi) = (eig[0], eig[2]);
        if hi <= 0.0 || lo < -PSD_TOLERANCE * hi {
            return Err(format!(
                "is not positive semidefinite (eigenvalues {:.3e}, {:.3e}, {:.3e})",
                eig[0], eig[1], eig[2]
            ));
        }
        if let Some(reason) = crate::validate::weight_out_of_range(h.trace()) {
            return Err(format!("trace: {reason}"));
        }
        Ok(Information {
            h,
            eigenvalues: eig,
            asymmetry,
        })
    }

    /// `sym(S^T H S)` for a rotation `S`, for a **solve** (a rig's frame step, `[H24]`): its
    /// eigenvalues are `H`'s, those of the exact congruence, not computed again to high
    /// relative accuracy (which took 44 % of a 2000-frame, 6-sensor rig's solve). A certificate
    /// builds its matrices with [`Self::new`], which computes them for the matrix it stores.
    pub(crate) fn turned_for_solve(&self, s: &Rotation) -> Self {
        let t = s.matrix().transpose() * self.h * s.matrix();
        Information {
            h: (t + t.transpose()) * 0.5,
            eigenvalues: self.eigenvalues,
            asymmetry: 0.0,
        }
    }

    /// `H = w I`: the isotropic measurement of weight `w` (its chordal cost is exactly the
    /// isotropic `w ||R_j - R_ij R_i||_F^2`).
    pub fn isotropic(w: f64) -> Result<Self> {
        Self::new(Matrix3::identity() * w)
    }

    /// The matrix `H` (the symmetric part of the matrix given).
    pub fn matrix(&self) -> &Matrix3<f64> {
        &self.h
    }

    /// `max |H - H^T| / max |H|` of the matrix as given: 0 when it was exactly symmetric, at
    /// most [`SYMMETRY_TOLERANCE`] (rounding; its symmetric part is [`Self::matrix`]).
    pub fn asymmetry(&self) -> f64 {
        self.asymmetry
    }

    /// `M = tr(H)/2 I - H`, the matrix of the chordal cost `[A1]` (indefinite when one
    /// eigenvalue of `H` exceeds the sum of the other two).
    pub fn chordal_matrix(&self) -> Matrix3<f64> {
        Matrix3::identity() * (0.5 * self.h.trace()) - self.h
    }

    /// `2M = tr(H) I - 2H`, as the Laplacian blocks use it `[A2]`.
    pub fn twice_chordal_matrix(&self) -> Matrix3<f64> {
        Matrix3::identity() * self.h.trace() - self.h * 2.0
    }

    /// The isotropic weight with the same trace, `tr(H) / 3` (the weight of spanning trees,
    /// spectral starts and preconditioners; never of a cost).
    pub fn mean_weight(&self) -> f64 {
        self.h.trace() / 3.0
    }

    /// The isotropic weight of a **start** (`[A17]`): `3 / tr(H^-1)`, the inverse of the
    /// measurement's mean variance (the harmonic mean of `H`'s eigenvalues, each at least
    /// [`START_WEIGHT_FLOOR`] times `tr(H) / 3`, so a singular `H` keeps a small weight). An edge
    /// with one weak axis weighs about three times that axis's information, not the mean of its
    /// strong ones: a spectral start by [`Self::mean_weight`] trusts the weak axes' noise as
    /// much as the strong axes' and, on chains of such edges, starts the local solve in another
    /// basin (a rig's 10^4-frame path graph: `J` 4.9e5 against 2.7e5).
    ///
    /// ```
    /// use rotavg::multiple::anisotropic::Information;
    /// use nalgebra::{Matrix3, Vector3};
    /// let h = Information::new(Matrix3::from_diagonal(&Vector3::new(100.0, 100.0, 1.0)))?;
    /// assert!((h.start_weight() - 3.0 / 1.02).abs() < 1e-12);
    /// assert!((Information::isotropic(2.5)?.start_weight() - 2.5).abs() < 1e-15);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn start_weight(&self) -> f64 {
        let floor = START_WEIGHT_FLOOR * self.mean_weight();
        let variance: f64 = self.eigenvalues.iter().map(|l| 1.0 / l.max(floor)).sum();
        3.0 / variance
    }

    /// `Some(w)` when `H` was given exactly as `w I` (symmetric, off-diagonal entries zero,
    /// diagonal equal) with `w` a valid scalar weight: then the anisotropic costs are exactly the
    /// isotropic costs with weight `w` (contract section 1), and
    /// [`crate::multiple::MultipleProblem::with_information`] keeps the weight instead.
    ///
    /// ```
    /// use rotavg::multiple::anisotropic::Information;
    /// use nalgebra::{Matrix3, Vector3};
    /// assert_eq!(Information::isotropic(2.5)?.scalar_weight(), Some(2.5));
    /// let h = Matrix3::from_diagonal(&Vector3::new(2.5, 2.5, 2.5 + 1e-15));
    /// assert_eq!(Information::new(h)?.scalar_weight(), None);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn scalar_weight(&self) -> Option<f64> {
        let w = exactly_isotropic(&self.h)?;
        (self.asymmetry == 0.0 && crate::validate::weight_out_of_range(w).is_none()).then_some(w)
    }

    /// The smallest positive eigenvalue of `H` (the tolerance's weight scale, contract section 3,
    /// `[A9]`, `[A12]`): the smallest **nonzero magnitude** of its eigenvalues, so that an
    /// accepted negative part (within [`PSD_TOLERANCE`]) counts with its size instead of leaving
    /// the scale to the larger ones; rounded **down** by the eigenvalues' relative accuracy
    /// ([`crate::linalg::symmetric3::RELATIVE_ACCURACY`]) so that it never loosens the
    /// tolerance, however far below `lambda_max` it lies (`diag(1e8, 1e8, 1e-8)` gives `1e-8`).
    /// Only an exact zero is left out.
    ///
    /// ```
    /// use rotavg::multiple::anisotropic::Information;
    /// use nalgebra::{Matrix3, Vector3};
    /// let h = Information::new(Matrix3::from_diagonal(&Vector3::new(1e8, 1e8, 1e-8)))?;
    /// assert!((h.min_positive_eigenvalue() / 1e-8 - 1.0).abs() < 1e-6);
    /// let singular = Information::new(Matrix3::from_diagonal(&Vector3::new(2.0, 0.0, 5.0)))?;
    /// assert!((singular.min_positive_eigenvalue() / 2.0 - 1.0).abs() < 1e-6);
    /// let rounded = Information::new(Matrix3::from_diagonal(&Vector3::new(1e8, 1e8, -1e-5)))?;
    /// assert!((rounded.min_positive_eigenvalue() / 1e-5 - 1.0).abs() < 1e-6);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn min_positive_eigenvalue(&self) -> f64 {
        let lowest = self
            .eigenvalues
            .iter()
            .map(|x| x.abs())
            .filter(|x| *x > 0.0)
            .fold(f64::INFINITY, f64::min);
        lowest * (1.0 - crate::linalg::symmetric3::RELATIVE_ACCURACY)
    }

    /// The eigenvalues of `H`, ascending, to high relative accuracy (`[A12]`).
    pub fn eigenvalues(&self) -> [f64; 3] {
        self.eigenvalues
    }

    /// `lambda_max(H) / lambda_min(H)` (infinite for a singular `H`): 1 for isotropic edges.
    pub fn anisotropy(&self) -> f64 {
        let [lo, _, hi] = self.eigenvalues;
        if lo > 0.0 { hi / lo } else { f64::INFINITY }
    }

    /// `true` when `M` is indefinite (an eigenvalue of `H` above the sum of the other two):
    /// such edges are what can make the `O(3)` relaxation prefer reflections `[A5]`.
    pub fn chordal_matrix_indefinite(&self) -> bool {
        self.chordal_matrix().symmetric_eigenvalues().min() < 0.0
    }

    /// `true` when `2M` ([`Self::twice_chordal_matrix`]) has an exactly zero row: the edge sees
    /// only two coordinates of its ends (information `w diag(1, 1, 0)` in the first node's
    /// frame, a soft gravity prior's edge to the world node, `paper-notes/gravity.md` `[G10]`).
    pub fn sees_two_coordinates(&self) -> bool {
        let m2 = self.twice_chordal_matrix();
        (0..3).any(|r| (0..3).all(|c| m2[(r, c)] == 0.0))
    }
}

/// The smallest eigenvalue [`Information::start_weight`] counts, relative to `tr(H) / 3`: a
/// singular `H` weighs about `3e-6` of its mean in a start (real two-view information reaches
/// eigenvalue ratios of ~1e5, above this floor).
pub const START_WEIGHT_FLOOR: f64 = 1e-6;

impl TryFrom<[[f64; 3]; 3]> for Information {
    type Error = String;
    fn try_from(rows: [[f64; 3]; 3]) -> std::result::Result<Self, String> {
        Self::check(Matrix3::from_fn(|a, b| rows[a][b]))
    }
}

impl From<Information> for [[f64; 3]; 3] {
    fn from(h: Information) -> Self {
        std::array::from_fn(|a| std::array::from_fn(|b| h.h[(a, b)]))
    }
}

/// What the reports say about a problem's information matrices.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InformationSummary {
    /// Edges with an information matrix (all of them).
    pub edges: usize,
    /// Median of `lambda_max(H) / lambda_min(H)` over the edges (infinite for singular `H`).
    pub median_anisotropy: f64,
    /// Largest `lambda_max(H) / lambda_min(H)`.
    pub max_anisotropy: f64,
    /// Edges whose `M = tr(H)/2 I - H` is indefinite (`[A5]`: where the `O(3)` relaxation may
    /// prefer reflections).
    pub indefinite_chordal_matrices: usize,
    /// `true` when every `H` was exactly `w I`: the problem is the isotropic one with weights
    /// `w`, solved and certified as such (contract section 1: `H = w I` gives exactly the
    /// isotropic cost).
    #[serde(default)]
    pub scalar_weights: bool,
}

impl InformationSummary {
    /// The summary of `info` (`None` when empty).
    pub fn of(info: &[Information]) -> Option<Self> {
        if info.is_empty() {
            return None;
        }
        let mut ratios: Vec<f64> = info.iter().map(Information::anisotropy).collect();
        ratios.sort_by(f64::total_cmp);
        Some(InformationSummary {
            edges: info.len(),
            median_anisotropy: ratios[ratios.len() / 2],
            max_anisotropy: ratios[ratios.len() - 1],
            indefinite_chordal_matrices: info
                .iter()
                .filter(|h| h.chordal_matrix_indefinite())
                .count(),
            scalar_weights: false,
        })
    }

    /// The summary of `edges` matrices that were all exactly `w I` (kept as scalar weights).
    pub fn isotropic(edges: usize) -> Self {
        InformationSummary {
            edges,
            median_anisotropy: 1.0,
            max_anisotropy: 1.0,
            indefinite_chordal_matrices: 0,
            scalar_weights: true,
        }
    }
}

impl std::fmt::Display for InformationSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "information: 3x3 on {} edges; anisotropy (eigenvalue max / min) median {:.3}, max {:.3}",
            self.edges, self.median_anisotropy, self.max_anisotropy
        )?;
        if self.scalar_weights {
            write!(
                f,
                "\n  every H is w I: solved and certified with scalar weights w"
            )?;
        }
        if self.indefinite_chordal_matrices > 0 {
            write!(
                f,
                "\n  {} edges with indefinite M: the O(3) relaxation may prefer reflections",
                self.indefinite_chordal_matrices
            )?;
        }
        Ok(())
    }
}

/// `B_e = R_i^T M R_ij^T R_j` `[A4]`: the edge's term is `4 tr M - 4 tr(B_e)`, its gradient
/// `grad_i = -8 vee(B_e)`, `grad_j = 8 vee(B_e)`.
pub fn edge_b(
    h: &Information,
    r_ij: &Matrix3<f64>,
    r_i: &Matrix3<f64>,
    r_j: &Matrix3<f64>,
) -> Matrix3<f64> {
    r_i.transpose() * h.chordal_matrix() * r_ij.transpose() * r_j
}

/// The anisotropic chordal term `4 (tr M - <R_ij M, R_j R_i^T>)` of one edge `[A1]`.
pub fn chordal_term(h: &Information, r_ij: &Rotation, r_i: &Rotation, r_j: &Rotation) -> f64 {
    let m = h.chordal_matrix();
    let gram = r_j.matrix() * r_i.matrix().transpose();
    4.0 * (m.trace() - (r_ij.matrix() * m).dot(&gram))
}

/// The anisotropic chordal cost of `edges` with information `info` at `rotations`, every product
/// of data entries accumulated in double-double and rounded once (`[A1]`, `[A2]`): the trace form
/// `4 (tr M - <R_ij M, R_j R_i^T>)` cancels to its small value, which plain floating point would
/// know only to `u tr(H)` per edge (a negative cost on noise-free data, and a gap of heavy
/// information off by more than the tolerance's absolute part). Expanded:
/// `2 tr H - 2 sum H_kk R_ij[a][b] R_j[a][d] R_i[b][d] + 4 sum R_ij[a][c] H_cb R_j[a][d] R_i[b][d]`.
/// Evaluated as `2 tr H - 2 tr H <R_ij, P> + 4 <R_ij H, P>` with `P = R_j R_i^T` and `R_ij H`
/// formed in double-double first (each entry a compensated sum of three exact products, error
/// `O(u^2)` of its terms): about 120 error-free products per edge instead of the expansion's
/// 486 (`--information full` on mrob/sphere spent 94 M of its 322 M certify instructions here).
pub(crate) fn chordal_cost_compensated(
    edges: &[crate::multiple::Edge],
    info: &[Information],
    rotations: &[Rotation],
) -> f64 {
    use crate::linalg::compensated::Accumulator;
    let mut acc = Accumulator::default();
    for (e, h) in edges.iter().zip(info) {
        let (h, r) = (h.matrix(), e.rotation.matrix());
        let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
        let p = product_dd(|a, b, d| (rj[(a, d)], ri[(b, d)]));
        // tr E = <R_ij, P> for E = R_ij^T R_j R_i^T
        let mut tr_e = Accumulator::default();
        for (a, b) in (0..3).flat_map(|a| (0..3).map(move |b| (a, b))) {
            let (hi, lo) = p[a][b];
            tr_e.add_product(r[(a, b)], hi);
            tr_e.add_product(r[(a, b)], lo);
        }
        let (te_hi, te_lo) = tr_e.parts();
        if let Some(w) = exactly_isotropic(h) {
            // H = w I: 6 w - 6 w tr E + 4 w tr E, the same sum without R_ij H
            acc.add_product(6.0, w);
            acc.add_product(-2.0 * w, te_hi);
            acc.add_product(-2.0 * w, te_lo);
            continue;
        }
        let m = product_dd(|a, b, c| (r[(a, c)], h[(c, b)]));
        for k in 0..3 {
            acc.add_product(2.0, h[(k, k)]);
            acc.add_product(-2.0 * h[(k, k)], te_hi);
            acc.add_product(-2.0 * h[(k, k)], te_lo);
        }
        // 4 <H, E> = 4 <R_ij H, P>
        for (a, b) in (0..3).flat_map(|a| (0..3).map(move |b| (a, b))) {
            let ((mh, ml), (ph, pl)) = (m[a][b], p[a][b]);
            for (x, y) in [(mh, ph), (mh, pl), (ml, ph), (ml, pl)] {
                acc.add_product(4.0 * x, y);
            }
        }
    }
    acc.value()
}

/// `Some(w)` when `h` is exactly `w I` (its off-diagonal entries zero, its diagonal equal).
pub(crate) fn exactly_isotropic(h: &Matrix3<f64>) -> Option<f64> {
    let w = h[(0, 0)];
    let diagonal = (0..3).all(|r| (0..3).all(|c| r == c || h[(r, c)] == 0.0));
    (diagonal && h[(1, 1)] == w && h[(2, 2)] == w).then_some(w)
}

/// The entries `sum_d x_abd y_abd` of a 3 x 3 product, `(x, y) = f(a, b, d)`, each as an
/// unevaluated double-double pair.
fn product_dd(f: impl Fn(usize, usize, usize) -> (f64, f64)) -> [[(f64, f64); 3]; 3] {
    std::array::from_fn(|a| {
        std::array::from_fn(|b| {
            let mut s = crate::linalg::compensated::Accumulator::default();
            for d in 0..3 {
                let (x, y) = f(a, b, d);
                s.add_product(x, y);
            }
            s.parts()
        })
    })
}

/// The anisotropic geodesic term `e^T H e`, `e = log(R_ij^T R_j R_i^T)` `[A8]`.
pub fn geodesic_term(h: &Information, r_ij: &Rotation, r_i: &Rotation, r_j: &Rotation) -> f64 {
    let e = log(&(r_ij.inverse() * r_j * r_i.inverse()));
    e.dot(&(h.matrix() * e))
}

/// The Mahalanobis angle `theta_H = sqrt(e^T H e / wbar)` of an edge, `wbar = tr(H) / 3` its
/// mean weight `[A10]`: the residual angle in the units of the edge's mean noise, equal to the
/// residual angle `theta` when `H = w I`. The anisotropic geodesic cost is `sum wbar theta_H^2 =
/// sum e^T H e`, and every loss applies to it (`sum wbar rho(theta_H)`), so the losses' thresholds
/// keep their meaning in degrees.
pub fn mahalanobis_angle(h: &Information, r_ij: &Rotation, r_i: &Rotation, r_j: &Rotation) -> f64 {
    (geodesic_term(h, r_ij, r_i, r_j) / h.mean_weight())
        .max(0.0)
        .sqrt()
}

/// One edge of the anisotropic geodesic costs, linearised `[A10]`.
pub(crate) struct GeodesicEdge {
    /// `theta_H` ([`mahalanobis_angle`]).
    pub angle: f64,
    /// `H e`.
    pub he: Vector3<f64>,
    /// `G = J_r^{-1}(e) R_i`: under `R_k -> R_k exp(hat w_k)`, `e -> e + G (w_j - w_i) + O(|w|^2)`.
    pub g: Matrix3<f64>,
}

/// [`GeodesicEdge`] of the edge `(i, j)` with information `h`.
pub(crate) fn geodesic_edge(
    h: &Information,
    r_ij: &Rotation,
    r_i: &Rotation,
    r_j: &Rotation,
) -> GeodesicEdge {
    let e = log(&(r_ij.inverse() * r_j * r_i.inverse()));
    let he = h.matrix() * e;
    GeodesicEdge {
        angle: (e.dot(&he) / h.mean_weight()).max(0.0).sqrt(),
        he,
        g: right_jacobian_inverse(&e) * r_i.matrix(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3::{exp, random_rotation};
    use rand::SeedableRng;

    /// The solve's turned information is the matrix [`Information::new`] validates, bit for
    /// bit, and its eigenvalues (taken from `H`) are those computed afresh for that matrix, to
    /// `1e-12` of `lambda_max` (the congruence by a rotation keeps them; rounding moves them by
    /// a few `u lambda_max`), on spreads `1` to `1e8`.
    #[test]
    fn turned_information_keeps_its_eigenvalues() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        for spread in [1.0_f64, 1e2, 1e4, 1e8] {
            for _ in 0..20 {
                let q = random_rotation(&mut rng);
                let d = Matrix3::from_diagonal(&Vector3::new(1.0, spread.sqrt(), spread));
                let m = q.matrix() * d * q.matrix().transpose();
                let h = Information::new((m + m.transpose()) * 0.5).unwrap();
                let s = random_rotation(&mut rng);
                let turned = h.turned_for_solve(&s);
                let t = s.matrix().transpose() * h.matrix() * s.matrix();
                let fresh = Information::new((t + t.transpose()) * 0.5).unwrap();
                assert_eq!(turned.matrix(), fresh.matrix());
                for (a, b) in turned.eigenvalues().iter().zip(fresh.eigenvalues()) {
                    assert!(
                        (a - b).abs() <= 1e-12 * spread,
                        "{a} against {b} at {spread}"
                    );
                }
            }
        }
    }

    /// `H = w I` reproduces the isotropic chordal term to rounding (`[A1]`), for any rotations.
    #[test]
    fn isotropic_information_is_the_isotropic_cost() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        for k in 0..50 {
            let w = 0.1 + k as f64;
            let (r_ij, r_i, r_j) = (
                random_rotation(&mut rng),
                random_rotation(&mut rng),
                random_rotation(&mut rng),
            );
            let iso = w * (r_j.matrix() - r_ij.matrix() * r_i.matrix()).norm_squared();
            let an = chordal_term(&Information::isotropic(w).unwrap(), &r_ij, &r_i, &r_j);
            assert!((iso - an).abs() <= 1e-13 * w * 8.0, "{iso} vs {an}");
        }
    }

    /// The closed form `4 (1 - cos theta) u^T H u` `[A1]` with a random PSD `H` and a planted
    /// residual (written independently of `chordal_term`).
    #[test]
    fn chordal_term_closed_form() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for k in 0..50 {
            let a = Matrix3::from_fn(|p, q| ((p * 7 + q * 3 + k) % 5) as f64 - 2.0);
            let h = Information::new(a * a.transpose() + Matrix3::identity() * 0.01).unwrap();
            let e = Vector3::new(0.3, -1.1, 0.7) * (k as f64 / 20.0 + 0.01);
            let (r_ij, r_i) = (random_rotation(&mut rng), random_rotation(&mut rng));
            let r_j = r_ij * exp(&e) * r_i;
            let (t, u) = (e.norm(), e.normalize());
            let closed = 4.0 * (1.0 - t.cos()) * u.dot(&(h.matrix() * u));
            let f = chordal_term(&h, &r_ij, &r_i, &r_j);
            assert!(
                (f - closed).abs() <= 1e-11 * (1.0 + closed),
                "{f} vs {closed}"
            );
        }
    }

    /// The double-double cost is exact where the exact value is known: noise-free edges between
    /// rotations whose entries are 0 or +-1 (exactly orthogonal in floating point) cost exactly
    /// 0 for any information, while the plain trace form rounds `tr(H)`-sized terms.
    #[test]
    fn compensated_cost_is_exact_on_exact_data() {
        use crate::multiple::{Edge, MultipleProblem};
        let quarter = |v: Vector3<f64>| {
            let r = exp(&(v * std::f64::consts::FRAC_PI_2));
            Rotation::from_matrix_unchecked(r.matrix().map(|x| x.round()))
        };
        let truth = [
            Rotation::identity(),
            quarter(Vector3::x()),
            quarter(Vector3::y()),
            quarter(Vector3::z()) * quarter(Vector3::x()),
            quarter(-Vector3::y()) * quarter(Vector3::z()),
        ];
        let mut edges = Vec::new();
        let mut info = Vec::new();
        let mut plain = 0.0;
        for i in 0..5 {
            for j in (i + 1)..5 {
                let a =
                    Matrix3::from_fn(|p, q| ((p * 3 + q + i * 7 + j) as f64 * 0.37).sin() * 1e3);
                let h = Information::new(a * a.transpose() + Matrix3::identity() * 0.1).unwrap();
                let rotation = truth[j] * truth[i].inverse();
                plain += chordal_term(&h, &rotation, &truth[i], &truth[j]);
                edges.push(Edge {
                    i,
                    j,
                    rotation,
                    weight: 1.0,
                });
                info.push(h);
            }
        }
        let p = MultipleProblem::new(5, edges)
            .unwrap()
            .with_information(info)
            .unwrap();
        assert_eq!(p.chordal_cost(&truth), 0.0, "plain trace form: {plain:e}");
    }
}

#[cfg(test)]
mod chordal_cost_tests {
    use super::*;
    use crate::multiple::Edge;
    use crate::so3::{exp, random_rotation};
    use nalgebra::Vector3;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// The expansion the evaluation replaced, every term an exact quadruple product summed in
    /// double-double: an independent reference.
    fn expanded(edges: &[Edge], info: &[Information], rotations: &[Rotation]) -> f64 {
        let mut acc = crate::linalg::compensated::Accumulator::default();
        for (e, h) in edges.iter().zip(info) {
            let (h, r) = (h.matrix(), e.rotation.matrix());
            let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
            for k in 0..3 {
                acc.add_product(2.0, h[(k, k)]);
            }
            for a in 0..3 {
                for b in 0..3 {
                    for d in 0..3 {
                        let (x, y) = (rj[(a, d)], ri[(b, d)]);
                        for k in 0..3 {
                            acc.add_quad(-2.0 * h[(k, k)], r[(a, b)], x, y);
                        }
                        for c in 0..3 {
                            acc.add_quad(4.0 * h[(c, b)], r[(a, c)], x, y);
                        }
                    }
                }
            }
        }
        acc.value()
    }

    /// The double-double evaluation agrees with the expansion to the final rounding, on noise
    /// from 0 (the cost cancels to the rounding of the data) to 0.1 rad and information spreads
    /// up to 1e8 (spread 0: exactly `2.5 I`, the isotropic path), including measurements off
    /// SO(3) by 1e-9.
    #[test]
    fn chordal_cost_compensated_matches_the_expansion() {
        let mut rng = StdRng::seed_from_u64(11);
        for noise in [0.0, 1e-9, 1e-6, 1e-3, 0.1] {
            for spread in [0.0f64, 1.0, 1e4, 1e8] {
                let n = 6;
                let truth: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
                let mut edges = Vec::new();
                let mut info = Vec::new();
                for i in 0..n {
                    for j in i + 1..n {
                        let e = Vector3::from_fn(|_, _| noise * (rng.random::<f64>() - 0.5));
                        let mut r = exp(&e) * truth[j] * truth[i].inverse();
                        let defect = Matrix3::from_fn(|_, _| 1e-9 * (rng.random::<f64>() - 0.5));
                        r = Rotation::from_matrix_unchecked(r.matrix() + defect);
                        edges.push(Edge {
                            i,
                            j,
                            rotation: r,
                            weight: 1.0,
                        });
                        let q = random_rotation(&mut rng);
                        let d = Matrix3::from_diagonal(&Vector3::new(1.0, spread.sqrt(), spread));
                        let h = if spread == 0.0 {
                            Matrix3::identity() * 2.5
                        } else {
                            q.matrix() * d * q.matrix().transpose()
                        };
                        info.push(Information::new((h + h.transpose()) * 0.5).unwrap());
                    }
                }
                let new = chordal_cost_compensated(&edges, &info, &truth);
                let old = expanded(&edges, &info, &truth);
                let scale: f64 = info.iter().map(|h| h.matrix().trace()).sum();
                let tol = 4.0 * f64::EPSILON * old.abs() + 1e-28 * scale;
                assert!(
                    (new - old).abs() <= tol,
                    "noise {noise}, spread {spread}: {new} vs {old}"
                );
            }
        }
    }
}
