//! SO(3) primitives: hat/vee, exp/log, angles and the three distances, projection onto SO(3),
//! validation of user rotations, and seeded random rotations for tests, examples and the demo.
//!
//! Equations are stated in `paper-notes/conventions.md` (labels `[C1]`..`[C6]`).
//!
//! - Maps: [`hat`], [`vee`], [`exp`], [`log`] (accurate near 0 and pi), [`angle`].
//! - Distances: [`angle_between`], [`chordal_distance`], [`quaternion_distance`], or
//!   [`Metric::distance`] / [`Metric::from_angle`].
//! - Matrices from users: [`project_to_so3`], [`nearest_rotation`] (every returned estimate),
//!   [`rotation_from_matrix`] and
//!   [`rotation_from_rows`] (validation at [`DEFAULT_ROTATION_TOLERANCE`]), [`rotation_to_rows`].
//! - Seeded randomness: [`random_rotation`], [`perturb`] (exact angle), [`perturb_gaussian`].
//!
//! ```
//! use rotavg::so3::{angle_between, exp, log, Metric};
//! use nalgebra::Vector3;
//! let r = exp(&Vector3::new(0.0, 0.0, 0.5));
//! let s = exp(&Vector3::new(0.0, 0.0, -0.5));
//! assert!((angle_between(&r, &s) - 1.0).abs() < 1e-12);
//! assert!((Metric::Chordal.distance(&r, &s) - Metric::Chordal.from_angle(1.0)).abs() < 1e-12);
//! assert!((log(&r) - Vector3::new(0.0, 0.0, 0.5)).norm() < 1e-15);
//! ```

pub mod serde_rows;

use crate::error::{Error, Result};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// The public rotation type: a 3x3 orthogonal matrix with determinant +1.
pub type Rotation = Rotation3<f64>;

/// Default tolerance for accepting a user matrix as a rotation: `||R^T R - I||_F <= tol` and
/// `|det R - 1| <= tol`. Real data files are orthonormal to ~3e-6 (1DSfM) and quaternions
/// are printed to ~1e-7, hence 1e-5.
pub const DEFAULT_ROTATION_TOLERANCE: f64 = 1e-5;

/// The distance used to compare two rotations (contract section 1, `[C2]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Metric {
    /// Angle (geodesic) distance `theta(R, S)`.
    Geodesic,
    /// Chordal distance `||R - S||_F = 2 sqrt(2) sin(theta / 2)`.
    #[default]
    Chordal,
    /// Quaternion distance `min ||q_R -+ q_S|| = 2 sin(theta / 4)`.
    Quaternion,
}

impl Metric {
    /// Distance between `r` and `s` under this metric.
    ///
    /// ```
    /// use rotavg::so3::{exp, Metric};
    /// use nalgebra::Vector3;
    /// let r = exp(&Vector3::new(0.0, 0.0, 0.5));
    /// let s = exp(&Vector3::new(0.0, 0.0, -0.25));
    /// assert!((Metric::Geodesic.distance(&r, &s) - 0.75).abs() < 1e-12);
    /// ```
    pub fn distance(self, r: &Rotation, s: &Rotation) -> f64 {
        match self {
            Metric::Geodesic => angle_between(r, s),
            Metric::Chordal => chordal_distance(r, s),
            Metric::Quaternion => quaternion_distance(r, s),
        }
    }

    /// The distance as a function of the angle `theta` between the two rotations `[C2]`.
    ///
    /// ```
    /// use rotavg::so3::{chordal_distance, exp, Metric};
    /// use nalgebra::Vector3;
    /// // A quarter turn: chordal distance 2 sqrt(2) sin(pi/4) = 2.
    /// let theta = std::f64::consts::FRAC_PI_2;
    /// assert!((Metric::Chordal.from_angle(theta) - 2.0).abs() < 1e-12);
    /// let r = exp(&Vector3::new(theta, 0.0, 0.0));
    /// assert!((chordal_distance(&r, &rotavg::Rotation::identity()) - 2.0).abs() < 1e-12);
    /// ```
    pub fn from_angle(self, theta: f64) -> f64 {
        match self {
            Metric::Geodesic => theta,
            Metric::Chordal => 2.0 * std::f64::consts::SQRT_2 * (theta / 2.0).sin(),
            Metric::Quaternion => 2.0 * (theta / 4.0).sin(),
        }
    }
}

