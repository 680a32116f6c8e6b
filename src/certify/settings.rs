//! The settings of every `certify_*` function: one [`CertifySettings`] for the three problems
//! (each reads the parts that apply to it), with the [`CertifyMode`] that chooses the method.

use super::budget::Budget;
use super::proof::Proof;
use super::tolerance::ToleranceRule;
use crate::error::{Error, Result};
use crate::linalg::LanczosSettings;
use crate::relax::SdpSettings;
use crate::so3::Rotation;
use crate::validate::{at_least_one, check_rotation};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Which argument bounds the global minimum.
///
/// | mode | single | multiple | conjugate |
/// |---|---|---|---|
/// | `auto` | theory, then branch and bound | dual, then staircase, then SDP (`n <= sdp_max_nodes`) if the staircase stops short | SDP (chordal L2), then branch and bound |
/// | `theory` | closed forms, convexity `[S1]`-`[S7]` | — | — |
/// | `branch_and_bound` | branch and bound `[B1]`-`[B6]` | — | branch and bound |
/// | `dual` | — | dual certificate only `[D3]`-`[D9]` | — |
/// | `sdp` | — | dual, then the SDP | SDP |
/// | `staircase` | — | dual, then the Riemannian staircase `[D11]` | — |
/// | `none` | no certificate | no certificate | no certificate |
///
/// A mode that does not apply to a problem is refused ([`Error::InvalidSettings`], field
/// `mode`) before any work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CertifyMode {
    /// The best method for the problem (table above).
    #[default]
    Auto,
    /// Theorems: closed forms and convexity balls (single averaging).
    Theory,
    /// The dual certificate of the estimate (multiple averaging).
    Dual,
    /// The SDP relaxation (multiple: after a failed dual certificate; conjugate: always).
    Sdp,
    /// The Riemannian staircase after a failed dual certificate (multiple averaging).
    Staircase,
    /// Branch and bound over SO(3) only (single and conjugate averaging).
    BranchAndBound,
    /// No certificate (the pipelines skip certification; `certify_*` refuse it).
    None,
}

impl CertifyMode {
    /// Short name: `auto`, `theory`, `dual`, `sdp`, `staircase`, `branch_and_bound`, `none`.
    pub fn name(self) -> &'static str {
        match self {
            CertifyMode::Auto => "auto",
            CertifyMode::Theory => "theory",
            CertifyMode::Dual => "dual",
            CertifyMode::Sdp => "sdp",
            CertifyMode::Staircase => "staircase",
            CertifyMode::BranchAndBound => "branch_and_bound",
            CertifyMode::None => "none",
        }
    }

    /// [`Error::InvalidSettings`] (field `mode`) unless this mode is one of `allowed` for
    /// `problem`.
    pub(crate) fn require(self, problem: &str, allowed: &[CertifyMode]) -> Result<()> {
        if allowed.contains(&self) {
            return Ok(());
        }
        let names: Vec<&str> = allowed.iter().map(|m| m.name()).collect();
        Err(Error::InvalidSettings {
            name: "mode".into(),
            reason: format!(
                "certify mode `{}` does not apply to {problem} averaging (use {})",
                self.name(),
                names.join(", ")
            ),
        })
    }
}

