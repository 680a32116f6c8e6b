//! The rig's joint Gauss-Newton (`paper-notes/conjugate.md` `[H19]` "Joint steps"): the frames
//! and the unknown sensors move together, each step a Levenberg-Marquardt step of `J(F, S)` in
//! both. Each step's system (frames' block: the sparse `3(n-1) x 3(n-1)` pattern of the frames'
//! view graph, frame 0 held; the `3K` sensors dense) is solved by conjugate gradients on the whole
//! system, preconditioned by the frames' scalar Laplacian `[M6b]` (block-Jacobi on expander-like
//! view graphs) and the sensors' block, to an inexact-Newton tolerance; where those run past
//! about the time of a factorisation, by the frames' sparse Cholesky with the sensors eliminated
//! by their Schur complement (`3K + 1` right-hand sides). No `3n x 3n` dense matrix is formed.
//! Once the steps are small the systems take Newton's Hessian (the residuals' second-order
//! terms, [`Joint::hessian`]), back to Gauss-Newton's where it is indefinite.
//!
//! Each edge's term is `4 (tr M - tr(M E))`, `E = R^T X_b X_a^T`, `X = S F` (`[A1]`; scalar
//! weights are `H = w I`, `M = w/2 I`). Under right perturbations `S exp([d]x)`, `F exp([phi]x)`
//! the rotation `E` moves on the left by `omega` with `omega = R^T S_t d_t + R^T X_b phi_g - E S_s
//! d_s - E X_a phi_f` to first order (images `a = (f, s)`, `b = (g, t)`), the term's gradient in
//! `omega` is `gamma_k = -4 tr([e_k]x E M)`, and its Gauss-Newton Hessian `4 J^T H J` (of `2
//! omega^T H omega`, the term to second order at `E = I`). The systems below hold half of each.

use super::problem::RigProblem;
use crate::deadline::{Deadline, limit_reached};
use crate::error::Result;
use crate::linalg::block_pattern::{BlockPattern, SymbolicFactor};
use crate::linalg::linear_solver::{LinearSolver, ScalarLaplacian, SolverKind, jacobi_inverses};
use crate::linalg::threads::{PARALLEL_EDGES, in_chunks};
use crate::multiple::chordal::{choose_solver, grounded_pattern};
use crate::so3::{Rotation, exp, nearest_rotation};
use crate::termination::Termination;
use faer::Mat;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// The relative predicted decrease of `J` below which the steps stop: about the rounding of a
/// sum of `10^5` terms.
pub const JOINT_TOLERANCE: f64 = 1e-14;

/// The largest factor of the frames' block (stored values: 400 MB) the steps fall back to when
/// their conjugate gradients run long.
pub const JOINT_DIRECT_VALUES: usize = 50_000_000;

/// The most multiply-adds of that factorisation (about 0.5-0.8 s on the 2-core reference
/// machine). Beyond either limit the frames' factor fills (random view graphs: 2.8e8 values at
/// 10^4 frames) and the steps keep their conjugate gradients (at most
/// [`JOINT_CG_ITERATIONS`] per step).
pub const JOINT_MULTIPLY_ADDS: f64 = 1e10;

/// The relative rounding of `J`'s sum within which a step below [`JOINT_TOLERANCE`] may raise
/// it when it halves the gradient (the certificate's couplings need the sensors' gradient far
/// below what `J`'s decrease resolves, `[H21]`).
const COST_ROUNDING: f64 = 1e-12;

/// The largest damping (relative to the diagonal) at which a small predicted decrease means
/// convergence. Beyond it the Gauss-Newton model is not trusted: on the world rig of `[G16]`
/// (priors with information `w diag(1, 1, 0)`) the steps were refused up to a damping of `1e2`
/// 2.3e-4 above the minimum, the gradient stuck at 4e-6, and the alternation passes found it.
const TRUSTED_DAMPING: f64 = 1e-3;

/// Steps at most per call.
pub const JOINT_MAX_STEPS: usize = 100;

/// Conjugate-gradient iterations at most per step where there is no frames' factor to fall
/// back to (each iterate still decreases the step's model: a step cut short still descends).
pub const JOINT_CG_ITERATIONS: usize = 1000;

/// The fewest conjugate-gradient iterations a step is given before the frames' factor takes
/// over.
const JOINT_CG_MIN_BUDGET: usize = 30;

/// The relative predicted decrease below which the steps take Newton's Hessian of `J` (the
/// residuals' second-order terms) instead of Gauss-Newton's. Gauss-Newton converges linearly
/// where the residuals are large against the weak directions' curvature: on a rig of 10^4
/// frames and 2 sensors along a path of 3-frame pairs with information matrices, 56 steps and
/// then alternation passes (11.1 s) against 9 steps (5.1 s) with Newton's Hessian from here.
/// Far from the minimum it is indefinite (on the 3x10^4-frame such rig 7x slower from the
/// start), and where it is near the minimum too (damping above [`TRUSTED_DAMPING`] finds no
/// step) the steps go back to Gauss-Newton's for good.
const JOINT_NEWTON_FROM: f64 = 1e-6;

/// The conjugate gradients' relative residual at the first step (inexact Newton); later steps
/// take the square root of the last relative predicted decrease, within
/// `[JOINT_CG_FINEST, JOINT_CG_FORCING]`.
const JOINT_CG_FORCING: f64 = 1e-2;

/// The finest relative residual the conjugate gradients are asked for.
const JOINT_CG_FINEST: f64 = 1e-10;

/// One edge: its images' frames and sensors, `R`, `H` and `M`, and the frames' slot.
#[derive(Clone, Copy)]
struct Term {
    frames: (usize, usize),
    sensors: (usize, usize),
    r: Matrix3<f64>,
    h: Matrix3<f64>,
    m: Matrix3<f64>,
    slot: usize,
}

/// A variable group of one edge: a frame's block (frames `1..n` as blocks `0..n-1`) or an
/// unknown sensor's column in the dense part.
#[derive(Clone, Copy)]
enum Var {
    Frame(usize),
    Sensor(usize),
}

/// Each variable group's `omega` Jacobian in one term (at most four: two frames, two sensors).
type Jacobians = [Option<(Var, Matrix3<f64>)>; 4];

/// A step taken: the point, `J` and the system there, and the step's relative predicted
/// decrease.
struct Taken {
    frames: Vec<Rotation>,
    sensors: Vec<Rotation>,
    cost: f64,
    system: System,
    relative: f64,
}