impl std::fmt::Display for Metric {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Metric::Geodesic => "geodesic",
            Metric::Chordal => "chordal",
            Metric::Quaternion => "quaternion",
        })
    }
}

/// `hat(v)`: the skew-symmetric matrix with `hat(v) w = v x w` `[C1]`.
///
/// ```
/// use rotavg::so3::{hat, vee};
/// use nalgebra::Vector3;
/// let v = Vector3::new(1.0, 2.0, 3.0);
/// assert_eq!(vee(&hat(&v)), v);
/// ```
pub fn hat(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// `vee(M)`: the vector of the skew-symmetric part of `M` (inverse of [`hat`] on so(3)).
pub fn vee(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
    )
}

/// Exponential map `exp(hat(v))` (Rodrigues, with Taylor series for small `|v|`) `[C3]`.
///
/// ```
/// use rotavg::so3::{exp, log};
/// use nalgebra::Vector3;
/// let v = Vector3::new(0.3, -0.2, 1.1);
/// assert!((log(&exp(&v)) - v).norm() < 1e-14);
/// ```
pub fn exp(v: &Vector3<f64>) -> Rotation {
    let t2 = v.norm_squared();
    let t = t2.sqrt();
    let (a, b) = if t < 1e-4 {
        // sin(t)/t and (1 - cos t)/t^2 to O(t^6)
        (
            1.0 - t2 / 6.0 + t2 * t2 / 120.0,
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
        )
    } else {
        (t.sin() / t, (1.0 - t.cos()) / t2)
    };
    let k = hat(v);
    Rotation3::from_matrix_unchecked(Matrix3::identity() + k * a + k * k * b)
}

/// Rotation angle of `r` in `[0, pi]`, accurate near 0 and near pi `[C4]`:
/// `theta = atan2(||vee(R - R^T)||, tr R - 1)`.
///
/// ```
/// use rotavg::so3::{angle, exp};
/// use nalgebra::Vector3;
/// assert!((angle(&exp(&Vector3::new(0.0, 3.0, 0.0))) - 3.0).abs() < 1e-12);
/// // exp of a vector of length 4 > pi is the rotation by 2 pi - 4 about the opposite axis.
/// let t = 2.0 * std::f64::consts::PI - 4.0;
/// assert!((angle(&exp(&Vector3::new(4.0, 0.0, 0.0))) - t).abs() < 1e-12);
/// ```
pub fn angle(r: &Rotation) -> f64 {
    let m = r.matrix();
    let s = vee(m).norm(); // sin(theta)
    let c = 0.5 * (m.trace() - 1.0); // cos(theta)
    s.atan2(c).clamp(0.0, PI)
}

/// `theta(R, S)`: the angle of `R^T S`, in `[0, pi]`.
///
/// ```
/// use rotavg::so3::{angle_between, exp};
/// use nalgebra::Vector3;
/// let r = exp(&Vector3::new(0.0, 0.0, 0.25));
/// let s = exp(&Vector3::new(0.0, 0.0, 1.0));
/// assert!((angle_between(&r, &s) - 0.75).abs() < 1e-12);
/// assert!((angle_between(&r, &s) - angle_between(&s, &r)).abs() < 1e-15);
/// ```
pub fn angle_between(r: &Rotation, s: &Rotation) -> f64 {
    angle(&(r.inverse() * s))
}

/// Chordal distance `||R - S||_F`.
pub fn chordal_distance(r: &Rotation, s: &Rotation) -> f64 {
    (r.matrix() - s.matrix()).norm()
}

/// Quaternion distance `min(||q_R - q_S||, ||q_R + q_S||) = 2 sin(theta / 4)`, evaluated as
/// `2 sin(theta / 4)` of the angle `theta` of [`angle_between`] (contract section 1: every distance
/// is a function of `theta`), so that it is defined by the same formula for a matrix that is a
/// rotation only to the validation tolerance (its proven perturbation bound is the angle's,
/// `paper-notes/branch_and_bound.md` `[B6]`).
///
/// ```
/// use rotavg::so3::{exp, quaternion_distance, Metric};
/// use nalgebra::Vector3;
/// // Near pi the quaternion distance 2 sin(theta/4) -> sqrt(2), whichever sign the
/// // quaternions have.
/// let r = exp(&Vector3::new(0.0, 3.1, 0.0));
/// let d = quaternion_distance(&r, &rotavg::Rotation::identity());
/// assert!((d - Metric::Quaternion.from_angle(3.1)).abs() < 1e-12);
/// // small angles keep their relative accuracy
/// let t = exp(&Vector3::new(1e-9, 0.0, 0.0));
/// assert!((quaternion_distance(&t, &rotavg::Rotation::identity()) / 5e-10 - 1.0).abs() < 1e-9);
/// ```
pub fn quaternion_distance(r: &Rotation, s: &Rotation) -> f64 {
    Metric::Quaternion.from_angle(angle_between(r, s))
}