impl fmt::Display for CertifyMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Settings of the verification of the dual certificate of multiple averaging `[D4]`-`[D8]`,
/// `[D13]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DualSettings {
    /// Fraction of the gap tolerance spent on the first Cholesky shift:
    /// `delta_0 = fraction * max(abs_tol, rel_tol |f|) / (3n)` (so that a verified
    /// `lambda_min >= -delta_0` costs at most this fraction of the tolerance). In `(0, 1)`.
    pub shift_budget_fraction: f64,
    /// At an estimate found not critical whose refinement follows, a check of its own
    /// multipliers predicted to take more than this many seconds, and more than a dual
    /// certificate, gives way to the refinement (default 1 s; issue 35: the dearer checks
    /// proved too little on a 10^6-node lattice, while on small graphs a shifted Cholesky
    /// often certifies a point slightly off critical faster than the refinement would).
    pub give_way_above_seconds: f64,
    /// Maximum number of numeric Cholesky factorisations tried (>= 1).
    pub max_factorizations: usize,
    /// Lanczos settings for the eigenvalue *estimates* (never used as bounds by themselves).
    pub lanczos: LanczosSettings,
    /// Largest Cholesky factor (stored values) attempted, on top of the [`Budget`] (which
    /// predicts memory and time from the factor size and is the guard by default: the
    /// default cap is `usize::MAX`, none). Graphs with good separators (pose graphs, grids)
    /// fill little; random expander graphs fill badly (a 10^4-node random graph with 3 10^4
    /// edges needs ~1.1e8 values, 7.7 s on an idle 2-core machine; the scalar comparison
    /// `[D13]` usually avoids it). Above the cap no factorisation is tried: the bound falls
    /// back to Gershgorin (valid, weak) and the verdict is `inconclusive` with the reason, as
    /// over the [`Budget`]. (Until 2026-11-25 the default was 2e8 values, which kept a larger
    /// `--max-memory` from certifying a 10^6-node chain.)
    pub max_factor_nonzeros: usize,
    /// Also estimate `lambda_min(S)` (shift-invert Lanczos) when the first shift already
    /// verifies. Costs a few triangular solves; the estimate is reported, not used in the bound.
    pub estimate_when_verified: bool,
    /// The proofs of `lambda_min(S) >= mu` the ladder may climb (default
    /// [`Proof::MATRIX_CHECKS`]: grounded, shifted Cholesky, scalar and block comparisons; others are
    /// ignored). They run in the order of their predicted time (the strongest first when all are
    /// cheap, [`crate::certify::log::FREE_SECONDS`]), each only when its own prediction fits
    /// the [`Budget`]: a larger budget never removes a proof. Until 2026-11-26 the scalar
    /// comparison ran only above a factor size (`scalar_comparison_above`), which let a
    /// larger budget give a weaker verdict (issue 24).
    pub proofs: Vec<Proof>,
    /// Let the scalar comparison `[D13]` fall back to sparsified subgraphs and splits of the
    /// graph when the whole graph's factor does not fit or fails (default `true`). Off for
    /// graphs whose extra edges are far from consistent, where they fail (a rig's couplings,
    /// `paper-notes/conjugate.md` `[H21]`).
    pub scalar_fallbacks: bool,
    /// The block comparison `[A15]` (anisotropic edges) runs only when the whole graph's `3n`
    /// factor, that of `S` itself, is predicted above this many values (default 2e6: below,
    /// the grounded and shifted Cholesky proofs factorise `S` in a fraction of a second). It
    /// was 5e7 until 2026-12-04, when the comparison's three regions `[A15]` made it faster than
    /// one factorisation of `S` on the realistic two-view class from 1000 cameras
    /// (`anisotropic_ladder -- N 10N [block-always]`: 1000 cameras 0.16 s against 0.22 s,
    /// 2000 0.41 s against 0.87 s, 3000 0.72 s against 1.9 s); on sparse graphs, where its
    /// sufficient condition fails, the ladder gives it a chance of 1/4 and the grounded bound
    /// runs first (`BLOCK_SPARSE_EDGES_PER_NODE`). The threshold is on the graph, not the
    /// budget, so a larger budget never removes the rung.
    pub block_comparison_above: usize,
    /// The randomized Chebyshev test `[D16]`, run when no deterministic proof fits the
    /// [`Budget`]: a Monte Carlo lower bound reported beside the `inconclusive` verdict
    /// (never as the verdict's proven bound).
    pub randomized: RandomizedSettings,
    /// The `conv(SO(3))` dual certificate of anisotropic problems `[A11]` (its multipliers'
    /// search).
    pub conv: ConvDualSettings,
}