/// The joint steps of a rig without gravity priors with sensors to estimate.
pub(super) struct Joint<'a> {
    problem: &'a RigProblem,
    terms: Vec<Term>,
    /// Each sensor's first column in the dense part (`None`: held).
    column: Vec<Option<usize>>,
    unknown: Vec<usize>,
    /// The frames' pattern and factor, shared by the reweightings of one robust solve.
    shape: Arc<Shape>,
    /// The frames' preconditioner `[M6b]` where the frames' view graph is not expander-like
    /// ([`frames_laplacian`]); block-Jacobi otherwise.
    laplacian: Option<ScalarLaplacian>,
    /// Conjugate-gradient iterations per step before the factor takes over (where there is
    /// one): about the time of one factorisation ([`cg_budget`]).
    cg_budget: usize,
    /// Set when a step's conjugate gradients ran out of `cg_budget`: the factor then solves
    /// this step and every later one.
    factorise: AtomicBool,
    /// Set once the steps are small ([`JOINT_NEWTON_FROM`]): the systems built from then on
    /// carry Newton's Hessian ([`Joint::hessian`]) instead of Gauss-Newton's.
    newton: AtomicBool,
}

/// What the steps need of a rig's structure alone (its images, the ends of its edges, its
/// held sensors; not its weights): made by [`Joint::new`], shared by [`Joint::reweighted`]. A
/// robust solve's reweightings keep the rig and change its weights; at 10^4 frames and 6
/// sensors this part took 0.1-0.13 s (the symbolic factor's ordering most of it) of each
/// reweighting's 0.45 s.
struct Shape {
    pattern: BlockPattern,
    /// The frames' sparse Cholesky, where it fits ([`JOINT_DIRECT_VALUES`],
    /// [`JOINT_MULTIPLY_ADDS`], the caller's memory).
    direct: Option<LinearSolver>,
    /// Whether the frames' Laplacian preconditioner applies (the frames' view graph is not
    /// expander-like, [`choose_solver`]), within `max_values`.
    laplacian: bool,
    max_values: usize,
}

/// Multiply-adds per second of a sparse Cholesky factorisation, and values per second of a
/// sparse product or triangular solve, on the 2-core reference machine (measured at 10^4
/// frames: a factor of 5.6e9 multiply-adds in 0.36-0.49 s; a conjugate-gradient iteration over
/// 2.5e6 values in 2.2 ms). Only their ratio matters: it sets [`cg_budget`].
const FACTOR_RATE: f64 = 1.2e10;
const SPARSE_RATE: f64 = 1e9;

/// The conjugate-gradient iterations that take about as long as one step by the frames'
/// factor (a factorisation and `3K + 1` right-hand sides of it; an iteration: the product and
/// the preconditioner), within `[JOINT_CG_MIN_BUDGET, JOINT_CG_ITERATIONS]`;
/// [`JOINT_CG_ITERATIONS`] without a factor. On random view graphs the factor fills and
/// conjugate gradients converge in tens of iterations.
fn cg_budget(
    pattern: &BlockPattern,
    (symbolic, laplacian): (Option<&SymbolicFactor>, Option<&ScalarLaplacian>),
    sensors: usize,
) -> usize {
    let Some(f) = symbolic else {
        return JOINT_CG_ITERATIONS;
    };
    let rows = (pattern.col_ptr().len() - 1) as f64;
    let columns = (3 * sensors + 1) as f64;
    let factor = f.multiply_adds() / FACTOR_RATE + 2.0 * columns * f.len_val() as f64 / SPARSE_RATE;
    let preconditioner = laplacian.map_or(0.0, |l| 6.0 * l.factor_len() as f64);
    let product = 2.0 * (pattern.nnz() as f64 + rows * 3.0 * sensors as f64);
    let iteration = (product + preconditioner) / SPARSE_RATE;
    ((factor / iteration) as usize).clamp(JOINT_CG_MIN_BUDGET, JOINT_CG_ITERATIONS)
}

/// The frames' scalar Laplacian preconditioner `[M6b]`, `K ⊗ I_3` with `K` the frames' view
/// graph's Laplacian grounded at frame 0, each edge weighted `2 tr(H) / 3`: under right
/// perturbations of the frames both ends of a consistent edge move `omega` by `X_a`, so the
/// frames' block of the (half) Gauss-Newton Hessian is `sum 2 X_a^T H X_a (e_f - e_g)(e_f -
/// e_g)^T`, which scalar weights make exactly `K ⊗ I_3` and information matrices approximate by
/// their trace. The same factor serves every step. `None` where the multiple solver would not
/// use it ([`Shape::laplacian`]: expander-like graphs, whose factor fills; block-Jacobi there),
/// where its factor has more than the shape's `max_values` values (the caller's memory), or
/// where `K` is not numerically positive definite.
fn frames_laplacian(
    shape: &Shape,
    num_frames: usize,
    terms: &[Term],
) -> Result<Option<ScalarLaplacian>> {
    if !shape.laplacian {
        return Ok(None);
    }
    let frame = |f: usize| f.checked_sub(1);
    let edges: Vec<_> = (terms.iter())
        .filter(|t| t.frames.0 != t.frames.1)
        .map(|t| {
            (
                frame(t.frames.0),
                frame(t.frames.1),
                2.0 * t.h.trace() / 3.0,
            )
        })
        .collect();
    let nodes = num_frames - 1;
    let pattern = ScalarLaplacian::pattern(nodes, &edges);
    let Some(symbolic) = pattern.symbolic_llt_within(shape.max_values)? else {
        return Ok(None);
    };
    ScalarLaplacian::new(nodes, &edges, 0.0, None, Some(symbolic))
}

/// Each edge's [`Term`], its frames' slot in `pattern`.
fn terms(problem: &RigProblem, pattern: &BlockPattern) -> Vec<Term> {
    let info = problem.information();
    (problem.edges().iter().enumerate())
        .map(|(k, e)| {
            let (a, b) = (problem.images()[e.i], problem.images()[e.j]);
            let (h, m) = term_matrices(info, k, e);
            let (f, g) = (a.frame, b.frame);
            let slot = match (f.max(g), f.min(g)) {
                (hi, lo) if lo >= 1 && hi != lo => pattern.slot(hi - 1, lo - 1),
                _ => 0,
            };
            Term {
                frames: (f, g),
                sensors: (a.sensor, b.sensor),
                r: *e.rotation.matrix(),
                h,
                m,
                slot,
            }
        })
        .collect()
}

/// Edge `k`'s `H` and `M` (`w I` and `w I / 2` with scalar weights).
fn term_matrices(
    info: Option<&[crate::multiple::anisotropic::Information]>,
    k: usize,
    e: &crate::multiple::Edge,
) -> (Matrix3<f64>, Matrix3<f64>) {
    match info {
        Some(info) => (*info[k].matrix(), info[k].chordal_matrix()),
        None => (
            e.weight * Matrix3::identity(),
            0.5 * e.weight * Matrix3::identity(),
        ),
    }
}

/// A step: the frames' and the sensors' moves and the model's predicted decrease of `J`.
type Step = (Vec<f64>, DVector<f64>, f64);

