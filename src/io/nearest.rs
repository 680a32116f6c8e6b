//! `certify --nearest-rotations`: an estimate whose matrices are rotations only approximately
//! (orthogonal to 1e-6, as a Burer-Monteiro solver's rounding returns them) or all reflected
//! (det -1: a solution of the O(3) relaxation, its mirror image) is certified at its nearest
//! rotations, and the report says so (`estimate_projected`, `paper-notes/certificates.md`
//! `[D19]`).
//!
//! What is certified is then the projected estimate, never the matrices as given: its cost is
//! evaluated and bounded like any estimate's. The chordal costs of view graphs, rigs and
//! hand-eye problems are unchanged when every rotation is negated (`||(-R_j) - R_ij (-R_i)||`
//! is `||R_j - R_ij R_i||`), so an estimate whose every matrix is a reflection is negated
//! first; an estimate with some reflections and some rotations is no rotation set up to sign,
//! and is refused.
//!
//! Without the option, a matrix beyond `--rotation-tolerance` is an error as before, and the
//! message names the option ([`with_nearest_hint`]).

use crate::io::input::LoadedEstimate;
use crate::io::json::Estimate;
use crate::so3::{NEARLY_ORTHOGONAL, project_to_so3, rotation_defect};
use crate::warning::Warning;
use crate::{Error, Result, Rotation};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// What [`project_estimate`] did to an estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Projection {
    /// Matrices in the estimate.
    pub matrices: usize,
    /// The largest `||M^T M - I||_F` of a matrix as given.
    pub max_orthogonality_error: f64,
    /// Every matrix had det < 0, and the estimate was negated before the projection.
    pub negated: bool,
}

impl Projection {
    /// The `estimate_projected` warning, counting the matrices.
    pub fn warning(&self) -> Warning {
        let negated = if self.negated {
            "every matrix was a reflection (det -1), so the estimate was negated (the chordal \
             cost does not change) and "
        } else {
            ""
        };
        Warning::new(
            "estimate_projected",
            format!(
                "--nearest-rotations: {negated}each of its {} matrices was replaced by its \
                 nearest rotation (largest ||M^T M - I||_F {:.1e}); the certificate is about \
                 these rotations",
                self.matrices, self.max_orthogonality_error
            ),
        )
        .with_count(self.matrices)
    }
}

/// The read options for an estimate certified at its nearest rotations: every finite matrix
/// is read as given (the tolerance is checked by [`project_estimate`]).
pub fn permissive(options: &crate::io::detect::ReadOptions) -> crate::io::detect::ReadOptions {
    crate::io::detect::ReadOptions {
        rotation_tolerance: f64::INFINITY,
        ..*options
    }
}

/// Replace each matrix of `rotations` by its nearest rotation, negating them all first when
/// every one has det < 0. Errors (naming `file` and the matrix): a matrix farther than
/// [`NEARLY_ORTHOGONAL`] from O(3) (no estimate of a rotation), or reflections mixed with
/// rotations.
///
/// ```
/// use rotavg::io::nearest::project_estimate;
/// use rotavg::so3::{exp, rotation_defect};
/// use rotavg::Rotation;
/// use nalgebra::Vector3;
/// let truth: Vec<Rotation> = (0..3).map(|k| exp(&Vector3::new(0.3 * k as f64, 0.1, -0.2))).collect();
/// // the mirror image, orthogonal to 1e-6 only, as a relaxation's rounding may return
/// let mut given: Vec<Rotation> = truth
///     .iter()
///     .map(|r| Rotation::from_matrix_unchecked(-r.matrix() * (1.0 + 1e-6)))
///     .collect();
/// let p = project_estimate(&mut given, "est.json")?;
/// assert!(p.negated && p.max_orthogonality_error > 1e-6);
/// for (g, t) in given.iter().zip(&truth) {
///     assert!((g.matrix() - t.matrix()).norm() < 1e-14);
///     assert!(rotation_defect(g.matrix()).0 < 1e-14);
/// }
/// // one reflection among rotations is refused
/// let mut mixed = truth.clone();
/// mixed[1] = Rotation::from_matrix_unchecked(-truth[1].matrix());
/// let err = project_estimate(&mut mixed, "est.json").unwrap_err().to_string();
/// assert!(err.contains("1 of its 3 matrices are reflections"), "{err}");
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn project_estimate(rotations: &mut [Rotation], file: &str) -> Result<Projection> {
    let defects: Vec<(f64, f64)> = rotations
        .iter()
        .map(|r| rotation_defect(r.matrix()))
        .collect();
    if let Some(k) = defects
        .iter()
        .position(|(orth, _)| orth.is_nan() || *orth > NEARLY_ORTHOGONAL)
    {
        return Err(Error::parse(
            Some(file),
            None,
            format!(
                "rotation {k} is no estimate of a rotation: ||M^T M - I||_F = {:.3e} (at most \
                 {NEARLY_ORTHOGONAL} for --nearest-rotations)",
                defects[k].0
            ),
        ));
    }
    let reflected = defects.iter().filter(|(_, det)| *det < 0.0).count();
    let negated = reflected == rotations.len() && reflected > 0;
    if reflected > 0 && !negated {
        return Err(Error::parse(
            Some(file),
            None,
            format!(
                "{reflected} of its {} matrices are reflections (det < 0) and the others \
                 rotations: not a rotation estimate up to a global sign, which \
                 --nearest-rotations could undo",
                rotations.len()
            ),
        ));
    }
    let sign = if negated { -1.0 } else { 1.0 };
    for r in rotations.iter_mut() {
        let m: Matrix3<f64> = r.matrix() * sign;
        // finite (the readers check) and within NEARLY_ORTHOGONAL of O(3) with det > 0
        *r = project_to_so3(&m).unwrap_or(*r);
    }
    Ok(Projection {
        matrices: rotations.len(),
        max_orthogonality_error: defects.iter().map(|d| d.0).fold(0.0, f64::max),
        negated,
    })
}

impl LoadedEstimate {
    /// The estimate at its nearest rotations ([`project_estimate`]), with the
    /// `estimate_projected` warning. A single rotation (single and conjugate problems) is
    /// never negated: a single mean's cost changes with the sign.
    pub fn into_nearest_rotations(mut self) -> Result<LoadedEstimate> {
        let projection = match &mut self.estimate {
            Estimate::Multiple(rotations) => project_estimate(rotations, &self.name)?,
            Estimate::Single(r) => {
                if r.matrix().determinant() < 0.0 {
                    return Err(Error::parse(
                        Some(&self.name),
                        None,
                        "the rotation is a reflection (det < 0); --nearest-rotations undoes \
                         only a reflection of every rotation of a view graph's estimate",
                    ));
                }
                project_estimate(std::slice::from_mut(r), &self.name)?
            }
        };
        self.warnings.push(projection.warning());
        Ok(self)
    }
}

/// `e` with a pointer to `--nearest-rotations` when it says a matrix of an estimate is not a
/// rotation (other errors unchanged).
pub fn with_nearest_hint(e: Error) -> Error {
    let message = e.to_string();
    if !message.contains("is not a rotation") {
        return e;
    }
    Error::Parse {
        location: Default::default(),
        message: format!(
            "{message}; with `--nearest-rotations`, certify takes the nearest rotations of \
             an estimate orthogonal only approximately, or all reflected (det -1, as a \
             relaxation's rounding may return), and says so"
        ),
    }
}