/// Logarithm map: the vector `v` with `exp(hat(v)) = R` and `|v| = theta in [0, pi]` `[C3]`.
/// Accurate near `theta = 0` (first-order series) and near `theta = pi` (axis from the symmetric
/// part `R + R^T`, sign from the skew part). At exactly `theta = pi` either sign is a valid
/// logarithm; one is returned.
///
/// ```
/// use rotavg::so3::{exp, log};
/// use nalgebra::Vector3;
/// // near pi
/// let v = Vector3::new(1.0, 2.0, -0.5).normalize() * (std::f64::consts::PI - 1e-9);
/// assert!((log(&exp(&v)) - v).norm() < 1e-7);
/// ```
pub fn log(r: &Rotation) -> Vector3<f64> {
    let m = r.matrix();
    let w = vee(m); // sin(theta) * axis
    let s = w.norm();
    let c = 0.5 * (m.trace() - 1.0);
    let theta = s.atan2(c);
    if theta < 1e-4 {
        // theta / sin(theta) = 1 + theta^2 / 6 + ...
        return w * (1.0 + theta * theta / 6.0);
    }
    if theta < PI - 1e-3 {
        return w * (theta / s);
    }
    // Near pi: (R + R^T)/2 = cos(t) I + (1 - cos t) a a^T.
    let sym = (m + m.transpose()) * 0.5;
    let one_minus_c = 1.0 - c;
    let d = Vector3::new(sym[(0, 0)] - c, sym[(1, 1)] - c, sym[(2, 2)] - c) / one_minus_c;
    let k = d.imax();
    let mut axis = sym.column(k).into_owned() / one_minus_c;
    axis[k] = d[k];
    // axis ~ a * a_k; normalise.
    let n = axis.norm();
    if n == 0.0 || !n.is_finite() {
        return Vector3::new(theta, 0.0, 0.0);
    }
    axis /= n;
    // Sign: sin(theta) * axis = w.
    if axis.dot(&w) < 0.0 {
        axis = -axis;
    }
    axis * theta
}

/// Inverse right Jacobian `J_r^{-1}(v)` of SO(3) `[C3]`: for small `d`,
/// `log(exp(hat v) exp(hat d)) = v + J_r^{-1}(v) d + O(|d|^2)`, with
/// `J_r^{-1}(v) = I + hat(v) / 2 + (1/t^2 - (1 + cos t) / (2 t sin t)) hat(v)^2`, `t = |v| < pi`
/// (the last coefficient by its series `1/12 + t^2/720 + t^4/30240` for `t < 1e-2`). It fixes
/// `v` (`J_r^{-1}(v) v = v`). At `t = pi`, where the logarithm is not differentiable, `sin t`
/// is floored at `1e-12`: the result is large but finite.
///
/// ```
/// use rotavg::so3::{exp, log, right_jacobian_inverse};
/// use nalgebra::Vector3;
/// let (v, d) = (Vector3::new(0.4, -1.1, 0.7), Vector3::new(1e-7, -2e-7, 3e-7));
/// let moved = log(&(exp(&v) * exp(&d)));
/// assert!((moved - v - right_jacobian_inverse(&v) * d).norm() < 1e-12);
/// assert!((right_jacobian_inverse(&v) * v - v).norm() < 1e-14);
/// ```
pub fn right_jacobian_inverse(v: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = v.norm_squared();
    let t = t2.sqrt();
    let c = if t < 1e-2 {
        1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    } else {
        1.0 / t2 - (1.0 + t.cos()) / (2.0 * t * t.sin().max(1e-12))
    };
    let k = hat(v);
    Matrix3::identity() + k * 0.5 + k * k * c
}

/// The unit quaternion of a rotation (Hamilton convention, nalgebra's).
pub fn to_quaternion(r: &Rotation) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(r)
}