/// A damped system: the frames' values and the sensors' block with the damping added, and the
/// damping's diagonal (frames, then sensors).
struct Damped {
    frames: Vec<f64>,
    sensors: DMatrix<f64>,
    added: Vec<f64>,
}

impl Damped {
    /// `y = (h + D) x`, the damped system's product (frames then sensors; `coupling`: the
    /// frames-sensors block).
    fn times(&self, pattern: &BlockPattern, coupling: &Mat<f64>, x: &[f64], y: &mut [f64]) {
        let rows = coupling.nrows();
        let (xf, xs) = x.split_at(rows);
        let (yf, ys) = y.split_at_mut(rows);
        pattern.sym_mul_flat(&self.frames, xf, yf);
        for u in 0..coupling.ncols() {
            let (column, xu) = (coupling.col_as_slice(u), xs[u]);
            for (y, c) in yf.iter_mut().zip(column) {
                *y += c * xu;
            }
            let along: f64 = column.iter().zip(xf).map(|(c, x)| c * x).sum();
            ys[u] = along
                + (0..xs.len())
                    .map(|v| self.sensors[(u, v)] * xs[v])
                    .sum::<f64>();
        }
    }
}

impl System {
    /// The gradient's Euclidean norm (half of it).
    fn gradient_norm(&self) -> f64 {
        let frames: f64 = self.frames_g.iter().map(|g| g * g).sum();
        (frames + self.sensors_g.norm_squared()).sqrt()
    }
}

/// Half the gradient and half the Gauss-Newton Hessian of `J` at a point: the frames' block
/// (values on the pattern), the frames-sensors block, the sensors' block.
struct System {
    frames_h: Vec<f64>,
    coupling: Mat<f64>,
    sensors_h: DMatrix<f64>,
    frames_g: Vec<f64>,
    sensors_g: DVector<f64>,
}

impl System {
    /// Adds `other` (of the same shape) term by term.
    fn add(&mut self, other: &System) {
        let sum = |a: &mut [f64], b: &[f64]| a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        sum(&mut self.frames_h, &other.frames_h);
        sum(&mut self.frames_g, &other.frames_g);
        sum(self.sensors_h.as_mut_slice(), other.sensors_h.as_slice());
        sum(self.sensors_g.as_mut_slice(), other.sensors_g.as_slice());
        for j in 0..self.coupling.ncols() {
            let column = other.coupling.col(j);
            (self.coupling.col_mut(j).iter_mut())
                .zip(column.iter())
                .for_each(|(x, y)| *x += y);
        }
    }
}

impl<'a> Joint<'a> {
    /// The steps of `problem` (the frames' block's pattern from its frames' view graph at
    /// `sensors`; the frames' factor to fall back to, and the frames' Laplacian
    /// preconditioner, only within `max_values`, a caller's memory budget, and
    /// [`JOINT_DIRECT_VALUES`]; the factor also within [`JOINT_MULTIPLY_ADDS`]), `None` with
    /// gravity priors, no sensor to estimate, or a single frame.
    pub fn new(
        problem: &'a RigProblem,
        sensors: &[Rotation],
        max_values: usize,
    ) -> Result<Option<Self>> {
        if !Self::applies(problem) {
            return Ok(None);
        }
        let (graph, _) = problem.frame_graph_for_solve(sensors)?;
        let pattern = grounded_pattern(&graph, 3);
        let max_values = max_values.min(JOINT_DIRECT_VALUES);
        let symbolic = pattern.symbolic_llt_within(max_values)?;
        let symbolic = symbolic.filter(|f| f.multiply_adds() <= JOINT_MULTIPLY_ADDS);
        let terms = terms(problem, &pattern);
        let shape = Shape {
            pattern,
            direct: symbolic.map(LinearSolver::Direct),
            laplacian: choose_solver(&graph)?.kind != SolverKind::Jacobi,
            max_values,
        };
        Self::with_terms(problem, Arc::new(shape), terms).map(Some)
    }

