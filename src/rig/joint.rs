//! The rig's joint Gauss-Newton (`paper-notes/conjugate.md` `[H19]` "Joint steps"): the frames
//! and the unknown sensors move together, each step a Levenberg-Marquardt step of `J(F, S)` in
//! both. The frames' block is the sparse `3(n-1) x 3(n-1)` system of the frames' view graph
//! (frame 0 held, the gauge), factorised by a sparse Cholesky at each step; the `3K` sensors are
//! eliminated by their Schur complement (`3K + 1` right-hand sides of the frames' factor and a
//! dense `3K x 3K` system), so no `3n x 3n` dense matrix is formed. Where the alternation of
//! [`super::solve`] converges linearly (a ratio of about 0.7 per pass: rigs captured along a
//! path, many sensors), these steps converge as Gauss-Newton does on small residuals. Where the
//! frames' factor fills (random view graphs), the alternation runs instead.
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
use crate::linalg::block_pattern::BlockPattern;
use crate::linalg::linear_solver::LinearSolver;
use crate::multiple::chordal::grounded_pattern;
use crate::so3::{Rotation, exp, nearest_rotation};
use crate::termination::Termination;
use faer::Mat;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// The relative predicted decrease of `J` below which the steps stop: about the rounding of a
/// sum of `10^5` terms.
pub const JOINT_TOLERANCE: f64 = 1e-14;

/// The largest factor of the frames' block (stored values: 400 MB) factorised at each step.
pub const JOINT_DIRECT_VALUES: usize = 50_000_000;

/// The most multiply-adds of that factorisation (about 0.5-0.8 s on the 2-core reference
/// machine). Beyond either limit the frames' factor fills (random view graphs: 2.8e8 values at
/// 10^4 frames) and the alternation, whose frame steps run conjugate gradients, is faster.
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

/// One edge: its images' frames and sensors, `R`, `H` and `M`, and the frames' slot.
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
    pattern: BlockPattern,
    solver: LinearSolver,
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

