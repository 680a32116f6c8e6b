//! The grounded bound `[D15]` (`paper-notes/certificates.md`): the gauge null space of `S` is
//! deflated by removing the block of one node `g` (the ground). With `S_{-g} >= c I` proven by
//! a sparse Cholesky factorisation, `rho >= ||S Y||` and `Y^T S Y >= -h I` (both from
//! double-double residuals), `f* >= sum tr(Lambda_i) - (rho^2 / c + h) ||R_g^-1||_F^2`: no `3n`
//! factor, and no margin at the null space.

use super::check::{Check, Notes, ThreeN, counted_factorisation_prediction, ordering_refusal};
use super::multipliers::GaugeTerms;
use super::verified::{GroundedBound, VerifiedBound};
use crate::certify::log::{Prediction, Refusal};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::error::Result;
use crate::linalg::cholesky::{without_block, without_zero_rows};
use crate::linalg::two_pass_lanczos::smallest_ritz_value;
use crate::linalg::{ShiftedCholesky, UNIT_ROUNDOFF};
use crate::multiple::laplacian::edge_blocks;
use nalgebra::Matrix3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// The grounded rung: its analysis of `S_{-g}` (made when planned) and the ground.
#[derive(Default)]
pub(super) struct GroundedProof {
    analysed: Option<Analysed>,
    done: bool,
}

struct Analysed {
    ground: usize,
    /// `||R_g^-1||_F^2 <= 3 / (1 - d)` and `d`, the ground's orthogonality defect bound.
    rinv2: f64,
    defect: f64,
    /// `None` for a single node (no `S_{-g}`: `c = inf`), or until the attempt analyses it
    /// (`pending`).
    factor: Option<ShiftedCholesky>,
    /// The analysis of `S_{-g}` is left to the attempt (the prediction came from the scalar
    /// factor: no `3n` analysis when an earlier rung proves enough).
    pending: bool,
    terms: GaugeTerms,
    predicted: Prediction,
}

impl<'a> Rung<Check<'a>> for GroundedProof {
    fn proof(&self) -> Proof {
        Proof::Grounded
    }

    fn plan(&mut self, cx: &Check<'a>) -> Result<Plan> {
        if self.done {
            return Ok(Plan::Done);
        }
        if let Some(a) = &self.analysed {
            return Ok(Plan::Run(a.predicted));
        }
        Ok(match self.predict(cx)? {
            Some(Ok(p)) => Plan::Run(p),
            Some(Err(refusal)) => Plan::Refuse(refusal, None),
            None => Plan::Wait,
        })
    }

    fn attempt(&mut self, cx: &mut Check<'a>) -> Result<Found> {
        self.done = true;
        let Some(a) = self.analysed.as_mut() else {
            return Ok(Found::failed("not analysed"));
        };
        if a.pending {
            match analyse(cx, a.ground)? {
                Ok((factor, exact)) => (a.factor, a.predicted) = (factor, exact),
                Err(refusal) => return Ok(Found::refused(refusal)),
            }
        }
        let proven = match a.factor.as_mut() {
            Some(ch) => prove_c(cx, ch, a.terms.rho, &mut cx.notes()),
            None => Ok((f64::INFINITY, 0.0)),
        };
        Ok(
            match proven.and_then(|(c, margin)| bound(cx, a, c, margin)) {
                Ok(b) => Found::new(cx.offer(b), ""),
                Err(reason) => Found::failed(reason),
            },
        )
    }
}