/// Settings of the randomized Chebyshev test `[D16]` ([`crate::linalg::ChebyshevTest`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RandomizedSettings {
    /// Run the test when no deterministic proof fits the budget (default `true`); `false`
    /// also skips the Lanczos estimate of `lambda_min(S)` on the gauge's complement `[D7]` it
    /// starts from (a labelled estimate beside an `inconclusive` verdict, never a bound).
    pub enabled: bool,
    /// The probability, over the test's own random vectors, that a passing test is wrong
    /// (default `1e-12`). In `(0, 0.5]`.
    pub failure_probability: f64,
    /// Seed of the random vectors; `None` (default): a fresh seed per run, reported with the
    /// result so that the run can be repeated.
    pub seed: Option<u64>,
    /// Most matrix-vector products with `S` the test may use (default 20000, about a minute
    /// for a 10^5-node graph with 3 10^5 edges); over it the test is not run.
    pub max_matvecs: usize,
}

impl Default for RandomizedSettings {
    fn default() -> Self {
        RandomizedSettings {
            enabled: true,
            failure_probability: 1e-12,
            seed: None,
            max_matvecs: 20_000,
        }
    }
}

impl RandomizedSettings {
    /// Check every value; [`Error::InvalidSettings`] names the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.failure_probability > 0.0 && self.failure_probability <= 0.5) {
            return Err(Error::InvalidSettings {
                name: "dual.randomized.failure_probability".into(),
                reason: format!("must be in (0, 0.5], got {}", self.failure_probability),
            });
        }
        at_least_one("dual.randomized.max_matvecs", self.max_matvecs)
    }

    /// The seed to use: the configured one, or a fresh one from the process's random state.
    pub fn resolve_seed(&self) -> u64 {
        self.seed.unwrap_or_else(|| {
            use std::hash::{BuildHasher, Hasher};
            let mut h = std::collections::hash_map::RandomState::new().build_hasher();
            h.write_u128(
                std::time::SystemTime::now()
                    .duration_since(std::time::UNIX_EPOCH)
                    .map_or(0, |d| d.as_nanos()),
            );
            h.finish()
        })
    }
}

impl Default for DualSettings {
    fn default() -> Self {
        DualSettings {
            shift_budget_fraction: 0.1,
            give_way_above_seconds: 1.0,
            max_factorizations: 24,
            max_factor_nonzeros: usize::MAX,
            lanczos: LanczosSettings::default(),
            estimate_when_verified: true,
            proofs: Proof::MATRIX_CHECKS.to_vec(),
            scalar_fallbacks: true,
            block_comparison_above: 2_000_000,
            randomized: RandomizedSettings::default(),
            conv: Default::default(),
        }
    }
}

impl DualSettings {
    /// Check every value; [`Error::InvalidSettings`] names the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.give_way_above_seconds.is_finite() && self.give_way_above_seconds >= 0.0) {
            return Err(Error::InvalidSettings {
                name: "dual.give_way_above_seconds".into(),
                reason: format!(
                    "must be finite and >= 0, got {}",
                    self.give_way_above_seconds
                ),
            });
        }
        if !(self.shift_budget_fraction > 0.0 && self.shift_budget_fraction < 1.0) {
            return Err(Error::InvalidSettings {
                name: "dual.shift_budget_fraction".into(),
                reason: format!("must be in (0, 1), got {}", self.shift_budget_fraction),
            });
        }
        at_least_one("dual.max_factorizations", self.max_factorizations)?;
        self.randomized.validate()?;
        self.conv.validate()?;
        self.lanczos.validate("dual.lanczos")
    }
}

/// Settings of `certify_single`, `certify_multiple` and `certify_conjugate` (and of the
/// certification step of the pipelines). Each problem reads the parts that apply to it:
/// single `mode`, `tolerance`; multiple all but none; conjugate `mode`, `tolerance`, `sdp`,
/// `spectrum`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CertifySettings {
    /// Which method bounds the global minimum (default `auto`).
    pub mode: CertifyMode,
    /// Gap tolerance of the verdict: certified when
    /// `gap <= max(relative |f|, absolute_per_min_weight x w_min)` (defaults `1e-6` and `1e-9`;
    /// `w_min` the smallest edge, pair or sample weight). Scale-free: multiplying every weight
    /// by `c` never changes a verdict, and no set of measurements can loosen it.
    pub tolerance: ToleranceRule,
    /// Multiple averaging: verification of the dual certificate.
    pub dual: DualSettings,
    /// The SDP solve (Clarabel).
    pub sdp: SdpSettings,
    /// Multiple averaging, mode `auto`: after a failed dual certificate the staircase runs; the
    /// SDP follows only when the staircase stopped short of a verified point and the graph has
    /// at most this many nodes (default 150) and its predicted cost fits the budget.
    pub sdp_max_nodes: usize,
    /// Multiple averaging: the Riemannian staircase.
    pub staircase: StaircaseSettings,
    /// Memory and time limits, checked before each expensive step.
    pub budget: Budget,
    /// When set, also estimate the smallest eigenvalues of the certificate matrix whose
    /// multipliers gave the reported bound ([`super::Certificate::smallest_eigenvalues`],
    /// `[D14]`; estimates for figures, not bounds). Default `None`: no extra work.
    pub spectrum: Option<SpectrumSettings>,
    /// Single and conjugate averaging: the branch and bound (its time limit is
    /// `budget.max_seconds`).
    pub branch_and_bound: BranchAndBoundSettings,
}