impl<'a> Joint<'a> {
    /// The steps of `problem` (the frames' block's pattern from its frames' view graph at
    /// `sensors`), `None` with gravity priors, no sensor to estimate, a single frame, or a
    /// frames' factor over `max_values` (a caller's memory budget), [`JOINT_DIRECT_VALUES`] or
    /// [`JOINT_MULTIPLY_ADDS`].
    pub fn new(
        problem: &'a RigProblem,
        sensors: &[Rotation],
        max_values: usize,
    ) -> Result<Option<Self>> {
        let unknown = problem.estimated_sensors();
        if problem.gravity().is_some() || unknown.is_empty() || problem.num_frames() < 2 {
            return Ok(None);
        }
        let (graph, _) = problem.frame_graph_for_solve(sensors)?;
        let pattern = grounded_pattern(&graph, 3);
        // `3K + 1` right-hand sides per step: a factor pays for itself where it fits
        let Some(symbolic) = pattern.symbolic_llt_within(max_values.min(JOINT_DIRECT_VALUES))?
        else {
            return Ok(None);
        };
        if symbolic.multiply_adds() > JOINT_MULTIPLY_ADDS {
            return Ok(None);
        }
        let solver = LinearSolver::Direct(symbolic);
        let mut column = vec![None; problem.held().len()];
        for (k, &s) in unknown.iter().enumerate() {
            column[s] = Some(3 * k);
        }
        let info = problem.information();
        let terms = (problem.edges().iter().enumerate())
            .map(|(k, e)| {
                let (a, b) = (problem.images()[e.i], problem.images()[e.j]);
                let (h, m) = match info {
                    Some(info) => (*info[k].matrix(), info[k].chordal_matrix()),
                    None => (
                        e.weight * Matrix3::identity(),
                        0.5 * e.weight * Matrix3::identity(),
                    ),
                };
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
            .collect();
        Ok(Some(Joint {
            problem,
            terms,
            column,
            unknown,
            pattern,
            solver,
        }))
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
        let mut steps = 0;
        let stop = loop {
            let measure = (relative, JOINT_TOLERANCE);
            if let Some(limit) = limit_reached(steps, max_steps, deadline, measure) {
                break limit;
            }
            let taken = self.accepted((&frames, &sensors), (cost, polish), &system, &mut damping);
            let taken = match taken {
                Ok(taken) => taken,
                Err(last) => break self.converged(last, damping),
            };
            (frames, sensors, relative) = (taken.frames, taken.sensors, taken.relative);
            (cost, system) = (taken.cost, taken.system);
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
        system: &System,
        damping: &mut f64,
    ) -> std::result::Result<Taken, f64> {
        let mut last = f64::INFINITY;
        while *damping <= 1e12 {
            let Some((dx, dy, decrease)) = self.step(system, *damping) else {
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

    /// The damped step `(dx, dy)` and its predicted decrease `-g^T d + damping d^T D d` (of
    /// `J`'s model `J + 2 g^T d + d^T h d`), or `None` when a damped block is not positive
    /// definite. The sensors by the Schur complement of the frames' block.
    fn step(&self, s: &System, damping: f64) -> Option<(Vec<f64>, DVector<f64>, f64)> {
        let mut a = s.frames_h.clone();
        let diagonal = self.pattern.diagonal(&a);
        let floor = 1e-12 * diagonal.iter().fold(f64::MIN_POSITIVE, |m, &d| m.max(d));
        let pointers = self.pattern.col_ptr();
        for (c, d) in diagonal.iter().enumerate() {
            a[pointers[c]] += damping * d.max(floor);
        }
        let factor = self.solver.factor(&self.pattern, &a)?;
        let (rows, k) = (s.frames_g.len(), s.sensors_g.len());
        let mut b = Mat::from_fn(rows, k + 1, |r, c| match c < k {
            true => s.coupling[(r, c)],
            false => s.frames_g[r],
        });
        // a direct factor: no tolerance, no iterations
        factor.solve(&mut b, 0.0, 0)?;
        // Schur complement: (C - B^T Y) y = -g_S + B^T z, Y = A^-1 B, z = A^-1 g_F
        let mut c = s.sensors_h.clone();
        let mut rhs = -&s.sensors_g;
        for u in 0..k {
            c[(u, u)] += damping * s.sensors_h[(u, u)].max(floor);
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
        let mut decrease = -s.sensors_g.dot(&dy);
        decrease -= s.frames_g.iter().zip(&dx).map(|(g, d)| g * d).sum::<f64>();
        decrease += damping
            * (0..k)
                .map(|u| s.sensors_h[(u, u)].max(floor) * dy[u] * dy[u])
                .sum::<f64>();
        decrease += damping
            * (diagonal.iter().zip(&dx))
                .map(|(d, x)| d.max(floor) * x * x)
                .sum::<f64>();
        Some((dx, dy, decrease))
    }

    /// The half gradient and half Gauss-Newton Hessian at `(frames, sensors)`.
    fn system(&self, frames: &[Rotation], sensors: &[Rotation]) -> System {
        let rows = 3 * (frames.len() - 1);
        let k = 3 * self.unknown.len();
        let mut s = System {
            frames_h: vec![0.0; self.pattern.nnz()],
            coupling: Mat::zeros(rows, k),
            sensors_h: DMatrix::zeros(k, k),
            frames_g: vec![0.0; rows],
            sensors_g: DVector::zeros(k),
        };
        for t in &self.terms {
            let (gamma, vars) = self.jacobians(t, frames, sensors);
            for &(u, ju) in vars.iter().flatten() {
                let g = 0.5 * ju.transpose() * gamma;
                let (gs, base) = match u {
                    Var::Frame(p) => (&mut s.frames_g[..], 3 * p),
                    Var::Sensor(c) => (s.sensors_g.as_mut_slice(), c),
                };
                (0..3).for_each(|i| gs[base + i] += g[i]);
                let hu = 2.0 * ju.transpose() * t.h;
                for &(v, jv) in vars.iter().flatten() {
                    self.add_block(&mut s, (u, v), t.slot, &(hu * jv));
                }
            }
        }
        s
    }

    /// Adds the block `m` at `(u, v)`: the frames' pattern takes each pair once (its lower
    /// triangle), the coupling its frame rows, the sensors' block every ordered pair.
    fn add_block(&self, s: &mut System, (u, v): (Var, Var), slot: usize, m: &Matrix3<f64>) {
        match (u, v) {
            (Var::Frame(p), Var::Frame(q)) if p == q => {
                self.pattern.add(&mut s.frames_h, p, p, 0, m)
            }
            (Var::Frame(p), Var::Frame(q)) if p > q => {
                self.pattern.add(&mut s.frames_h, p, q, slot, m)
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

    /// The system's gradient and Hessian as dense arrays, in the variables of [`turned`].
    fn dense(joint: &Joint<'_>, s: &System) -> (DVector<f64>, DMatrix<f64>) {
        let (rows, k) = (s.frames_g.len(), s.sensors_g.len());
        let g = DVector::from_iterator(
            rows + k,
            s.frames_g.iter().chain(s.sensors_g.iter()).copied(),
        );
        let lower = crate::linalg::cholesky::to_dense(joint.pattern.matrix(&s.frames_h));
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
            let t = 1e-4;
            let at = |v: usize, a: f64, w: usize, b: f64| turned(&p, (&f, &s), &[(v, a), (w, b)]);
            let fd = DMatrix::from_fn(h.nrows(), h.ncols(), |v, w| {
                (at(v, t, w, t) - at(v, t, w, -t) - at(v, -t, w, t) + at(v, -t, w, -t))
                    / (4.0 * t * t)
            });
            assert!((2.0 * &h - &fd).amax() <= 1e-5 * fd.amax(), "{anisotropy}");
            // the sensors are coupled to the frames
            assert!(h.view((0, h.nrows() - 6), (h.nrows() - 6, 6)).amax() > 0.0);
        }
    }
}