impl GroundedProof {
    /// The ground, the cheap test of criticality, and the analysis of `S_{-g}` (or its
    /// prediction from the scalar factor); `None` while the `3n` rungs wait
    /// ([`Check::three_n_waits`]).
    fn predict(
        &mut self,
        cx: &Check<'_>,
    ) -> Result<Option<std::result::Result<Prediction, Refusal>>> {
        let Some(rotations) = cx.rotations else {
            return Ok(Some(Err(not_applicable(
                "the estimate's rotations are not known",
            ))));
        };
        let n = cx.problem.num_rotations();
        let (ground, defect) = ground(cx, rotations);
        if defect.is_nan() || defect >= 0.5 {
            return Ok(Some(Err(not_applicable(
                "the ground's rotation is far from orthogonal",
            ))));
        }
        let terms = *cx.gauge_terms(rotations);
        if let Some(c_upper) = not_critical(cx, &terms, ground) {
            cx.mark_not_critical();
            return Ok(Some(Err(not_applicable(&format!(
                "not a critical point: ||S Y|| <= {:.1e} against lambda_min(S_{{-g}}) <= \
                 {c_upper:.1e} leaves a deficit above the tolerance whatever S_{{-g}} proves",
                terms.rho
            )))));
        }
        let free = Prediction::new(0.0, 0.0);
        let (factor, pending, predicted) = match (n > 1, cx.three_n_predicted(cx.dim() - 3, 1.0)) {
            (false, _) => (None, false, free),
            (true, ThreeN::Known(Ok(p))) => (None, true, p),
            (true, ThreeN::Known(Err(refusal))) => return Ok(Some(Err(refusal))),
            (true, ThreeN::Wait) => return Ok(None),
            (true, ThreeN::Unknown) => match analyse(cx, ground)? {
                Ok((f, p)) => (f, false, p),
                Err(refusal) => return Ok(Some(Err(refusal))),
            },
        };
        self.analysed = Some(Analysed {
            ground,
            rinv2: 3.0 / (1.0 - defect) * (1.0 + 4.0 * UNIT_ROUNDOFF),
            defect,
            factor,
            pending,
            terms,
            predicted,
        });
        Ok(Some(Ok(predicted)))
    }
}

fn not_applicable(reason: &str) -> Refusal {
    Refusal::NotApplicable {
        reason: reason.into(),
    }
}

/// The ground (the node of largest weighted degree) and its orthogonality defect bound
/// `d >= ||R_g^T R_g - I||_F` (`sigma_min(R_g)^2 >= 1 - d`).
fn ground(cx: &Check<'_>, rotations: &[crate::so3::Rotation]) -> (usize, f64) {
    let n = cx.problem.num_rotations();
    let mut degree = vec![0.0f64; n];
    for e in cx.problem.edges() {
        degree[e.i] += e.weight;
        degree[e.j] += e.weight;
    }
    // a node with an exactly zero row of S (a coordinate no edge sees) cannot ground: the
    // gauge's columns restricted to the other nodes stay null
    let blocks = cx.diagonal_blocks();
    let g = (0..n)
        .filter(|&i| (0..3).all(|a| blocks[i][(a, a)] != 0.0))
        .max_by(|&a, &b| degree[a].total_cmp(&degree[b]))
        .unwrap_or(0);
    let u = UNIT_ROUNDOFF;
    let rg = rotations[g].matrix();
    let d = (rg.transpose() * rg - Matrix3::identity()).norm() * (1.0 + 8.0 * u) + 8.0 * u;
    (g, d)
}