    /// The steps of `problem`, this rig with other weights (a robust solve's reweighting, which
    /// changes nothing else): this one's [`Shape`], the terms' weights from `problem`. `None`
    /// when `problem` is another rig (its images, the ends of its edges or its held sensors
    /// differ).
    pub(super) fn reweighted<'b>(&self, problem: &'b RigProblem) -> Result<Option<Joint<'b>>> {
        let (old, new) = (self.problem, problem);
        let (a, b) = (old.edges().iter(), new.edges().iter());
        let same_ends = a.map(|e| (e.i, e.j)).eq(b.map(|e| (e.i, e.j)));
        if old.images() != new.images() || old.held() != new.held() || !same_ends {
            return Ok(None);
        }
        let info = problem.information();
        let terms = (self.terms.iter().zip(problem.edges().iter().enumerate()))
            .map(|(t, (k, e))| {
                let (h, m) = term_matrices(info, k, e);
                let r = *e.rotation.matrix();
                Term { r, h, m, ..*t }
            })
            .collect();
        Joint::with_terms(problem, self.shape.clone(), terms).map(Some)
    }

    /// The steps of `problem` with its `shape` and `terms`.
    fn with_terms(problem: &'a RigProblem, shape: Arc<Shape>, terms: Vec<Term>) -> Result<Self> {
        let unknown = problem.estimated_sensors();
        let laplacian = frames_laplacian(&shape, problem.num_frames(), &terms)?;
        let symbolic = match &shape.direct {
            Some(LinearSolver::Direct(f)) => Some(f),
            _ => None,
        };
        let solvers = (symbolic, laplacian.as_ref());
        let cg_budget = cg_budget(&shape.pattern, solvers, unknown.len());
        let mut column = vec![None; problem.held().len()];
        for (k, &s) in unknown.iter().enumerate() {
            column[s] = Some(3 * k);
        }
        Ok(Joint {
            problem,
            terms,
            column,
            unknown,
            shape,
            laplacian,
            cg_budget,
            factorise: AtomicBool::new(false),
            newton: AtomicBool::new(false),
        })
    }

    /// Whether [`Joint::new`] gives steps for `problem`: no gravity priors, a sensor to
    /// estimate, two frames or more.
    pub(super) fn applies(problem: &RigProblem) -> bool {
        let unknown = problem.estimated_sensors();
        problem.gravity().is_none() && !unknown.is_empty() && problem.num_frames() >= 2
    }

    /// Levenberg-Marquardt steps from `(frames, sensors)` until the predicted decrease is below
    /// [`JOINT_TOLERANCE`] of `J` (with `polish`, until the steps within it stop halving the
    /// gradient: a certificate's polish, `[H21]`), no damping gives a decrease, `max_steps`, or
    /// `deadline`: the point, the steps taken and why they stopped. No step increases `J`
    /// (beyond [`COST_ROUNDING`] when polishing).
    pub fn run(
        &self,
        (mut frames, mut sensors): (Vec<Rotation>, Vec<Rotation>),
        (max_steps, polish): (usize, bool),
        deadline: Option<Deadline>,
    ) -> (Vec<Rotation>, Vec<Rotation>, usize, Termination) {
        let mut cost = self.problem.cost(&frames, &sensors);
        let (mut damping, mut relative) = (1e-6, f64::NAN);
        let mut system = self.system(&frames, &sensors);
        let (mut steps, mut eta) = (0, JOINT_CG_FORCING);
        let stop_at = deadline.and_then(|d| d.instant());
        let mut newton_refused = false;
        self.newton.store(false, Ordering::Relaxed);
        let stop = loop {
            let measure = (relative, JOINT_TOLERANCE);
            if let Some(limit) = limit_reached(steps, max_steps, deadline, measure) {
                break limit;
            }
            let (solve, before) = ((eta, stop_at), damping);
            let at = (&frames[..], &sensors[..]);
            let taken = self.accepted(at, (cost, polish), (&system, solve), &mut damping);
            let taken = match taken {
                Ok(taken) => taken,
                Err(last) => {
                    let stop = self.converged(last, damping);
                    if !self.newton.load(Ordering::Relaxed)
                        || !matches!(stop, Termination::Stalled { .. })
                    {
                        break stop;
                    }
                    // Newton's Hessian is indefinite about this point: Gauss-Newton from it
                    (newton_refused, damping) = (true, before);
                    self.newton.store(false, Ordering::Relaxed);
                    system = self.system(&frames, &sensors);
                    continue;
                }
            };
            (frames, sensors, relative) = (taken.frames, taken.sensors, taken.relative);
            (cost, system) = (taken.cost, taken.system);
            // inexact Newton: the conjugate gradients' tolerance follows the decrease
            eta = relative.sqrt().clamp(JOINT_CG_FINEST, JOINT_CG_FORCING);
            if !newton_refused && relative < JOINT_NEWTON_FROM {
                self.newton.store(true, Ordering::Relaxed);
            }
            steps += 1;
            crate::progress::phase(crate::progress::Phase::Solve, || {
                format!(
                    "rig joint step {steps}: J = {cost:.6e}, predicted relative decrease {relative:.1e}"
                )
            });
        };
        (frames, sensors, steps, stop)
    }

    /// The damped step from `(frames, sensors)` that is taken, with `J` and the system there and
    /// its relative predicted decrease: above [`JOINT_TOLERANCE`], the first damping that does
    /// not increase `J` (raising `damping` tenfold per refusal); within it (the decrease is
    /// below `J`'s rounding) and `polish`, the step when `J` stays within [`COST_ROUNDING`] and
    /// the gradient at least halves. Otherwise the last relative predicted decrease (infinite when no
    /// damping gave a step).
    fn accepted(
        &self,
        (frames, sensors): (&[Rotation], &[Rotation]),
        (cost, polish): (f64, bool),
        (system, solve): (&System, (f64, Option<Instant>)),
        damping: &mut f64,
    ) -> std::result::Result<Taken, f64> {
        let mut last = f64::INFINITY;
        while *damping <= 1e12 {
            let Some((dx, dy, decrease)) = self.step(system, *damping, solve) else {
                *damping *= 10.0;
                continue;
            };
            let relative = (decrease / cost.abs().max(f64::MIN_POSITIVE)).max(0.0);
            last = relative;
            let (f, s) = self.moved((frames, sensors), (&dx, &dy));
            let next = self.problem.cost(&f, &s);
            let within = relative <= JOINT_TOLERANCE;
            if within && (!polish || next > cost * (1.0 + COST_ROUNDING)) {
                return Err(relative);
            }
            if within || next <= cost {
                let at = self.system(&f, &s);
                if within && at.gradient_norm() > 0.5 * system.gradient_norm() {
                    return Err(relative);
                }
                if !within {
                    *damping = (*damping * 0.1).max(1e-12);
                }
                return Ok(Taken {
                    frames: f,
                    sensors: s,
                    cost: next,
                    system: at,
                    relative,
                });
            }
            *damping *= 10.0;
        }
        Err(last)
    }

    /// Converged when the predicted decrease is within [`JOINT_TOLERANCE`] of `J` at a damping
    /// of at most [`TRUSTED_DAMPING`] (a heavily damped step predicts little whatever the
    /// gradient); stalled otherwise, or when no damping decreases `J`.
    fn converged(&self, relative: f64, damping: f64) -> Termination {
        if relative <= JOINT_TOLERANCE && damping <= TRUSTED_DAMPING {
            return Termination::Converged {
                measure: "predicted decrease of J / J (joint Gauss-Newton)".into(),
                value: relative,
                threshold: JOINT_TOLERANCE,
            };
        }
        Termination::Stalled {
            value: relative,
            threshold: JOINT_TOLERANCE,
        }
    }

    /// `F_f exp([dx_f]x)` (frame 0 held) and `S_s exp([dy_s]x)` for the unknown sensors.
    fn moved(
        &self,
        (frames, sensors): (&[Rotation], &[Rotation]),
        (dx, dy): (&[f64], &DVector<f64>),
    ) -> (Vec<Rotation>, Vec<Rotation>) {
        let mut f = frames.to_vec();
        for (k, frame) in f.iter_mut().enumerate().skip(1) {
            let d = Vector3::new(dx[3 * k - 3], dx[3 * k - 2], dx[3 * k - 1]);
            *frame = nearest_rotation(&(*frame * exp(&d)));
        }
        let mut s = sensors.to_vec();
        for (k, &u) in self.unknown.iter().enumerate() {
            let d = Vector3::new(dy[3 * k], dy[3 * k + 1], dy[3 * k + 2]);
            s[u] = nearest_rotation(&(s[u] * exp(&d)));
        }
        (f, s)
    }

    /// The damped step `(dx, dy)` and its predicted decrease (of `J`'s model
    /// `J + 2 g^T d + d^T h d`), or `None` when the damped system is not positive definite: by
    /// conjugate gradients to the relative residual `eta` ([`Self::iterative_step`]) or, once
    /// they have run past `cg_budget` where there is a frames' factor, by that factor
    /// ([`Self::direct_step`]).
    fn step(
        &self,
        s: &System,
        damping: f64,
        (eta, stop_at): (f64, Option<Instant>),
    ) -> Option<Step> {
        let damped = self.damped(s, damping);
        if !self.factorise.load(Ordering::Relaxed) {
            let (step, converged) = self.iterative_step(s, &damped, (eta, stop_at))?;
            if converged || self.shape.direct.is_none() {
                return Some(step);
            }
            self.factorise.store(true, Ordering::Relaxed);
        }
        self.direct_step(s, &damped)
    }

    /// The damped system's frames' values and sensors' block, and the damping's diagonal
    /// (`damping` times each diagonal entry, at least `1e-12` of the largest: frames, then
    /// sensors).
    fn damped(&self, s: &System, damping: f64) -> Damped {
        let mut frames = s.frames_h.clone();
        let diagonal = self.shape.pattern.diagonal(&frames);
        let largest = diagonal.iter().fold(f64::MIN_POSITIVE, |m, &d| m.max(d));
        let floor = 1e-12 * largest;
        let sensors_diagonal = (0..s.sensors_g.len()).map(|u| s.sensors_h[(u, u)]);
        let added: Vec<f64> = (diagonal.into_iter().chain(sensors_diagonal))
            .map(|d| damping * d.max(floor))
            .collect();
        let pointers = self.shape.pattern.col_ptr();
        let rows = s.frames_g.len();
        for (c, d) in added[..rows].iter().enumerate() {
            frames[pointers[c]] += d;
        }
        let mut sensors = s.sensors_h.clone();
        for (u, d) in added[rows..].iter().enumerate() {
            sensors[(u, u)] += d;
        }
        Damped {
            frames,
            sensors: 0.5 * (&sensors + sensors.transpose()),
            added,
        }
    }

    /// [`Self::step`] by the frames' factor, the sensors by its Schur complement.
    fn direct_step(&self, s: &System, d: &Damped) -> Option<Step> {
        let factor = self
            .shape
            .direct
            .as_ref()?
            .factor(&self.shape.pattern, &d.frames)?;
        let (rows, k) = (s.frames_g.len(), s.sensors_g.len());
        let mut b = Mat::from_fn(rows, k + 1, |r, c| match c < k {
            true => s.coupling[(r, c)],
            false => s.frames_g[r],
        });
        // a direct factor: no tolerance, no iterations
        factor.solve(&mut b, 0.0, 0)?;
        // Schur complement: (C - B^T Y) y = -g_S + B^T z, Y = A^-1 B, z = A^-1 g_F
        let mut c = d.sensors.clone();
        let mut rhs = -&s.sensors_g;
        for u in 0..k {
            for r in 0..rows {
                rhs[u] += s.coupling[(r, u)] * b[(r, k)];
            }
            for v in 0..k {
                c[(u, v)] -= (0..rows)
                    .map(|r| s.coupling[(r, u)] * b[(r, v)])
                    .sum::<f64>();
            }
        }
        let c = 0.5 * (&c + c.transpose());
        let dy = c.cholesky()?.solve(&rhs);
        let dx: Vec<f64> = (0..rows)
            .map(|r| -b[(r, k)] - (0..k).map(|v| b[(r, v)] * dy[v]).sum::<f64>())
            .collect();
        // exact: d^T (h + D) d = -g^T d, so the model's decrease is -g^T d + d^T D d
        let mut decrease = -s.sensors_g.dot(&dy);
        decrease -= s.frames_g.iter().zip(&dx).map(|(g, d)| g * d).sum::<f64>();
        decrease += (d.added.iter().zip(dx.iter().chain(dy.iter())))
            .map(|(a, x)| a * x * x)
            .sum::<f64>();
        Some((dx, dy, decrease))
    }

    /// [`Self::step`] by conjugate gradients on the whole damped system (frames and sensors),
    /// preconditioned by the frames' diagonal blocks and the sensors' block, to the relative
    /// residual `eta` (or `cg_budget` iterations, or `stop_at`), and whether it stopped before
    /// the budget. Every iterate decreases the model, so an inexact step still descends; its
    /// decrease is evaluated, not assumed. `None`: a block or the system is not positive
    /// definite.
    fn iterative_step(
        &self,
        s: &System,
        d: &Damped,
        (eta, stop_at): (f64, Option<Instant>),
    ) -> Option<(Step, bool)> {
        let rows = s.frames_g.len();
        // block-Jacobi on the frames where there is no Laplacian preconditioner
        let blocks = match self.laplacian {
            Some(_) => Vec::new(),
            None => jacobi_inverses(&self.shape.pattern, &d.frames)?,
        };
        let sensors_inverse = d.sensors.clone().cholesky()?.inverse();
        let pattern = &self.shape.pattern;
        let times = |x: &[f64], y: &mut [f64]| d.times(pattern, &s.coupling, x, y);
        let laplacian = self.laplacian.as_ref();
        let apply = |r: &[&[f64]], z: &mut [&mut [f64]]| {
            if let Some(l) = laplacian {
                let frames: Vec<&[f64]> = r.iter().map(|rk| &rk[..rows]).collect();
                let mut out: Vec<&mut [f64]> = z.iter_mut().map(|zk| &mut zk[..rows]).collect();
                l.apply(&frames, &mut out);
            }
            for (rk, zk) in r.iter().zip(z.iter_mut()) {
                if laplacian.is_none() {
                    for (q, m) in blocks.iter().enumerate() {
                        let v = m * Vector3::new(rk[3 * q], rk[3 * q + 1], rk[3 * q + 2]);
                        zk[3 * q..3 * q + 3].copy_from_slice(v.as_slice());
                    }
                }
                let v = &sensors_inverse * DVector::from_column_slice(&rk[rows..]);
                zk[rows..].copy_from_slice(v.as_slice());
            }
        };
        let g: Vec<f64> = s
            .frames_g
            .iter()
            .chain(s.sensors_g.iter())
            .copied()
            .collect();
        let rhs: Vec<f64> = g.iter().map(|v| -v).collect();
        let limits = (self.cg_budget, stop_at);
        let (mut x, iterations) = crate::linalg::pcg::pcg(&times, &apply, &[rhs], eta, limits)?;
        let x = x.pop()?;
        // the model's decrease -(2 g^T d + d^T h d), h = (h + D) - D
        let mut hx = vec![0.0; x.len()];
        times(&x, &mut hx);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let damping: f64 = (d.added.iter().zip(&x)).map(|(a, v)| a * v * v).sum();
        let decrease = -(2.0 * dot(&g, &x) + dot(&x, &hx) - damping);
        let dy = DVector::from_column_slice(&x[rows..]);
        let mut dx = x;
        dx.truncate(rows);
        Some(((dx, dy, decrease), iterations < self.cg_budget))
    }

    /// The half gradient and half Gauss-Newton Hessian at `(frames, sensors)`: from
    /// [`PARALLEL_EDGES`] terms on, the sum of the two halves' systems, each half on its own
    /// thread where there are two (the same halves and the same sum on one thread).
    fn system(&self, frames: &[Rotation], sensors: &[Rotation]) -> System {
        let n = self.terms.len();
        if n < PARALLEL_EDGES {
            return self.system_of(&self.terms, frames, sensors);
        }
        let mut halves = [0..n / 2, n / 2..n];
        let parts = in_chunks(&mut halves, true, |_, hs| {
            (hs.iter())
                .map(|h| self.system_of(&self.terms[h.clone()], frames, sensors))
                .collect::<Vec<_>>()
        });
        let mut parts = parts.into_iter().flatten();
        let mut s = parts.next().expect("two halves");
        parts.for_each(|other| s.add(&other));
        s
    }

    /// The part of [`Joint::system`] of `terms`.
    fn system_of(&self, terms: &[Term], frames: &[Rotation], sensors: &[Rotation]) -> System {
        let rows = 3 * (frames.len() - 1);
        let k = 3 * self.unknown.len();
        let mut s = System {
            frames_h: vec![0.0; self.shape.pattern.nnz()],
            coupling: Mat::zeros(rows, k),
            sensors_h: DMatrix::zeros(k, k),
            frames_g: vec![0.0; rows],
            sensors_g: DVector::zeros(k),
        };
        let newton = self.newton.load(Ordering::Relaxed);
        for t in terms {
            let (gamma, vars) = self.jacobians(t, frames, sensors);
            for &(u, ju) in vars.iter().flatten() {
                let g = 0.5 * ju.transpose() * gamma;
                let (gs, base) = match u {
                    Var::Frame(p) => (&mut s.frames_g[..], 3 * p),
                    Var::Sensor(c) => (s.sensors_g.as_mut_slice(), c),
                };
                (0..3).for_each(|i| gs[base + i] += g[i]);
                if newton {
                    continue;
                }
                let hu = 2.0 * ju.transpose() * t.h;
                for &(v, jv) in vars.iter().flatten() {
                    self.add_block(&mut s, (u, v), t.slot, &(hu * jv));
                }
            }
            if newton {
                self.hessian(t, (frames, sensors), |uv, m| {
                    self.add_block(&mut s, uv, t.slot, m)
                });
            }
        }
        s
    }

    /// Half the Hessian of one term `4 (tr M - tr(M E))` in its variables, each ordered pair
    /// given to `add` (`[H19]` "Newton steps"). `E = P_0 e^{[d_t]} F_g e^{[phi_g]}
    /// e^{-[phi_f]} F_f^T e^{-[d_s]} S_s^T` (`P_0 = R^T S_t`) is a product of rotations and
    /// four exponentials at positions `k`, of signs `sigma_k`; with `L_k` and `R_k` the products
    /// left and right of position `k` and `A_k = R_k M L_k`, the second derivatives of
    /// `tr(M E)` are `sym(A_k) - tr(A_k) I` within a position and `sigma_k sigma_l (A_k B -
    /// tr(A_k) B)` between positions `k < l`, `B` the rotation between them (from `tr(N [u]x
    /// [w]x) = u^T N w - (u . w) tr N` and `B [w]x = [B w]x B`).
    fn hessian(
        &self,
        t: &Term,
        (frames, sensors): (&[Rotation], &[Rotation]),
        mut add: impl FnMut((Var, Var), &Matrix3<f64>),
    ) {
        let ((f, g), (sa, sb)) = (t.frames, t.sensors);
        let (ms, mt) = (sensors[sa].matrix(), sensors[sb].matrix());
        let (ff, fg) = (frames[f].matrix().transpose(), frames[g].matrix());
        let (p0, st) = (t.r.transpose() * mt, ms.transpose());
        let left = [p0, p0 * fg, p0 * fg, p0 * fg * ff];
        let right = [fg * ff * st, ff * st, ff * st, st];
        let across = f != g;
        let frame = |h: usize| (across && h >= 1).then_some(Var::Frame(h - 1));
        let sensor = |s: usize| self.column[s].map(Var::Sensor);
        let vars = [sensor(sb), frame(g), frame(f), sensor(sa)];
        let sign = [1.0, 1.0, -1.0, -1.0];
        let between = |k: usize, l: usize| match (k, l) {
            (0, 1) | (0, 2) => *fg,
            (0, _) => fg * ff,
            (1, 2) => Matrix3::identity(),
            _ => ff,
        };
        for k in 0..4 {
            let Some(u) = vars[k] else { continue };
            let a = right[k] * t.m * left[k];
            let trace = a.trace();
            let within = 0.5 * (a + a.transpose()) - trace * Matrix3::identity();
            add((u, u), &(-2.0 * within));
            for l in k + 1..4 {
                let Some(v) = vars[l] else { continue };
                let b = between(k, l);
                let block = -2.0 * sign[k] * sign[l] * (a * b - trace * b);
                add((u, v), &block);
                add((v, u), &block.transpose());
            }
        }
    }

    /// Adds the block `m` at `(u, v)`: the frames' pattern takes each pair once (its lower
    /// triangle), the coupling its frame rows, the sensors' block every ordered pair.
    fn add_block(&self, s: &mut System, (u, v): (Var, Var), slot: usize, m: &Matrix3<f64>) {
        match (u, v) {
            (Var::Frame(p), Var::Frame(q)) if p == q => {
                self.shape.pattern.add(&mut s.frames_h, p, p, 0, m)
            }
            (Var::Frame(p), Var::Frame(q)) if p > q => {
                self.shape.pattern.add(&mut s.frames_h, p, q, slot, m)
            }
            (Var::Frame(_), Var::Frame(_)) | (Var::Sensor(_), Var::Frame(_)) => {}
            (Var::Frame(p), Var::Sensor(c)) => {
                for (i, l) in (0..3).flat_map(|i| (0..3).map(move |l| (i, l))) {
                    s.coupling[(3 * p + i, c + l)] += m[(i, l)];
                }
            }
            (Var::Sensor(a), Var::Sensor(c)) => {
                for (i, l) in (0..3).flat_map(|i| (0..3).map(move |l| (i, l))) {
                    s.sensors_h[(a + i, c + l)] += m[(i, l)];
                }
            }
        }
    }

    /// `gamma` and the variables' `omega` Jacobians of one term (frames only across frames,
    /// sensors only when unknown).
    fn jacobians(
        &self,
        t: &Term,
        frames: &[Rotation],
        sensors: &[Rotation],
    ) -> (Vector3<f64>, Jacobians) {
        let ((f, g), (sa, sb)) = (t.frames, t.sensors);
        let (ms, mt) = (sensors[sa].matrix(), sensors[sb].matrix());
        let xa = ms * frames[f].matrix();
        let xb = mt * frames[g].matrix();
        let e = t.r.transpose() * xb * xa.transpose();
        let c = e * t.m;
        let gamma = -4.0
            * Vector3::new(
                c[(1, 2)] - c[(2, 1)],
                c[(2, 0)] - c[(0, 2)],
                c[(0, 1)] - c[(1, 0)],
            );
        let across = f != g;
        let frame =
            |h: usize, j: Matrix3<f64>| (across && h >= 1).then_some((Var::Frame(h - 1), j));
        let sensor = |s: usize, j: Matrix3<f64>| self.column[s].map(|c| (Var::Sensor(c), j));
        let vars = [
            sensor(sb, t.r.transpose() * mt),
            frame(g, t.r.transpose() * xb),
            sensor(sa, -(e * ms)),
            frame(f, -(e * xa)),
        ];
        (gamma, vars)
    }
}