/// Nearest rotation to `m` in the Frobenius norm: `U diag(1, 1, det(U V^T)) V^T` from the SVD
/// `m = U S V^T` (determinant-corrected) `[C5]`, in SO(3) to rounding (`||R^T R - I||_F` and
/// `|det R - 1|` of a few 1e-16, [`NEARLY_ORTHOGONAL`]). Returns `None` when `m` has a non-finite
/// entry. For rank-deficient `m` the result is one of the (non-unique) minimisers.
///
/// ```
/// use rotavg::so3::{exp, project_to_so3};
/// use nalgebra::Vector3;
/// let r = exp(&Vector3::new(0.1, 0.2, 0.3));
/// let p = project_to_so3(&(r.matrix() * 2.5)).unwrap();
/// assert!((p.matrix() - r.matrix()).norm() < 1e-12);
/// ```
pub fn project_to_so3(m: &Matrix3<f64>) -> Option<Rotation> {
    if !m.iter().all(|x| x.is_finite()) {
        return None;
    }
    let (orth, det) = rotation_defect(m);
    let start = if orth <= NEARLY_ORTHOGONAL && det > 0.0 {
        *m
    } else {
        let svd = m.svd(true, true);
        let u = svd.u?;
        let vt = svd.v_t?;
        let mut d = Matrix3::identity();
        if (u * vt).determinant() < 0.0 {
            d[(2, 2)] = -1.0; // nalgebra sorts singular values descending: flip the smallest.
        }
        u * d * vt
    };
    Some(Rotation3::from_matrix_unchecked(newton_schulz_polar(start)))
}

/// A matrix with `||M^T M - I||_F <= NEARLY_ORTHOGONAL` and `det M > 0` is projected `[C5]` by
/// the Newton-Schulz (Bjorck) iteration `X <- X (3 I - X^T X) / 2` from `M` alone: it keeps the
/// singular vectors and maps each singular value `s` (here in `[0.94, 1.05]`) to
/// `s (3 - s^2) / 2`, which converges quadratically to 1, so the limit is the polar factor
/// `U V^T` of `M`, a rotation since `det M > 0` (five steps from this bound, three from the
/// validation tolerance, about 0.1 us against 1 us for the SVD). Other matrices go through the
/// SVD first, and that result (orthogonal to about 4e-15) gets the same steps.
pub const NEARLY_ORTHOGONAL: f64 = 0.1;

/// The Newton-Schulz iteration of [`NEARLY_ORTHOGONAL`] until `||X^T X - I||_F` is at the
/// rounding level (at least one step, at most 8).
fn newton_schulz_polar(mut x: Matrix3<f64>) -> Matrix3<f64> {
    for _ in 0..8 {
        let g = x.transpose() * x;
        let defect = (g - Matrix3::identity()).norm();
        x = x * (Matrix3::identity() * 3.0 - g) * 0.5;
        // the step from a defect d leaves about 3 d^2 / 4 plus rounding
        if defect <= 1e-9 {
            break;
        }
    }
    x
}

/// The rotation nearest to `r`, in SO(3) to rounding (about 1e-16 in `||R^T R - I||_F` and
/// `det`): [`project_to_so3`] of its matrix, `r` itself when that is not finite. For matrices
/// that are rotations only approximately: a measurement accepted within the validation
/// tolerance, products of such (a spanning-tree start), a start read from a file, an iterate
/// after many steps. Every estimate rotavg returns passes through it (contract section 1): the
/// unknowns are rotations, whatever the defect of the data (the data themselves are used as
/// given, `[C6]`).
///
/// ```
/// use rotavg::so3::{nearest_rotation, rotation_defect, exp};
/// use nalgebra::Vector3;
/// let r = exp(&Vector3::new(0.3, -1.2, 0.4));
/// // a product of measurements orthogonal to 1e-5 only
/// let m = rotavg::Rotation::from_matrix_unchecked(r.matrix() * (1.0 + 1e-5));
/// let p = nearest_rotation(&m);
/// let (orth, det) = rotation_defect(p.matrix());
/// assert!(orth < 1e-15 && (det - 1.0).abs() < 1e-15);
/// assert!((p.matrix() - r.matrix()).norm() < 1e-15);
/// ```
pub fn nearest_rotation(r: &Rotation) -> Rotation {
    project_to_so3(r.matrix()).unwrap_or(*r)
}

