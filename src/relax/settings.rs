//! Settings and status of the SDP solves (Clarabel), shared by both relaxations.

use crate::error::{Error, Result};
use crate::validate::positive;
use serde::{Deserialize, Serialize};

/// Which SDP formulation to hand to the solver (`paper-notes/sdp.md`, `[P2]`, `[P3]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SdpForm {
    /// Variables `Lambda_i` (6 per node); cone over `svec(Q - blkdiag(Lambda))`, whose
    /// sparsity pattern is the view graph's, so chordal decomposition applies. Default.
    #[default]
    Dual,
    /// Variables `X` (dense `3n x 3n`), `X_ii = I_3`. Only for small problems and cross-checks.
    Primal,
}

/// Settings of the SDP solves (Clarabel interior-point method), for both relaxations
/// ([`super::relax_multiple`], [`super::relax_conjugate`]). `form`, `chordal_decomposition`,
/// `chordal_merge` and `dense_x_max_size` only concern the multiple-averaging SDP (the conjugate
/// one is a single dense 10x10 cone).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SdpSettings {
    /// Formulation.
    pub form: SdpForm,
    /// Absolute duality-gap tolerance (on the scaled problem, see `paper-notes/sdp.md` `[P4]`).
    pub tol_gap_abs: f64,
    /// Relative duality-gap tolerance.
    pub tol_gap_rel: f64,
    /// Primal/dual feasibility tolerance.
    pub tol_feas: f64,
    /// Maximum interior-point iterations.
    pub max_iterations: u32,
    /// Wall-clock limit in seconds (`None`: unlimited).
    pub time_limit_seconds: Option<f64>,
    /// Use Clarabel's chordal decomposition of the PSD cone (dual form only benefits).
    pub chordal_decomposition: bool,
    /// How Clarabel merges the cliques of the chordal decomposition.
    pub chordal_merge: ChordalMerge,
    /// Clarabel's iterative refinement of each KKT solve. Off by default: on this crate's SDPs
    /// it costs ~30% of the solve time (an extra KKT product per solve over the dense clique
    /// blocks) without changing the iteration count or the objective beyond ~1e-9 relative
    /// (measured n = 20..150, `paper-notes/sdp.md`), and no bound rests on the solver's
    /// accuracy: the multipliers are verified independently `[D4]`.
    pub iterative_refinement: bool,
    /// Print Clarabel's iteration log.
    pub verbose: bool,
    /// Return the dense primal matrix `X` in [`super::MultipleRelaxation::x_dense`] when `3n` is at most this.
    pub dense_x_max_size: usize,
}

impl Default for SdpSettings {
    fn default() -> Self {
        SdpSettings {
            form: SdpForm::Dual,
            tol_gap_abs: 1e-8,
            tol_gap_rel: 1e-8,
            tol_feas: 1e-8,
            max_iterations: 200,
            time_limit_seconds: None,
            chordal_decomposition: true,
            chordal_merge: ChordalMerge::Auto,
            iterative_refinement: false,
            verbose: false,
            dense_x_max_size: 150,
        }
    }
}

impl SdpSettings {
    /// Checks every value is in range; [`Error::InvalidSettings`] names the first bad one
    /// (`sdp.<field>`).
    pub fn validate(&self) -> Result<()> {
        positive("sdp.tol_gap_abs", self.tol_gap_abs)?;
        positive("sdp.tol_gap_rel", self.tol_gap_rel)?;
        positive("sdp.tol_feas", self.tol_feas)?;
        if self.max_iterations == 0 {
            return Err(Error::InvalidSettings {
                name: "sdp.max_iterations".into(),
                reason: "must be at least 1".into(),
            });
        }
        if let Some(t) = self.time_limit_seconds
            && (t.is_nan() || t <= 0.0)
        {
            return Err(Error::InvalidSettings {
                name: "sdp.time_limit_seconds".into(),
                reason: format!("must be > 0, got {t}"),
            });
        }
        Ok(())
    }
}

/// Clique merging strategy of Clarabel's chordal decomposition (`paper-notes/sdp.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChordalMerge {
    /// `CliqueGraph` when the mean node degree `2m/n` is at least 6, else `ParentChild`
    /// (default). Measured: `clique_graph` is ~2x faster on dense graphs (4n edges) but stalled
    /// for minutes in Clarabel's setup on sparse ones (n = 50, 75 edges), see
    /// `paper-notes/sdp.md`.
    Auto,
    /// Merge along the clique tree (parent and child).
    ParentChild,
    /// Clarabel's clique-graph merge (its own default).
    CliqueGraph,
    /// No merging.
    None,
}

impl ChordalMerge {
    /// Clarabel's name of the method for a graph with `n` nodes and `m` edges.
    pub(crate) fn clarabel_name(self, n: usize, m: usize) -> &'static str {
        match self {
            ChordalMerge::Auto => {
                if 2 * m >= 6 * n {
                    "clique_graph"
                } else {
                    "parent_child"
                }
            }
            ChordalMerge::ParentChild => "parent_child",
            ChordalMerge::CliqueGraph => "clique_graph",
            ChordalMerge::None => "none",
        }
    }
}

/// Outcome of the interior-point solve (our mapping of Clarabel's status).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SdpStatus {
    /// Converged to the requested tolerances.
    Solved,
    /// Converged to Clarabel's reduced ("almost") tolerances only.
    AlmostSolved,
    /// Iteration limit reached.
    MaxIterations,
    /// Time limit reached.
    MaxTime,
    /// The solver reported (almost) primal or dual infeasibility (should not happen for these
    /// relaxations, which are always feasible; indicates numerical trouble).
    Infeasible,
    /// Numerical error or insufficient progress.
    NumericalFailure,
    /// Any other non-converged state.
    Unsolved,
}

impl SdpStatus {
    /// `true` for [`SdpStatus::Solved`] and [`SdpStatus::AlmostSolved`].
    pub fn converged(self) -> bool {
        matches!(self, SdpStatus::Solved | SdpStatus::AlmostSolved)
    }
}