#[cfg(test)]
mod tests {
    use super::{Joint, System};
    use crate::rig::{RigProblem, RigScene};
    use crate::so3::{Rotation, exp};
    use nalgebra::{DMatrix, DVector, Vector3};
    use std::sync::atomic::Ordering;

    /// A rig of 40 frames and 3 sensors, 0.05 rad of noise, with scalar weights or information.
    fn medium(anisotropy: f64) -> (RigProblem, Vec<Rotation>, Vec<Rotation>) {
        let (p, truth) = RigScene {
            frames: 40,
            sensors: 3,
            noise_sigma: 0.05,
            anisotropy,
            seed: 11,
            ..Default::default()
        }
        .generate();
        (p, truth.frames, truth.sensors)
    }

    /// A reweighted rig's steps from the first rig's shape are the steps of its own: the same
    /// system (its weights, not the first rig's) and the same step taken; another rig (an
    /// edge's end changed) gets none.
    #[test]
    fn reweighted_steps_are_the_reweighted_rig_s_own() {
        let (p, f, s) = medium(1.0);
        let first = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
        let edges: Vec<_> = (p.edges().iter().enumerate())
            .map(|(k, e)| crate::multiple::Edge {
                weight: e.weight / (1.0 + (k % 7) as f64),
                ..e.clone()
            })
            .collect();
        let q = p.with_edges(edges.clone()).unwrap();
        let shared = first.reweighted(&q).unwrap().expect("the same rig");
        let own = Joint::new(&q, &s, usize::MAX).unwrap().unwrap();
        let (a, b) = (shared.system(&f, &s), own.system(&f, &s));
        assert_eq!((&a.frames_h, &a.frames_g), (&b.frames_h, &b.frames_g));
        assert_eq!((&a.sensors_h, &a.sensors_g), (&b.sensors_h, &b.sensors_g));
        assert_ne!(first.system(&f, &s).frames_g, a.frames_g);
        let steps = |j: &Joint<'_>| j.run((f.clone(), s.clone()), (1, false), None);
        let (x, y) = (steps(&shared), steps(&own));
        assert_eq!((x.0, x.1, x.2), (y.0, y.1, y.2));
        let mut moved = edges;
        moved[0].j = (moved[0].j + 1) % p.images().len();
        let other = p.with_edges(moved).unwrap();
        assert!(first.reweighted(&other).unwrap().is_none());
    }