/// `||R^T R - I||_F` and `det R` of a matrix: how far it is from being a rotation.
///
/// ```
/// use nalgebra::Matrix3;
/// let (orth, det) = rotavg::so3::rotation_defect(&(Matrix3::identity() * 2.0));
/// assert!((orth - 3f64.sqrt() * 3.0).abs() < 1e-12 && (det - 8.0).abs() < 1e-12);
/// ```
pub fn rotation_defect(m: &Matrix3<f64>) -> (f64, f64) {
    (
        (m.transpose() * m - Matrix3::identity()).norm(),
        m.determinant(),
    )
}

/// Accept `m` as a rotation when it is finite, `||m^T m - I||_F <= tol` and `|det m - 1| <= tol`
/// `[C6]`. The accepted matrix is kept **as given**, not replaced by its nearest rotation: every
/// cost and bound is then that of the data in the file (contract section 3), and the certificates
/// carry the matrix's defect exactly (`paper-notes/single.md` `[S1]`,
/// `paper-notes/certificates.md` `[D4]`, `paper-notes/branch_and_bound.md` `[B6]`).
/// `item` names the matrix in the error message (e.g. `"edge 12"`).
///
/// ```
/// use rotavg::so3::{rotation_from_matrix, DEFAULT_ROTATION_TOLERANCE};
/// use nalgebra::Matrix3;
/// assert!(rotation_from_matrix(&Matrix3::identity(), DEFAULT_ROTATION_TOLERANCE, "I").is_ok());
/// let reflection = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, -1.0));
/// assert!(rotation_from_matrix(&reflection, DEFAULT_ROTATION_TOLERANCE, "F").is_err());
/// // within the tolerance, the matrix is kept exactly as given
/// let nearly = Matrix3::identity() * (1.0 - 2.8e-6);
/// let r = rotation_from_matrix(&nearly, DEFAULT_ROTATION_TOLERANCE, "R")?;
/// assert_eq!(*r.matrix(), nearly);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn rotation_from_matrix(m: &Matrix3<f64>, tol: f64, item: &str) -> Result<Rotation> {
    if !m.iter().all(|x| x.is_finite()) {
        return Err(Error::NonFinite {
            item: item.to_owned(),
        });
    }
    let (orth, det) = rotation_defect(m);
    if !(orth <= tol && (det - 1.0).abs() <= tol) {
        return Err(Error::NotARotation {
            item: item.to_owned(),
            orthogonality_error: orth,
            determinant: det,
            tolerance: tol,
        });
    }
    Ok(Rotation3::from_matrix_unchecked(*m))
}

/// Build a rotation from a row-major 3x3 array (the JSON layout), validating it.
///
/// ```
/// use rotavg::so3::{rotation_from_rows, rotation_to_rows, DEFAULT_ROTATION_TOLERANCE};
/// // A quarter turn about z, row-major: (1, 0, 0) -> (0, 1, 0).
/// let rows = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
/// let r = rotation_from_rows(&rows, DEFAULT_ROTATION_TOLERANCE, "example")?;
/// assert!((r * nalgebra::Vector3::x() - nalgebra::Vector3::y()).norm() < 1e-15);
/// assert_eq!(rotation_to_rows(&r), rows); // kept exactly as given
/// // A matrix that is not a rotation is rejected and named in the error.
/// let err = rotation_from_rows(&[[1.0, 0.0, 0.0]; 3], DEFAULT_ROTATION_TOLERANCE, "edge 7");
/// assert!(err.unwrap_err().to_string().starts_with("edge 7 is not a rotation"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn rotation_from_rows(rows: &[[f64; 3]; 3], tol: f64, item: &str) -> Result<Rotation> {
    let m = Matrix3::from_fn(|i, j| rows[i][j]);
    rotation_from_matrix(&m, tol, item)
}