impl Default for CertifySettings {
    fn default() -> Self {
        CertifySettings {
            mode: CertifyMode::Auto,
            tolerance: ToleranceRule::default(),
            dual: DualSettings::default(),
            sdp: SdpSettings::default(),
            sdp_max_nodes: 150,
            staircase: StaircaseSettings::default(),
            budget: Budget::default(),
            spectrum: None,
            branch_and_bound: BranchAndBoundSettings::default(),
        }
    }
}

impl CertifySettings {
    /// The SDP settings with Clarabel's time limit at what `deadline` leaves minus `reserve`
    /// seconds (kept for what follows the solve: the verification of its multipliers, its
    /// rounding's polish); `None` when nothing is left. Every SDP rung: its prediction decides
    /// whether it starts, this bounds how long it runs.
    pub(crate) fn sdp_until(
        &self,
        deadline: &crate::certify::budget::Deadline,
        reserve: f64,
    ) -> Option<crate::relax::SdpSettings> {
        let mut sdp = self.sdp.clone();
        if let Some(left) = deadline.left() {
            let limit = left - reserve;
            if limit <= 0.0 {
                return None;
            }
            sdp.time_limit_seconds = Some(sdp.time_limit_seconds.map_or(limit, |t| t.min(limit)));
        }
        Some(sdp)
    }

    /// Default settings with the given mode.
    pub fn with_mode(mode: CertifyMode) -> Self {
        CertifySettings {
            mode,
            ..Default::default()
        }
    }

    /// Check every value (all parts, whichever problem reads them);
    /// [`Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::certify::CertifySettings;
    /// assert!(CertifySettings::default().validate().is_ok());
    /// let mut bad = CertifySettings::default();
    /// bad.sdp.max_iterations = 0;
    /// assert!(bad.validate().unwrap_err().to_string().contains("sdp.max_iterations"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        self.tolerance.validate()?;
        self.dual.validate()?;
        self.sdp.validate()?;
        self.staircase.validate()?;
        self.budget.validate()?;
        self.branch_and_bound.validate()?;
        if let Some(sp) = &self.spectrum {
            sp.validate()?;
        }
        Ok(())
    }

    /// The checks of a certifier of one rotation (`problem` averaging: single or conjugate),
    /// before any work: every value ([`Self::validate`]), a mode that applies (`auto`, the
    /// problem's own `bound` or `branch_and_bound`), and an estimate that is a rotation.
    pub(crate) fn check_one_rotation(
        &self,
        problem: &str,
        bound: CertifyMode,
        estimate: &Rotation,
    ) -> Result<()> {
        self.validate()?;
        let modes = [CertifyMode::Auto, bound, CertifyMode::BranchAndBound];
        self.mode.require(problem, &modes)?;
        check_rotation(|| "estimate".into(), estimate)
    }
}