    /// A rig of more than `PARALLEL_EDGES` edges: its system assembled in two halves and
    /// summed (on two threads where there are two) is the one assembled in one pass, to
    /// rounding, in Gauss-Newton's and Newton's Hessians.
    #[test]
    fn the_system_in_two_halves_is_the_whole_system() {
        let (p, truth) = RigScene {
            frames: 2500,
            sensors: 3,
            noise_sigma: 0.05,
            seed: 5,
            ..Default::default()
        }
        .generate();
        assert!(p.edges().len() >= super::PARALLEL_EDGES);
        let (f, s) = (truth.frames, truth.sensors);
        let joint = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
        for newton in [false, true] {
            joint.newton.store(newton, Ordering::Relaxed);
            let (halves, whole) = (joint.system(&f, &s), joint.system_of(&joint.terms, &f, &s));
            let close = |a: &[f64], b: &[f64]| {
                let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
                assert!(scale > 0.0 && a.len() == b.len());
                let gap = a
                    .iter()
                    .zip(b)
                    .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
                assert!(gap <= 1e-12 * scale, "{newton}: {gap} of {scale}");
            };
            close(&halves.frames_h, &whole.frames_h);
            close(&halves.frames_g, &whole.frames_g);
            close(halves.sensors_h.as_slice(), whole.sensors_h.as_slice());
            close(halves.sensors_g.as_slice(), whole.sensors_g.as_slice());
            let column = |m: &faer::Mat<f64>| -> Vec<f64> {
                (0..m.ncols())
                    .flat_map(|j| m.col(j).iter().copied().collect::<Vec<_>>())
                    .collect()
            };
            close(&column(&halves.coupling), &column(&whole.coupling));
        }
    }