/// Row-major 3x3 array of a rotation (the JSON layout).
pub fn rotation_to_rows(r: &Rotation) -> [[f64; 3]; 3] {
    let m = r.matrix();
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

/// A uniformly (Haar) distributed random rotation (Shoemake's subgroup algorithm).
///
/// ```
/// use rand::SeedableRng;
/// let mut rng = rand::rngs::StdRng::seed_from_u64(7);
/// let r = rotavg::so3::random_rotation(&mut rng);
/// assert!((r.matrix().determinant() - 1.0).abs() < 1e-12);
/// ```
pub fn random_rotation<R: Rng + ?Sized>(rng: &mut R) -> Rotation {
    let u1: f64 = rng.random();
    let u2: f64 = rng.random::<f64>() * 2.0 * PI;
    let u3: f64 = rng.random::<f64>() * 2.0 * PI;
    let a = (1.0 - u1).sqrt();
    let b = u1.sqrt();
    let q = nalgebra::Quaternion::new(b * u3.cos(), a * u2.sin(), a * u2.cos(), b * u3.sin());
    UnitQuaternion::from_quaternion(q).to_rotation_matrix()
}

/// A uniformly distributed unit vector.
pub fn random_unit_vector<R: Rng + ?Sized>(rng: &mut R) -> Vector3<f64> {
    let z: f64 = rng.random::<f64>() * 2.0 - 1.0;
    let phi: f64 = rng.random::<f64>() * 2.0 * PI;
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vector3::new(s * phi.cos(), s * phi.sin(), z)
}

/// `R exp(angle * hat(a))` for a uniformly random unit axis `a`: a rotation at exactly angle
/// `angle` (radians, in `[0, pi]`) from `r`.
///
/// ```
/// use rand::SeedableRng;
/// use rotavg::so3::{angle_between, perturb, random_rotation};
/// let mut rng = rand::rngs::StdRng::seed_from_u64(3);
/// let r = random_rotation(&mut rng);
/// let s = perturb(&r, 0.4, &mut rng);
/// assert!((angle_between(&r, &s) - 0.4).abs() < 1e-12);
/// ```
pub fn perturb<R: Rng + ?Sized>(r: &Rotation, angle: f64, rng: &mut R) -> Rotation {
    r * exp(&(random_unit_vector(rng) * angle))
}

/// `R exp(hat(w))` with `w` isotropic Gaussian of standard deviation `sigma` (radians) per
/// component: the usual noise model for synthetic data.
///
/// ```
/// use rand::SeedableRng;
/// use rotavg::so3::{angle_between, perturb_gaussian, Rotation};
/// let mut rng = rand::rngs::StdRng::seed_from_u64(4);
/// let id = Rotation::identity();
/// // The angle of exp(hat(w)), w ~ N(0, sigma^2 I_3), has mean sigma sqrt(8 / pi) ~ 0.016.
/// let mean: f64 = (0..2000).map(|_| angle_between(&id, &perturb_gaussian(&id, 0.01, &mut rng))).sum::<f64>() / 2000.0;
/// assert!((mean - 0.01 * (8.0 / std::f64::consts::PI).sqrt()).abs() < 1e-3);
/// ```
pub fn perturb_gaussian<R: Rng + ?Sized>(r: &Rotation, sigma: f64, rng: &mut R) -> Rotation {
    let w = Vector3::new(gaussian(rng), gaussian(rng), gaussian(rng)) * sigma;
    r * exp(&w)
}

/// A standard normal sample (Box-Muller).
pub fn gaussian<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// Central differences of `d -> log(exp(hat v) exp(hat d))` at `d = 0`, column by column,
    /// against the closed form, for angles from 1e-6 to pi - 0.01 (both branches of the
    /// coefficient).
    #[test]
    fn right_jacobian_inverse_matches_finite_differences() {
        let mut rng = StdRng::seed_from_u64(5);
        for &t in &[1e-6, 1e-3, 0.009, 0.011, 0.5, 1.5, 2.5, 3.0, PI - 0.01] {
            let v = random_unit_vector(&mut rng) * t;
            let j = right_jacobian_inverse(&v);
            let h = 1e-6;
            for a in 0..3 {
                let mut d = Vector3::zeros();
                d[a] = h;
                let col = (log(&(exp(&v) * exp(&d))) - log(&(exp(&v) * exp(&-d)))) / (2.0 * h);
                let err = (col - j.column(a)).norm();
                assert!(err < 1e-6 * (1.0 + j.norm()), "t = {t}, axis {a}: {err}");
            }
        }
    }

    #[test]
    fn log_exp_roundtrip_small_and_near_pi() {
        let mut rng = StdRng::seed_from_u64(1);
        for &t in &[
            0.0,
            1e-12,
            1e-8,
            1e-5,
            1e-3,
            0.5,
            2.0,
            PI - 1e-2,
            PI - 1e-4,
            PI - 1e-7,
        ] {
            for _ in 0..50 {
                let v = random_unit_vector(&mut rng) * t;
                let r = exp(&v);
                let w = log(&r);
                // near pi the accuracy of the axis is limited by sqrt(eps)-type conditioning
                let tol = if t > PI - 1e-3 { 1e-7 } else { 1e-13 };
                assert!(
                    (w - v).norm() <= tol * (1.0 + t),
                    "t={t}: |log exp v - v| = {}",
                    (w - v).norm()
                );
                assert!((angle(&r) - t).abs() <= 1e-13 + tol, "angle");
                // exp is an exact rotation
                let (orth, det) = rotation_defect(r.matrix());
                assert!(orth < 1e-14 && (det - 1.0).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn log_at_exactly_pi_is_a_valid_logarithm() {
        for axis in [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            Vector3::new(1.0, 1.0, 1.0).normalize(),
        ] {
            let r = Rotation3::from_matrix_unchecked(
                2.0 * axis * axis.transpose() - Matrix3::identity(),
            );
            let w = log(&r);
            assert!((w.norm() - PI).abs() < 1e-12);
            assert!((exp(&w).matrix() - r.matrix()).norm() < 1e-12);
        }
    }

    #[test]
    fn distances_agree_with_closed_forms_of_angle() {
        let mut rng = StdRng::seed_from_u64(2);
        for _ in 0..200 {
            let r = random_rotation(&mut rng);
            let s = random_rotation(&mut rng);
            let t = angle_between(&r, &s);
            for m in [Metric::Geodesic, Metric::Chordal, Metric::Quaternion] {
                assert!((m.distance(&r, &s) - m.from_angle(t)).abs() < 1e-12, "{m}");
                assert!((m.distance(&r, &s) - m.distance(&s, &r)).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn projection_fixes_reflections_and_rejects_nan() {
        let f = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        let p = project_to_so3(&f).unwrap();
        assert!((p.matrix().determinant() - 1.0).abs() < 1e-12);
        let mut m = Matrix3::identity();
        m[(1, 1)] = f64::NAN;
        assert!(project_to_so3(&m).is_none());
        assert!(matches!(
            rotation_from_matrix(&m, 1e-6, "x"),
            Err(Error::NonFinite { .. })
        ));
        assert!(matches!(
            rotation_from_matrix(&(Matrix3::identity() * 1.01), 1e-6, "x"),
            Err(Error::NotARotation { .. })
        ));
    }

    /// `[C5]`: the projection of `R (I + E)` (`||E||_F` from 0 to 0.3, both branches: the
    /// Newton-Schulz steps alone and after the SVD) and of arbitrary matrices is in SO(3) to
    /// rounding and equals the det-corrected polar factor computed here from nalgebra's SVD.
    #[test]
    fn projection_is_the_polar_factor_in_so3_to_rounding() {
        let mut rng = StdRng::seed_from_u64(7);
        let polar = |m: &Matrix3<f64>| {
            let svd = m.svd(true, true);
            let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
            let d =
                Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, (u * vt).determinant().signum()));
            u * d * vt
        };
        for defect in [
            0.0,
            1e-15,
            1e-12,
            1e-9,
            1e-7,
            1e-5,
            1e-3,
            0.03,
            0.3,
            f64::NAN,
        ] {
            for _ in 0..2000 {
                let e = Matrix3::from_fn(|_, _| gaussian(&mut rng));
                let m = if defect.is_nan() {
                    e // an arbitrary matrix
                } else {
                    random_rotation(&mut rng).matrix()
                        * (Matrix3::identity() + e * (defect / e.norm()))
                };
                let p = project_to_so3(&m).unwrap();
                let (orth, det) = rotation_defect(p.matrix());
                assert!(
                    orth <= 2e-15 && (det - 1.0).abs() <= 2e-15,
                    "{defect}: {orth:e} {det}"
                );
                let q = polar(&m);
                let tol = if defect.is_nan() { 1e-10 } else { 1e-13 };
                assert!(
                    (p.matrix() - q).norm() <= tol,
                    "{defect}: {:e}",
                    (p.matrix() - q).norm()
                );
                assert_eq!(nearest_rotation(&Rotation3::from_matrix_unchecked(m)), p);
            }
        }
    }

    #[test]
    fn perturb_moves_by_exact_angle() {
        let mut rng = StdRng::seed_from_u64(3);
        let r = random_rotation(&mut rng);
        for &t in &[0.0, 0.1, 1.0, 3.0] {
            let s = perturb(&r, t, &mut rng);
            assert!((angle_between(&r, &s) - t).abs() < 1e-12);
        }
    }
}