/// `Some(why)` when a cheap test shows that no bound from `lambdas` (the multipliers of
/// `rotations`) can be within `gap`: the estimate is not a critical point. The deficit of
/// `[D15]` is at least `rho^2 / c` (times `||R_g^-1||^2 >= 3`) with `c <= lambda_min(S_{-g})`, and
/// `lambda_min(S_{-g})` is at most every diagonal entry `d_i - Lambda_i,aa` of it; the other
/// proofs charge at least as much at a point that is not critical. `O(m)` in double-double, no
/// factorisation: a diagnosis that decides what runs, never part of a bound.
pub(super) fn hopeless(
    problem: &crate::multiple::MultipleProblem,
    rotations: &[crate::so3::Rotation],
    lambdas: &[Matrix3<f64>],
    terms: &GaugeTerms,
    gap: f64,
) -> Option<String> {
    let n = problem.num_rotations();
    if n < 2 || rotations.len() != n {
        return None;
    }
    let mut degree = vec![0.0f64; n];
    // the diagonal of Q: the weighted degree (isotropic), the sum of the edges' 2M (`[A2]`)
    let mut q_diag = vec![nalgebra::Vector3::zeros(); n];
    for (e, (i, j, qi, qj, _)) in problem.edges().iter().zip(edge_blocks(problem)) {
        degree[e.i] += e.weight;
        degree[e.j] += e.weight;
        q_diag[i] += qi.diagonal();
        q_diag[j] += qj.diagonal();
    }
    let g = (0..n)
        .filter(|&i| (0..3).all(|a| q_diag[i][a] != 0.0))
        .max_by(|&a, &b| degree[a].total_cmp(&degree[b]))?;
    let c_upper = (0..n)
        .filter(|&i| i != g)
        .flat_map(|i| (0..3).map(move |a| (i, a)))
        // coordinates no edge sees are left out of S_{-g} (their rows are zero)
        .filter(|&(i, a)| q_diag[i][a] != 0.0)
        .map(|(i, a)| q_diag[i][a] - lambdas[i][(a, a)])
        .fold(f64::INFINITY, f64::min);
    let deficit = 3.0 * terms.rho * terms.rho / c_upper;
    (c_upper > 0.0 && c_upper.is_finite() && deficit > gap).then(|| {
        format!(
            "not a critical point: ||S Y|| <= {:.1e} against lambda_min(S without node {g}) <= \
             {c_upper:.1e} leaves a deficit of at least {deficit:.1e}, above the tolerance \
             {gap:.1e}; no bound from its own multipliers can certify it",
            terms.rho
        )
    })
}

/// A cheap proof that no `c` can bring the deficit within the gap: `Some(c_upper)` with
/// `lambda_min(S_{-g}) <= c_upper` and `3 rho^2 / c_upper > gap`. `c_upper` is the smallest
/// diagonal entry of `S_{-g}`, or, when the estimate is far enough from critical for a better
/// one to decide (`3 rho^2 / gap` above `1e-3` of that entry), the smallest Ritz value of a
/// short Lanczos run on `S_{-g}` ([`ritz_upper`]). (A diagnosis only: it decides that the rung
/// does not run; a perturbed sphere2500 optimum spent 22 ms failing here before the shifted
/// Cholesky proved in 18 ms.)
fn not_critical(cx: &Check<'_>, terms: &GaugeTerms, ground: usize) -> Option<f64> {
    let diag = cx
        .diagonal_blocks()
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != ground)
        .flat_map(|(_, b)| (0..3).map(move |a| b[(a, a)]))
        // exactly zero: a coordinate no edge sees, left out of S_{-g}
        .filter(|&d| d != 0.0)
        .fold(f64::INFINITY, f64::min);
    let needed = 3.0 * terms.rho * terms.rho / cx.gap;
    if !(diag.is_finite() && diag > 0.0) {
        return None;
    }
    if needed > diag {
        return Some(diag);
    }
    if needed <= 1e-3 * diag {
        return None;
    }
    ritz_upper(cx, ground).filter(|&c| c > 0.0 && needed > c)
}

/// Products of the short Lanczos run of [`not_critical`].
const RITZ_TEST_STEPS: usize = 30;

/// An upper estimate of `lambda_min(S_{-g})`: the smallest Ritz value of
/// [`RITZ_TEST_STEPS`] plain Lanczos steps on `S` with the ground's block masked out (the Krylov
/// space stays in the vectors that vanish there, where `S` acts as `S_{-g}`), plus
/// `1e-10 ||S||_inf` for rounding ([`smallest_ritz_value`]). 2.7 ms on sphere2500.
fn ritz_upper(cx: &Check<'_>, ground: usize) -> Option<f64> {
    let n3 = cx.dim();
    if n3 <= 6 {
        return None;
    }
    let block = 3 * ground..3 * ground + 3;
    // a seeded random start, zero on the ground's block
    let mut rng = StdRng::seed_from_u64(cx.settings.dual.lanczos.seed);
    let mut start: Vec<f64> = (0..n3).map(|_| rng.random::<f64>() - 0.5).collect();
    start[block.clone()].fill(0.0);
    let s = cx.s().as_ref();
    let op = |x: &[f64], y: &mut [f64]| {
        crate::linalg::cholesky::sparse_matvec(s, x, y);
        y[block.clone()].fill(0.0);
    };
    cx.notes().lanczos_iterations += RITZ_TEST_STEPS;
    smallest_ritz_value(op, RITZ_TEST_STEPS.min(n3 - 3), cx.norm(), &start)
        .map(|v| v + 1e-10 * cx.norm())
}