/// Settings of the Riemannian staircase `[D11]` (`crate::certify::multiple::staircase`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StaircaseSettings {
    /// Largest rank `p` tried (`>= 3`; default 32: the rank of an SDP solution is at most
    /// about `sqrt(12 n)` (Barvinok-Pataki), and ranks stop growing when no negative
    /// eigenvector is left or the time budget is spent).
    pub max_rank: usize,
    /// Trust-region iterations per rank.
    pub max_iterations: usize,
    /// Converged at a rank when `||grad|| <= gradient_tolerance * (w_min + F)` (`w_min` the smallest weight).
    pub gradient_tolerance: f64,
    /// Stop once the relaxation's value is bracketed this tightly: the lifted cost `F(Y)` (a
    /// feasible point's, so at least the SDP optimum) is within `bracket_tolerance` times the
    /// reported gap (cost minus the verified bound) of the verified bound, or within the
    /// certificate's tolerance. A higher rank could then improve the bound by at most that
    /// fraction of the gap (in `[0, 1)`, default `1e-2`; `0` climbs while a negative eigenvector
    /// is left): the reported gap is then at most `1 / (1 - t)` times the relaxation's own.
    pub bracket_tolerance: f64,
}

impl Default for StaircaseSettings {
    fn default() -> Self {
        StaircaseSettings {
            max_rank: 32,
            max_iterations: 500,
            gradient_tolerance: 1e-9,
            bracket_tolerance: 1e-2,
        }
    }
}

impl StaircaseSettings {
    /// Check every value; [`Error::InvalidSettings`] names the first bad one
    /// (`staircase.<field>`).
    pub fn validate(&self) -> Result<()> {
        if self.max_rank < 3 {
            return Err(Error::InvalidSettings {
                name: "staircase.max_rank".into(),
                reason: format!("must be at least 3, got {}", self.max_rank),
            });
        }
        crate::validate::at_least_one("staircase.max_iterations", self.max_iterations)?;
        crate::validate::positive("staircase.gradient_tolerance", self.gradient_tolerance)?;
        // t >= 1 would stop at the first verification: the lifted cost is below the estimate's
        if !(0.0..1.0).contains(&self.bracket_tolerance) {
            return Err(Error::InvalidSettings {
                name: "staircase.bracket_tolerance".into(),
                reason: format!("must be a number in [0, 1), got {}", self.bracket_tolerance),
            });
        }
        Ok(())
    }
}

/// Settings of the branch and bound (`CertifySettings::branch_and_bound`); its time limit is
/// `CertifySettings::budget.max_seconds`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BranchAndBoundSettings {
    /// Largest number of cells bounded (default 2 000 000; >= 1).
    pub max_cells: usize,
    /// The axis-angle cube `[-pi, pi]^3` is first split into `k^3` cells (default 4; >= 1; measured on 10^4 samples with outliers: k = 4 bounds 15 % fewer cells than k = 8).
    pub initial_divisions: usize,
    /// Largest number of local solves started from cell centres that beat the incumbent
    /// (default 16).
    pub max_local_solves: usize,
    /// Mode `auto` falls back to the branch and bound only for problems with at most this many
    /// samples / pairs (default 20 000: each cell costs one pass over the terms, ~0.1 us per
    /// term, and a search bounds a few thousand cells); mode `branch_and_bound` has no limit.
    pub auto_max_terms: usize,
}

impl Default for BranchAndBoundSettings {
    fn default() -> Self {
        BranchAndBoundSettings {
            max_cells: 2_000_000,
            initial_divisions: 4,
            max_local_solves: 16,
            auto_max_terms: 20_000,
        }
    }
}

impl BranchAndBoundSettings {
    /// Check every value; [`crate::Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::certify::BranchAndBoundSettings;
    /// assert!(BranchAndBoundSettings::default().validate().is_ok());
    /// let bad = BranchAndBoundSettings { max_cells: 0, ..Default::default() };
    /// assert!(bad.validate().unwrap_err().to_string().contains("max_cells"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        at_least_one("branch_and_bound.max_cells", self.max_cells)?;
        at_least_one("branch_and_bound.initial_divisions", self.initial_divisions)
    }
}

/// Settings of the smallest-eigenvalue estimates (`crate::certify::spectrum`, `[D14]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SpectrumSettings {
    /// How many of the smallest eigenvalues (default 10; fewer when the matrix is smaller).
    pub count: usize,
    /// Dense eigen-decomposition up to this dimension (default 600).
    pub dense_max_dim: usize,
    /// Block size of the block Lanczos iteration (default 3, >= 1).
    pub block_size: usize,
    /// Largest Krylov subspace dimension (default 150; also capped so that the basis holds at
    /// most `4e7` numbers, 320 MB).
    pub max_subspace: usize,
    /// Converged when every residual `||S x - lambda x|| <= tolerance * ||S||_inf`
    /// (default `1e-8`).
    pub tolerance: f64,
    /// Seed of the random start block.
    pub seed: u64,
}

