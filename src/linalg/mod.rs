//! Linear algebra shared by the solvers and the certificates. Nothing here knows about
//! rotations.
//!
//! - [`cholesky`]: sparse helpers and the verified shifted Cholesky factorisation `[D5]`,
//!   `[D6]`, `[D8]` (the only source of proven eigenvalue bounds).
//! - [`chebyshev`]: the randomized Chebyshev test `[D16]` (a Monte Carlo lower bound on the
//!   smallest eigenvalue from products only, when no factorisation fits the budget).
//! - [`dense`]: dense symmetric eigenproblems and Cholesky solves of `nalgebra` matrices through
//!   faer's blocked kernels (the simultaneous problem's dense certificate `[H15]`).
//! - `compensated` (crate-internal): double-double sums of products with error bounds `[D15]`.
//! - `ldlt` (crate-internal): the verified inertia of a sparse `LDL^T` factorisation `[D13]`.
//! - [`lanczos`](mod@lanczos): the one eigen-estimation engine (block Lanczos with full
//!   reorthogonalisation) `[D7]`, `[D14]`.
//! - [`symmetric3`]: eigenvalues of a symmetric 3x3 matrix to high relative accuracy from its
//!   exactly evaluated invariants `[A12]` (the information matrices' weight scale and sign).
//! - [`two_pass_lanczos`]: the smallest eigenpair when thousands of steps are needed (no stored
//!   basis; the Ritz vector from a second pass), for the staircase's negative curvature `[D11]`.
//! - `small_symmetric` (crate-internal): a proven lower bound on the smallest eigenvalue of a
//!   small dense symmetric matrix (the edge comparisons of `[A15]`).
//! - `block_pattern`, `linear_solver`, `pcg` (crate-internal): the block-sparse Newton systems
//!   of the local solvers `[M6]`: pattern and assembly, sparse Cholesky or block-Jacobi
//!   preconditioned conjugate gradients.

pub(crate) mod block_pattern;
pub mod chebyshev;
pub mod cholesky;
pub(crate) mod compensated;
pub mod dense;
pub mod lanczos;
pub(crate) mod ldlt;
pub(crate) mod linear_solver;
pub(crate) mod pcg;
pub(crate) mod small_symmetric;
pub mod symmetric3;
pub(crate) mod threads;
pub mod two_pass_lanczos;

/// Factor size (stored values) above which a numeric sparse factorisation runs in parallel.
const PARALLEL_FACTOR_THRESHOLD: usize = 2_000_000;

/// The parallelism of a numeric sparse factorisation with `len` stored values: all threads
/// above 2e6 values, sequential (and deterministic) below. The floating-point margins `[D6]`
/// hold for any summation order. Triangular solves always run sequentially (`SparseLlt`).
pub(crate) fn factor_parallelism(len: usize) -> faer::Par {
    if len > PARALLEL_FACTOR_THRESHOLD {
        faer::Par::rayon(0)
    } else {
        faer::Par::Seq
    }
}

pub use chebyshev::{ChebyshevOutcome, ChebyshevTest};
pub use cholesky::{
    PositiveFactor, ShiftedCholesky, UNIT_ROUNDOFF, gamma, gershgorin_lower_bound, inf_norm,
    rayleigh_quotient, sparse_matvec, symmetric_matvec,
};
pub use lanczos::{
    EigenEstimate, Extreme, LanczosResult, LanczosSettings, LanczosStop, lanczos, lanczos_extreme,
    smallest_eigenpair,
};