/// The symbolic analysis of `S_{-g}` within the budget, and its prediction: one factorisation,
/// the first shift's, which proves at a critical estimate ([`prove_c`]: measured at 10^4
/// cameras of the realistic two-view class, 4 edges per node, 14.5 s for the rung against 35 s
/// predicted for two). Further shifts run only while they fit the time left.
fn analyse(
    cx: &Check<'_>,
    ground: usize,
) -> Result<std::result::Result<(Option<ShiftedCholesky>, Prediction), Refusal>> {
    let dim = cx.dim() - 3;
    let cap = cx
        .settings
        .budget
        .max_factor_values(dim)
        .min(cx.settings.dual.max_factor_nonzeros);
    // the rows of coordinates no edge sees (exactly zero with their multipliers) left out too
    let grounded = without_zero_rows(without_block(cx.s(), ground, 3)?);
    let ch = match ShiftedCholesky::new_within(grounded, cx.terms, cap)? {
        Ok(ch) => ch,
        Err(predicted) => {
            let refusal = ordering_refusal(cx.settings, predicted, dim)
                .unwrap_or_else(|| not_applicable("the ordering's prediction is over the cap"));
            cx.note_three_n_refused(&refusal);
            return Ok(Err(refusal));
        }
    };
    let scratch = ch.scratch_bytes().div_ceil(8);
    match counted_factorisation_prediction(
        cx.settings,
        ch.factor_len(),
        scratch,
        ch.multiply_adds(),
        1.0,
    ) {
        Ok(p) => Ok(Ok((Some(ch), p))),
        Err(refusal) => {
            cx.note_three_n_refused(&refusal);
            Ok(Err(refusal))
        }
    }
}

/// Prove `S_{-g} >= c I`: first the smallest `c` that makes `rho^2 / c` negligible against the
/// gap (one factorisation when `S_{-g}` is well inside the PD cone); if that fails, `c` from a
/// shift-invert Lanczos estimate of `lambda_min(S_{-g})` (`[D7]`, an estimate that only picks
/// the shifts). Returns `(c, floating-point margin)` or why not. The rung is predicted at one
/// factorisation (the first shift proves whenever the estimate is critical and `S` certifiable);
/// every later one runs only when the longest so far fits the time left ([`fits_again`]).
fn prove_c(
    cx: &Check<'_>,
    ch: &mut ShiftedCholesky,
    rho: f64,
    notes: &mut Notes,
) -> std::result::Result<(f64, f64), String> {
    let first = (30.0 * rho * rho / cx.gap.max(f64::MIN_POSITIVE)).max(1e-9 * cx.norm());
    let mut shifts = vec![first];
    let mut estimated = false;
    let mut longest = 0.0f64;
    while let Some(shift) = shifts.pop() {
        fits_again(cx.deadline.left(), longest)?;
        let since = std::time::Instant::now();
        notes.factorizations += 1;
        let factored = ch.factor(-shift, 0.25 * shift);
        longest = longest.max(since.elapsed().as_secs_f64());
        if let Some(f) = factored {
            // the anisotropic forming error [A3] (0 for isotropic data) off the proven c
            let lower = f.verified_lower_bound() - cx.forming;
            if lower > 0.0 {
                return Ok((lower, f.margin + cx.forming));
            }
        }
        if estimated {
            continue;
        }
        estimated = true;
        fits_again(cx.deadline.left(), longest)?;
        let estimate = estimate_c(cx, ch, notes)?;
        if 3.0 * rho * rho / (0.5 * estimate) > cx.gap {
            notes.not_critical = true;
            return Err(format!(
                "not a critical point: lambda_min(S_{{-g}}) ~ {estimate:.1e} and ||S Y|| <= \
                 {rho:.1e} leave a deficit above the tolerance"
            ));
        }
        // tried from the largest: the first that verifies gives the best c of the three
        shifts = vec![0.05 * estimate, 0.2 * estimate, 0.5 * estimate];
    }
    Err("S without the ground's block was not verified positive definite".into())
}

