//! The camera geometry of [`super`]: views, projection, relative poses, and the rotation
//! fitting of near-pure pairs.

use crate::so3::{Rotation, to_quaternion};
use nalgebra::{Matrix3, Vector2, Vector3};

/// A camera: world-to-camera rotation `r` (OpenCV axes) and centre `c` (world frame), so a
/// world point `X` is `r (X - c)` in the camera's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// World-to-camera rotation (COLMAP's `cam_from_world` rotation, this crate's `R_i`).
    pub r: Rotation,
    /// Centre, world frame (metres in [`super::SfmScene`]'s scenes).
    pub c: Vector3<f64>,
}

/// What a [`View`] sees: a pinhole of focal length `focal` (pixels) with the principal point at
/// the image centre, points within `half_width` x `half_height` pixels of it and at depths in
/// `(near, far)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frustum {
    /// Focal length, pixels.
    pub focal: f64,
    /// Largest `|x|` of a visible point from the principal point, pixels.
    pub half_width: f64,
    /// Largest `|y|` of a visible point from the principal point, pixels.
    pub half_height: f64,
    /// Smallest depth, world units (exclusive).
    pub near: f64,
    /// Largest depth, world units (exclusive).
    pub far: f64,
}

impl View {
    /// The normalised image coordinates (`z = 1` plane) of the world point `x`, if it is inside
    /// `frustum`.
    ///
    /// ```
    /// use rotavg::io::colmap::scene::{Frustum, View};
    /// use nalgebra::Vector3;
    /// let v = View { r: rotavg::Rotation::identity(), c: Vector3::zeros() };
    /// let f = Frustum { focal: 500.0, half_width: 320.0, half_height: 240.0, near: 0.5, far: f64::INFINITY };
    /// assert_eq!(v.project(&Vector3::new(1.0, 0.0, 4.0), &f).unwrap().x, 0.25);
    /// assert!(v.project(&Vector3::new(4.0, 0.0, 4.0), &f).is_none()); // 500 px off centre
    /// assert!(v.project(&Vector3::new(0.0, 0.0, -4.0), &f).is_none()); // behind
    /// ```
    pub fn project(&self, x: &Vector3<f64>, frustum: &Frustum) -> Option<Vector2<f64>> {
        let p = self.r * (x - self.c);
        if !(p.z > frustum.near && p.z < frustum.far) {
            return None;
        }
        let u = Vector2::new(p.x / p.z, p.y / p.z);
        ((u.x * frustum.focal).abs() < frustum.half_width
            && (u.y * frustum.focal).abs() < frustum.half_height)
            .then_some(u)
    }
}

/// `cam2_from_cam1` of two views as COLMAP stores it: `R = R_2 R_1^T` and the unit
/// `t = R_2 (c_1 - c_2) / |c_1 - c_2|` (zero when the centres coincide).
///
/// ```
/// use rotavg::io::colmap::scene::{View, relative_pose};
/// use nalgebra::Vector3;
/// let a = View { r: rotavg::Rotation::identity(), c: Vector3::zeros() };
/// let b = View { r: rotavg::so3::exp(&Vector3::new(0.0, 0.3, 0.0)), c: Vector3::new(2.0, 0.0, 0.0) };
/// let (r, t) = relative_pose(&a, &b);
/// // a point seen by both: x_2 = R x_1 + t, up to the scale of t
/// let x = Vector3::new(0.5, 0.2, 6.0);
/// let (x1, x2) = (a.r * (x - a.c), b.r * (x - b.c));
/// assert!((r * x1 + t * 2.0 - x2).norm() < 1e-12);
/// ```
pub fn relative_pose(a: &View, b: &View) -> (Rotation, Vector3<f64>) {
    let t = b.r * (a.c - b.c);
    let n = t.norm();
    (
        b.r * a.r.inverse(),
        if n > 0.0 { t / n } else { Vector3::zeros() },
    )
}

/// The world-to-camera rotation of a camera at `c` looking at `target` with the world's `z`
/// up (OpenCV axes: `x` right, `y` down the image).
pub(super) fn look_at(c: &Vector3<f64>, target: &Vector3<f64>) -> Rotation {
    let z = (target - c).normalize();
    let x = z.cross(&Vector3::z()).normalize();
    let y = z.cross(&x);
    Rotation::from_matrix_unchecked(Matrix3::from_rows(&[
        x.transpose(),
        y.transpose(),
        z.transpose(),
    ]))
}

/// The rotation by `pi` about the unit vector `t`: `2 t t^T - I` (the twisted pair's factor:
/// `[t]x Rot(t, pi) = -[t]x`).
pub(super) fn half_turn(t: &Vector3<f64>) -> Rotation {
    Rotation::from_matrix_unchecked(2.0 * t * t.transpose() - Matrix3::identity())
}

/// The rotation `R` minimising `sum |b2_k - R b1_k|^2` over the unit bearings `b` of the
/// normalised points `x1[k] <-> x2[k]` (Wahba's problem, by the SVD): the pose of a pure
/// rotation. `None` with fewer than 2 points or a degenerate SVD.
///
/// ```
/// use rotavg::io::colmap::scene::wahba_rotation;
/// use nalgebra::{Vector2, Vector3};
/// let r = rotavg::so3::exp(&Vector3::new(0.02, 0.15, -0.01));
/// let x1: Vec<Vector2<f64>> = (0..9).map(|k| Vector2::new((k % 3) as f64 * 0.2 - 0.2, (k / 3) as f64 * 0.2 - 0.2)).collect();
/// let x2: Vec<Vector2<f64>> = x1.iter().map(|p| { let u = r * p.push(1.0); u.xy() / u.z }).collect();
/// assert!(rotavg::so3::angle_between(&wahba_rotation(&x1, &x2).unwrap(), &r) < 1e-12);
/// ```
pub fn wahba_rotation(x1: &[Vector2<f64>], x2: &[Vector2<f64>]) -> Option<Rotation> {
    if x1.len() < 2 || x1.len() != x2.len() {
        return None;
    }
    let m: Matrix3<f64> = x1
        .iter()
        .zip(x2)
        .map(|(p, q)| q.push(1.0).normalize() * p.push(1.0).normalize().transpose())
        .sum();
    let svd = m.svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let d = (u * vt).determinant().signum();
    let r = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * vt;
    r.iter()
        .all(|v| v.is_finite())
        .then(|| Rotation::from_matrix_unchecked(r))
}

/// A rotation as COLMAP's `qvec` `(w, x, y, z)`, with `w >= 0`.
///
/// ```
/// assert_eq!(rotavg::io::colmap::scene::wxyz(&rotavg::Rotation::identity()), [1.0, 0.0, 0.0, 0.0]);
/// ```
pub fn wxyz(r: &Rotation) -> [f64; 4] {
    let q = to_quaternion(r);
    let s = if q.w < 0.0 { -1.0 } else { 1.0 };
    [s * q.w + 0.0, s * q.i + 0.0, s * q.j + 0.0, s * q.k + 0.0]
}
