//! The glue to Clarabel, shared by the relaxations of [`super::multiple`] and
//! [`super::conjugate`]: settings translation, one solve in standard conic form
//! `min q^T x  s.t.  b - A x in K`, and the mapping of Clarabel's status to [`SdpStatus`].
//! Clarabel's types never leave this module's callers (`paper-notes/sdp.md`).

use super::settings::{SdpSettings, SdpStatus};
use crate::error::{Error, Result};
use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultInfo, DefaultSettings, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// What one Clarabel solve hands back (of the problem as posed: scaled by the caller).
pub(crate) struct ConicSolution {
    /// Our status.
    pub status: SdpStatus,
    /// Primal variables `x`.
    pub x: Vec<f64>,
    /// Dual variables `z` (one per row of `A`).
    pub z: Vec<f64>,
    /// Clarabel's primal objective (informational only).
    pub primal_objective: f64,
    /// Clarabel's dual objective (informational only: never a bound).
    pub dual_objective: f64,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Clarabel's solve time, seconds.
    pub solve_seconds: f64,
}

/// Clarabel's settings from ours; `merge` is the chordal-decomposition clique merge method
/// (ignored when decomposition is off).
fn clarabel_settings(settings: &SdpSettings, merge: &str) -> DefaultSettings<f64> {
    DefaultSettings {
        verbose: settings.verbose,
        max_iter: settings.max_iterations,
        time_limit: settings.time_limit_seconds.unwrap_or(f64::INFINITY),
        tol_gap_abs: settings.tol_gap_abs,
        tol_gap_rel: settings.tol_gap_rel,
        tol_feas: settings.tol_feas,
        direct_solve_method: "faer".into(),
        chordal_decomposition_enable: settings.chordal_decomposition,
        chordal_decomposition_complete_dual: true,
        chordal_decomposition_merge_method: merge.into(),
        iterative_refinement_enable: settings.iterative_refinement,
        ..DefaultSettings::default()
    }
}

/// Our name for Clarabel's status.
fn status(s: SolverStatus) -> SdpStatus {
    use SolverStatus as S;
    match s {
        S::Solved => SdpStatus::Solved,
        S::AlmostSolved => SdpStatus::AlmostSolved,
        S::MaxIterations => SdpStatus::MaxIterations,
        S::MaxTime => SdpStatus::MaxTime,
        S::PrimalInfeasible
        | S::DualInfeasible
        | S::AlmostPrimalInfeasible
        | S::AlmostDualInfeasible => SdpStatus::Infeasible,
        S::NumericalError | S::InsufficientProgress => SdpStatus::NumericalFailure,
        S::Unsolved | S::CallbackTerminated => SdpStatus::Unsolved,
    }
}

/// A sparse `m x n` matrix from `(row, column, value)` triplets.
pub(crate) fn csc(m: usize, n: usize, t: Vec<(usize, usize, f64)>) -> CscMatrix<f64> {
    let mut rows = Vec::with_capacity(t.len());
    let mut cols = Vec::with_capacity(t.len());
    let mut vals = Vec::with_capacity(t.len());
    for (r, c, v) in t {
        rows.push(r);
        cols.push(c);
        vals.push(v);
    }
    CscMatrix::new_from_triplets(m, n, rows, cols, vals)
}

/// The cones of a standard-form problem.
pub(crate) enum Cone {
    /// `b - A x = 0` on this many rows.
    Zero(usize),
    /// A PSD cone of this matrix dimension on `svec` rows ([`super::svec`]).
    Psd(usize),
}

/// Solve `min q^T x  s.t.  b - A x in K` (no quadratic term) with Clarabel. Errors only when
/// Clarabel refuses the problem at setup; a non-converged solve is a status.
pub(crate) fn solve_conic(
    q: &[f64],
    a: CscMatrix<f64>,
    b: &[f64],
    cones: &[Cone],
    settings: &SdpSettings,
    merge: &str,
) -> Result<ConicSolution> {
    let nv = q.len();
    solve_quadratic_conic(
        (&CscMatrix::zeros((nv, nv)), q),
        a,
        b,
        cones,
        settings,
        merge,
    )
}

/// Solve `min x^T P x / 2 + q^T x  s.t.  b - A x in K` (`P` positive semidefinite, its upper
/// triangle) with Clarabel, as [`solve_conic`].
pub(crate) fn solve_quadratic_conic(
    (p, q): (&CscMatrix<f64>, &[f64]),
    a: CscMatrix<f64>,
    b: &[f64],
    cones: &[Cone],
    settings: &SdpSettings,
    merge: &str,
) -> Result<ConicSolution> {
    let cones: Vec<SupportedConeT<f64>> = cones
        .iter()
        .map(|c| match *c {
            Cone::Zero(k) => SupportedConeT::ZeroConeT(k),
            Cone::Psd(k) => SupportedConeT::PSDTriangleConeT(k),
        })
        .collect();
    // Clarabel's SDP cone calls dgemm_, dsyevr_, ... from rotavg-lapack: taking their addresses
    // here makes every linker load them whenever this solver is linked (see src/lib.rs).
    std::hint::black_box(rotavg_lapack::link_routines());
    let mut solver = DefaultSolver::new(p, q, &a, b, &cones, clarabel_settings(settings, merge))
        .map_err(|e| Error::Solver {
            message: format!("Clarabel setup: {e}"),
        })?;
    // per-iteration progress (the callback never terminates the solve)
    solver.set_termination_callback(|info: &DefaultInfo<f64>| {
        crate::progress::emit(|| crate::progress::Event::Iteration {
            phase: crate::progress::Phase::Sdp,
            iteration: info.iterations as usize,
            cost: info.cost_primal,
            measure: info.gap_rel,
        });
        false
    });
    solver.solve();
    let s = &solver.solution;
    Ok(ConicSolution {
        status: status(s.status),
        x: s.x.clone(),
        z: s.z.clone(),
        primal_objective: s.obj_val,
        dual_objective: s.obj_val_dual,
        iterations: s.iterations,
        solve_seconds: s.solve_time,
    })
}