impl Default for SpectrumSettings {
    fn default() -> Self {
        SpectrumSettings {
            count: 10,
            dense_max_dim: 600,
            block_size: 3,
            max_subspace: 150,
            tolerance: 1e-8,
            seed: 0x05ee_de16,
        }
    }
}

impl SpectrumSettings {
    /// Check every value; [`Error::InvalidSettings`] names the first bad one (`spectrum.<field>`).
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: &str| {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason: reason.into(),
            })
        };
        if self.count == 0 {
            return bad("spectrum.count", "must be at least 1");
        }
        if self.block_size == 0 {
            return bad("spectrum.block_size", "must be at least 1");
        }
        if self.tolerance.is_nan() || self.tolerance <= 0.0 {
            return bad("spectrum.tolerance", "must be > 0");
        }
        Ok(())
    }
}

/// Settings of the search for the `conv(SO(3))` multipliers `[A11]` (`dual.conv`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ConvDualSettings {
    /// Run it (anisotropic problems whose `O(3)` dual certificate did not certify; modes `auto`
    /// and `dual`). Default `true`.
    pub enabled: bool,
    /// Rounds of the search: each one Lanczos run on `S'` and the projections onto its cuts
    /// (0: only the edges' own reflection prices). Default 300.
    pub max_rounds: usize,
    /// Cuts (Ritz vectors of negative Ritz value) kept, the newest. Default 60.
    pub cuts_kept: usize,
    /// Most passes of cyclic projections over the kept cuts in a round (a round stops passing
    /// when no cut is violated). Default 30.
    pub passes: usize,
    /// Krylov subspace dimension of a round's Lanczos run (block size 3). Default 90.
    pub lanczos_iterations: usize,
    /// Fraction of the time left that the search may spend (the rest is the proof's). In
    /// `(0, 1)`, default 0.5.
    pub time_fraction: f64,
    /// Rounds without a 0.1 % rise of the smallest Ritz value after which the search stops
    /// (stalled). Default 40.
    pub stall_rounds: usize,
    /// Largest factor (stored values) of `S' + sigma I` for shift-invert rounds; above it (or
    /// above what the memory budget leaves beside the search) the rounds run Lanczos on `S'`
    /// itself, whose smallest Ritz values converge slowly. Default 2e7.
    pub shift_invert_max_factor: usize,
}

impl Default for ConvDualSettings {
    fn default() -> Self {
        ConvDualSettings {
            enabled: true,
            max_rounds: 300,
            cuts_kept: 60,
            passes: 30,
            lanczos_iterations: 90,
            time_fraction: 0.5,
            stall_rounds: 40,
            shift_invert_max_factor: 20_000_000,
        }
    }
}

impl ConvDualSettings {
    /// Checks `cuts_kept`, `passes` and `lanczos_iterations >= 1` (the Lanczos dimension at
    /// least 6) and `time_fraction` in `(0, 1)`.
    pub fn validate(&self) -> Result<()> {
        crate::validate::at_least_one("dual.conv.cuts_kept", self.cuts_kept)?;
        crate::validate::at_least_one("dual.conv.passes", self.passes)?;
        crate::validate::at_least_one("dual.conv.stall_rounds", self.stall_rounds)?;
        if self.lanczos_iterations < 6 {
            return Err(Error::InvalidSettings {
                name: "dual.conv.lanczos_iterations".into(),
                reason: format!("must be >= 6, got {}", self.lanczos_iterations),
            });
        }
        if !(self.time_fraction > 0.0 && self.time_fraction < 1.0) {
            return Err(Error::InvalidSettings {
                name: "dual.conv.time_fraction".into(),
                reason: format!("must be in (0, 1), got {}", self.time_fraction),
            });
        }
        Ok(())
    }
}