    /// One damped step by conjugate gradients (to a relative residual of `1e-13`, with the
    /// frames' Laplacian preconditioner and with block-Jacobi) is the step of the frames'
    /// factor and the sensors' Schur complement, to `1e-8` of its size; their predicted
    /// decreases agree as closely.
    #[test]
    fn conjugate_gradients_take_the_factor_s_step() {
        for anisotropy in [1.0, 9.0] {
            let (p, f, s) = medium(anisotropy);
            let mut joint = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
            joint.cg_budget = super::JOINT_CG_ITERATIONS;
            let system = joint.system(&f, &s);
            let damped = joint.damped(&system, 1e-4);
            let (dx, dy, decrease) = joint.direct_step(&system, &damped).unwrap();
            let size = (dx.iter().map(|v| v * v).sum::<f64>() + dy.norm_squared()).sqrt();
            for laplacian in [true, false] {
                if !laplacian {
                    joint.laplacian = None;
                }
                let ((cx, cy, cd), converged) = joint
                    .iterative_step(&system, &damped, (1e-13, None))
                    .unwrap();
                assert!(converged);
                let gap: f64 = dx
                    .iter()
                    .zip(&cx)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    + (&dy - &cy).norm_squared();
                assert!(
                    gap.sqrt() <= 1e-8 * size,
                    "{anisotropy} {laplacian}: {gap} {size}"
                );
                assert!((decrease - cd).abs() <= 1e-8 * decrease.abs());
            }
        }
    }

    /// Steps by conjugate gradients alone (no factor to fall back to, block-Jacobi) end where
    /// the steps by the frames' factor end: `J` within `1e-10` of it, the sensors within
    /// `1e-7` rad, both converged.
    #[test]
    fn conjugate_gradient_steps_reach_the_factor_s_minimum() {
        use crate::termination::Termination;
        for anisotropy in [1.0, 9.0] {
            let (p, f, s) = medium(anisotropy);
            let run = |joint: &Joint<'_>| joint.run((f.clone(), s.clone()), (100, false), None);
            let direct = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
            direct.factorise.store(true, Ordering::Relaxed);
            let (ff, fs, _, stop) = run(&direct);
            assert!(matches!(stop, Termination::Converged { .. }), "{stop:?}");
            let mut iterative = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
            let shape = std::sync::Arc::get_mut(&mut iterative.shape).expect("one joint");
            (shape.direct, iterative.laplacian) = (None, None);
            iterative.cg_budget = super::JOINT_CG_ITERATIONS;
            let (cf, cs, _, stop) = run(&iterative);
            assert!(matches!(stop, Termination::Converged { .. }), "{stop:?}");
            let (a, b) = (p.cost(&ff, &fs), p.cost(&cf, &cs));
            assert!((a - b).abs() <= 1e-10 * a, "{anisotropy}: {a} {b}");
            for (x, y) in fs.iter().zip(&cs) {
                assert!(crate::so3::angle_between(x, y) <= 1e-7);
            }
        }
    }

