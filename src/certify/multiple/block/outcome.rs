//! What a block comparison `[A15]` proves, or why it did not.

use serde::{Deserialize, Serialize};

/// The outcome of a successful block comparison `[A15]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlockComparison {
    /// Proven lower bound on `lambda_min(S)` (non-positive).
    pub verified_min_eigenvalue: f64,
    /// Largest `delta_i`, the charge of the edge comparisons at one node.
    pub max_delta: f64,
    /// Edges left out of the factorised block Laplacian.
    pub dropped_edges: usize,
    /// The uniform `zeta` added to the charges (its positive term absorbs the cross terms).
    pub zeta: f64,
    /// The margin `h` subtracted from the block matrix.
    pub headroom: f64,
    /// Rigorous bound on the `LDL^T` factorisation's backward error plus the forming error.
    pub backward_error: f64,
    /// Stored values of the `3n` factor of the block Laplacian.
    pub factor_nonzeros: usize,
    /// `kappa = ||w||_2 / sum(w)` (step 4).
    pub kappa: f64,
    /// Upper bound on `||M v0||_F` (the stationarity part, step 3), or for a subgraph in
    /// regions on the coarse correction's residual `||R||_2`.
    pub residual_bound: f64,
    /// The regions whose pencils were proven apart (`[A15]`, "Regions"; 0: one pencil, step 4).
    #[serde(default)]
    pub regions: usize,
    /// Directions deflated from the regions' factorisations and bounded with the coarse ones
    /// (`[A16]`, "Deflation"; padding included).
    #[serde(default)]
    pub deflated: usize,
}

/// Why a block comparison did not prove anything: the scalar comparison's reasons (its
/// inertia condition needs exactly three negative pivots, one per gauge direction).
pub type BlockFailure = crate::certify::multiple::scalar::ScalarFailure;