/// `Err` when another factorisation, as long as the `longest` so far (seconds), would pass the
/// time `left` (`None`: no limit).
fn fits_again(left: Option<f64>, longest: f64) -> std::result::Result<(), String> {
    match left {
        Some(left) if longest > left => Err(format!(
            "another factorisation of S without the ground's block ({longest:.2} s, as the \
             longest so far) would pass the time budget ({:.2} s left)",
            left.max(0.0)
        )),
        _ => Ok(()),
    }
}

/// A shift-invert Lanczos estimate of `lambda_min(S_{-g})` through its factor `[D7]`.
fn estimate_c(
    cx: &Check<'_>,
    ch: &mut ShiftedCholesky,
    notes: &mut Notes,
) -> std::result::Result<f64, String> {
    notes.factorizations += 1;
    let (estimate, iterations) = ch
        .shift_invert_estimate(&cx.settings.dual.lanczos)
        .ok_or("no positive estimate of lambda_min(S without the ground's block)")?;
    notes.lanczos_iterations += iterations;
    Ok(estimate)
}

/// The bound of `[D15]` from a proven `c` (with the factorisation's `margin`).
fn bound(
    cx: &Check<'_>,
    a: &Analysed,
    c: f64,
    margin: f64,
) -> std::result::Result<VerifiedBound, String> {
    let u = UNIT_ROUNDOFF;
    let GaugeTerms {
        rho,
        h,
        sym,
        y_norm,
        ..
    } = a.terms;
    let per_unit = rho * rho / c + h;
    let deficit = per_unit * a.rinv2 * (1.0 + 8.0 * u);
    let lower_bound = cx.trace_bound().with_deficit(deficit);
    if !lower_bound.is_finite() {
        return Err("the bound is not finite".into());
    }
    // the gauge directions' Rayleigh quotients: estimates of the smallest eigenvalues
    let estimate = (0..3)
        .map(|k| sym[(k, k)] / (y_norm * y_norm / 3.0).max(f64::MIN_POSITIVE))
        .fold(f64::INFINITY, f64::min);
    let mu = -per_unit / (1.0 - a.defect);
    let mut b = cx.bound_from_mu(mu, Proof::Grounded);
    b.lower_bound = lower_bound;
    b.fp_margin = margin;
    b.min_eigenvalue_estimate = Some(estimate);
    b.factor_nonzeros = a.factor.as_ref().map_or(0, |f| f.factor_len());
    b.grounded = Some(GroundedBound {
        ground: a.ground,
        c,
        rho,
        h,
        deficit,
    });
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::log::Point;
    use crate::certify::multiple::dual::dual_certificate;
    use crate::certify::multiple::multipliers::{certificate_matrix, multipliers};
    use crate::certify::settings::CertifySettings;
    use crate::linalg::inf_norm;
    use crate::multiple::MultipleProblem;
    use crate::multiple::synthetic::{SyntheticGraph, z_cycle};
    use crate::multiple::{Initialisation, MultipleSettings, MultipleSolution, solve_multiple};
    use crate::so3::Rotation;
    use crate::so3::random_rotation;
    use faer::sparse::SparseColMat;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// A factorisation after the first runs only when the longest so far fits the time left.
    #[test]
    fn another_factorisation_starts_only_when_it_fits() {
        assert!(fits_again(None, 1e9).is_ok());
        assert!(fits_again(Some(2.0), 1.5).is_ok());
        assert!(fits_again(Some(0.0), 0.0).is_ok());
        let why = fits_again(Some(1.0), 1.5).unwrap_err();
        assert!(
            why.contains("1.50 s") && why.contains("1.00 s left"),
            "{why}"
        );
    }

    fn dense_lambda_min(s: &SparseColMat<usize, f64>) -> f64 {
        crate::linalg::cholesky::to_dense(s.as_ref())
            .symmetric_eigenvalues()
            .min()
    }

    /// [D15] against independent references, on small instances where they are cheap: the
    /// verified `lambda_min` is below the dense one, the bound below the best cost of 12 local
    /// solutions (planted start, random starts), and non-global local solutions and perturbed
    /// optima (1e-7 to 0.1 rad per node: not critical points, so the deficit `rho^2 / c` is
    /// what keeps the bound below) are never certified. Noise 0 to 90 degrees, 0 / 20 % outliers; tolerance of the comparisons
    /// `1e-12 (1 + |S|)` (the dense solver's own accuracy) and `1e-10 (1 + f)`.
    #[test]
    fn grounded_bound_is_sound_against_dense_eigenvalues() {
        let mut rng = StdRng::seed_from_u64(15);
        let mut counts = GroundedCounts::default();
        for case in 0..120 {
            let n = 3 + case % 8;
            let spec = SyntheticGraph {
                num_rotations: n,
                num_edges: n - 1 + (case * 7) % (2 * n),
                noise_sigma: [0.0, 0.01, 0.1, 0.5, 1.5][case % 5],
                outlier_fraction: if case % 3 == 0 { 0.2 } else { 0.0 },
                seed: case as u64,
            };
            let (p, truth) = spec.generate();
            let sols = local_solutions(&p, truth, &mut rng);
            let best = sols
                .iter()
                .map(|s| s.chordal_cost)
                .fold(f64::INFINITY, f64::min);
            for (rotations, cost) in &sampled_points(&p, &sols, best, &mut rng) {
                counts.check(&p, rotations, *cost, best, case);
            }
        }
        let GroundedCounts {
            grounded,
            non_global,
        } = counts;
        println!("[D15]: {grounded} grounded bounds, {non_global} non-global solutions");
        assert!(grounded > 200, "only {grounded} grounded bounds");
        assert!(non_global > 20, "only {non_global} non-global solutions");
    }

    /// 12 local solutions of `p` (tight gradient tolerance): from the planted `truth` and from
    /// 11 random starts.
    fn local_solutions(
        p: &MultipleProblem,
        truth: Vec<Rotation>,
        rng: &mut StdRng,
    ) -> Vec<MultipleSolution> {
        let n = p.num_rotations();
        let mut starts = vec![truth];
        for _ in 0..11 {
            starts.push((0..n).map(|_| random_rotation(rng)).collect());
        }
        starts
            .into_iter()
            .filter_map(|s| {
                let st = MultipleSettings {
                    init: Initialisation::Given(s),
                    gradient_tolerance: 1e-14,
                    ..Default::default()
                };
                solve_multiple(p, &st).ok()
            })
            .collect()
    }

    /// The local solutions with their costs, and perturbed optima (1e-7 to 0.1 rad per node):
    /// not critical points, so rho (and the deficit) matter.
    fn sampled_points(
        p: &MultipleProblem,
        sols: &[MultipleSolution],
        best: f64,
        rng: &mut StdRng,
    ) -> Vec<(Vec<Rotation>, f64)> {
        let mut points: Vec<(Vec<Rotation>, f64)> = sols
            .iter()
            .map(|s| (s.rotations.clone(), s.chordal_cost))
            .collect();
        if let Some(opt) = sols.iter().find(|s| s.chordal_cost <= best) {
            for eps in [1e-7, 1e-5, 1e-3, 1e-1] {
                let y: Vec<Rotation> = opt
                    .rotations
                    .iter()
                    .map(|r| r * crate::so3::perturb_gaussian(&Rotation::identity(), eps, rng))
                    .collect();
                let f = p.chordal_cost(&y);
                points.push((y, f));
            }
        }
        points
    }

    /// How many grounded bounds and non-global points the soundness test checked.
    #[derive(Default)]
    struct GroundedCounts {
        grounded: usize,
        non_global: usize,
    }

    impl GroundedCounts {
        /// The dual certificate at `rotations` (cost `cost`): its bound at most the best cost
        /// `best` of the local solutions; a grounded bound's verified `lambda_min` at most the
        /// dense one; a point above `best` never certified.
        fn check(
            &mut self,
            p: &MultipleProblem,
            rotations: &[Rotation],
            cost: f64,
            best: f64,
            case: usize,
        ) {
            let c = dual_certificate(p, rotations, &CertifySettings::default()).unwrap();
            let b = &c.bound;
            assert!(
                b.lower_bound <= best + 1e-10 * (1.0 + best),
                "case {case}: bound {} above the best cost {best}",
                b.lower_bound
            );
            if b.verification == Proof::Grounded {
                self.grounded += 1;
                let l = multipliers(p, rotations).unwrap();
                let s = certificate_matrix(p, &l).unwrap();
                let dense = dense_lambda_min(&s);
                let scale = inf_norm(s.as_ref());
                assert!(
                    b.verified_min_eigenvalue <= dense + 1e-12 * (1.0 + scale),
                    "case {case}: verified {} above the dense lambda_min {dense}",
                    b.verified_min_eigenvalue
                );
            }
            if cost > best + 1e-6 * (1.0 + best) {
                self.non_global += 1;
                assert!(
                    !c.certificate.is_certified(),
                    "case {case}: a non-global local solution was certified: {c}"
                );
            }
        }
    }

    /// Regression (found when [D15] made the gaps tiny): on a tree the global minimum is ~0, and
    /// the measured rotations, made from quaternions, are orthogonal only to rounding, so
    /// `tr(Y^T Q Y)` exceeds the chordal cost by `c_0 = sum w (3 - ||R_ij||_F^2)` of order
    /// `1e-16 m w`. The bound must account for it: it was `5.9e-17 > f* ~ 0` on
    /// pose3Localizationexample.txt before.
    #[test]
    fn lower_bound_accounts_for_non_orthogonal_measurements() {
        let mut rng = StdRng::seed_from_u64(3);
        for weight in [1.0, 1e6] {
            let n = 12;
            let truth: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
            let edges: Vec<_> = (1..n)
                .map(|j| {
                    let i = j / 2; // a binary tree
                    let exact = truth[j] * truth[i].inverse();
                    // through a quaternion, as the readers do: orthogonal to rounding only
                    let q = nalgebra::UnitQuaternion::from_rotation_matrix(&exact);
                    crate::multiple::Edge {
                        i,
                        j,
                        rotation: q.to_rotation_matrix(),
                        weight,
                    }
                })
                .collect();
            let p = MultipleProblem::new(n, edges).unwrap();
            let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            // the residuals of a tree vanish up to the measurements' own rounding
            assert!(sol.chordal_cost < 1e-26 * weight);
            let c = dual_certificate(&p, &sol.rotations, &CertifySettings::default()).unwrap();
            assert!(
                c.bound.lower_bound <= 1e-28 * weight,
                "weight {weight}: bound {} above the minimum ~0",
                c.bound.lower_bound
            );
            assert!(c.certificate.is_certified(), "{c}");
        }
    }

    /// The winding configurations of the z-cycle [D10] are critical points that are not global:
    /// `S` is indefinite, `S` without a block is not positive definite, and [D15] does not
    /// apply (whatever the ground).
    #[test]
    fn grounded_bound_refuses_indefinite_certificate_matrices() {
        for (n, phi) in [(6, 0.5), (12, 0.3)] {
            let p = z_cycle(n, phi);
            let y: Vec<Rotation> = (0..n)
                .map(|i| {
                    crate::so3::exp(
                        &(nalgebra::Vector3::z()
                            * (i as f64 * 2.0 * std::f64::consts::PI / n as f64)),
                    )
                })
                .collect();
            let l = multipliers(&p, &y).unwrap();
            let settings = CertifySettings::default();
            let scope = crate::certify::multiple::check::Scope {
                point: Point::Given,
                within: Proof::DualCertificate,
                deadline: crate::certify::budget::Deadline::start(&settings.budget),
                refinement_follows: None,
            };
            let mut cx = Check::new(&p, &l, Some(&y), 1.0, &settings, scope).unwrap();
            let mut proof = GroundedProof::default();
            if let Plan::Run(_) = proof.plan(&cx).unwrap() {
                let found = proof.attempt(&mut cx).unwrap();
                let proved = matches!(found.outcome, crate::certify::log::Outcome::Proved { .. });
                assert!(!proved, "n={n}: {found:?}");
            }
            assert!(cx.best.is_none(), "n={n}");
        }
    }
}