    /// A rig of 6 frames and 3 sensors (sensor 0 held), with edges within frames and between
    /// frames of one sensor and of two, scalar weights or information matrices.
    fn small(noise_sigma: f64, anisotropy: f64) -> (RigProblem, Vec<Rotation>, Vec<Rotation>) {
        let (p, truth) = RigScene {
            frames: 6,
            sensors: 3,
            noise_sigma,
            anisotropy,
            cross_fraction: 1.0,
            seed: 3,
            ..Default::default()
        }
        .generate();
        assert!(
            p.edges()
                .iter()
                .any(|e| p.images()[e.i].frame == p.images()[e.j].frame)
        );
        (p, truth.frames, truth.sensors)
    }

    /// `J` with each variable `v` of `moves` (frames `1..n` then the unknown sensors, 3 each)
    /// turned by its `t`.
    fn turned(p: &RigProblem, (f, s): (&[Rotation], &[Rotation]), moves: &[(usize, f64)]) -> f64 {
        let (mut f, mut s) = (f.to_vec(), s.to_vec());
        for &(v, t) in moves {
            let mut d = Vector3::zeros();
            d[v % 3] = t;
            let frames = 3 * (f.len() - 1);
            match v < frames {
                true => f[v / 3 + 1] *= exp(&d),
                false => s[p.estimated_sensors()[(v - frames) / 3]] *= exp(&d),
            }
        }
        p.cost(&f, &s)
    }

    /// `J`'s second central differences (step `1e-4`) in the `dim` variables of [`turned`].
    fn second_differences(
        p: &RigProblem,
        x: (&[Rotation], &[Rotation]),
        dim: usize,
    ) -> DMatrix<f64> {
        let t = 1e-4;
        let at = |v: usize, a: f64, w: usize, b: f64| turned(p, x, &[(v, a), (w, b)]);
        DMatrix::from_fn(dim, dim, |v, w| {
            (at(v, t, w, t) - at(v, t, w, -t) - at(v, -t, w, t) + at(v, -t, w, -t)) / (4.0 * t * t)
        })
    }

    /// The system's gradient and Hessian as dense arrays, in the variables of [`turned`].
    fn dense(joint: &Joint<'_>, s: &System) -> (DVector<f64>, DMatrix<f64>) {
        let (rows, k) = (s.frames_g.len(), s.sensors_g.len());
        let g = DVector::from_iterator(
            rows + k,
            s.frames_g.iter().chain(s.sensors_g.iter()).copied(),
        );
        let lower = crate::linalg::cholesky::to_dense(joint.shape.pattern.matrix(&s.frames_h));
        let mut h = DMatrix::zeros(rows + k, rows + k);
        for (r, c) in (0..rows).flat_map(|r| (0..=r).map(move |c| (r, c))) {
            h[(r, c)] = lower[(r, c)];
            h[(c, r)] = lower[(r, c)];
        }
        for (r, c) in (0..rows).flat_map(|r| (0..k).map(move |c| (r, c))) {
            h[(r, rows + c)] = s.coupling[(r, c)];
            h[(rows + c, r)] = s.coupling[(r, c)];
        }
        h.view_mut((rows, rows), (k, k)).copy_from(&s.sensors_h);
        (g, h)
    }

    /// The system's gradient is half of `J`'s central differences under right perturbations, on
    /// a noisy rig with scalar weights and with information matrices (every edge kind).
    #[test]
    fn the_gradient_is_half_the_cost_s_derivative() {
        for anisotropy in [1.0, 9.0] {
            let (p, f, s) = small(0.1, anisotropy);
            let joint = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
            let (g, _) = dense(&joint, &joint.system(&f, &s));
            let t = 1e-6;
            let fd = DVector::from_fn(g.len(), |v, _| {
                (turned(&p, (&f, &s), &[(v, t)]) - turned(&p, (&f, &s), &[(v, -t)])) / (2.0 * t)
            });
            assert!(
                (2.0 * &g - &fd).norm() <= 1e-6 * fd.norm(),
                "{anisotropy}: {g} {fd}"
            );
        }
    }

    /// At a noise-free rig (`J = 0`, where Gauss-Newton's Hessian is the Hessian) the system's
    /// Hessian is half of `J`'s second central differences, couplings included.
    #[test]
    fn the_hessian_is_half_the_cost_s_at_a_noise_free_rig() {
        for anisotropy in [1.0, 9.0] {
            let (p, f, s) = small(0.0, anisotropy);
            let joint = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
            let (_, h) = dense(&joint, &joint.system(&f, &s));
            let fd = second_differences(&p, (&f, &s), h.nrows());
            assert!((2.0 * &h - &fd).amax() <= 1e-5 * fd.amax(), "{anisotropy}");
            // the sensors are coupled to the frames
            assert!(h.view((0, h.nrows() - 6), (h.nrows() - 6, 6)).amax() > 0.0);
        }
    }

    /// At a noisy rig (0.3 rad: where Gauss-Newton's Hessian is off by the residuals' terms,
    /// and this test fails with it: checked) Newton's Hessian is half of `J`'s second central
    /// differences (their symmetric part), every edge kind, scalar weights and information
    /// matrices, a sensor seen at both ends of an edge too.
    #[test]
    fn the_hessian_is_half_the_cost_s_at_a_noisy_rig() {
        for anisotropy in [1.0, 9.0] {
            let (p, f, s) = small(0.3, anisotropy);
            let joint = Joint::new(&p, &s, usize::MAX).unwrap().unwrap();
            joint.newton.store(true, Ordering::Relaxed);
            let (_, h) = dense(&joint, &joint.system(&f, &s));
            let fd = second_differences(&p, (&f, &s), h.nrows());
            // two moves of one rotation compose (`e^{a G_a} e^{b G_b}`): away from a critical
            // point their mixed differences carry the antisymmetric bracket term, which the
            // exponential's symmetric second derivative does not
            let fd = 0.5 * (&fd + fd.transpose());
            let error = (2.0 * &h - &fd).amax();
            assert!(
                error <= 1e-5 * fd.amax(),
                "{anisotropy}: {error} of {}",
                fd.amax()
            );
        }
    }
}
