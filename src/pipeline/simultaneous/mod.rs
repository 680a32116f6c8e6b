//! The simultaneous problem (issue 5 item 6, `paper-notes/conjugate.md` `[H12]`): nodes
//! `i = 0..n` with unknown absolute rotations `R_i` and the unknown `S`, measured only through
//! relative rotations on two view graphs: right edges `R_ij` (`R_ij R_i = R_j`) and left edges
//! `L_ij ~ S R_ij S^T` (so `L_ij S R_i = S R_j`). Joint chordal cost
//! `J(R, S) = sum_right w ||R_j - R_ij R_i||_F^2 + sum_left w ||S R_j - L_ij S R_i||_F^2`,
//! minimised by dense Gauss-Newton over `(R_1..R_{n-1}, S)` with the gauge `R_0 = I`.
//! The baseline [`average_then_conjugate`] averages each graph separately (gauge `R_0 = L_0 =
//! I`, which is consistent because `L_0 = S R_0 S^T = I`) and then solves the conjugate problem
//! on the pairs `(L_i, R_i)`. The dense Gauss-Newton is for small rigs (`3n x 3n` normal
//! equations); larger ones are solved by the sparse alternation of [`alternating`].

pub mod alternating;
mod held;

pub use held::average_with_sensor_held;

use super::{AverageSettings, Averaged, PipelineProblem, PipelineSolution, average};
use crate::certify::simultaneous::certify_simultaneous;
use crate::certify::{Certification, CertifyMode, CertifySettings};
use crate::conjugate::{ConjugatePair, ConjugateProblem, ConjugateSettings, solve_conjugate};
use crate::deadline::{Deadline, limit_reached, remaining};
use crate::error::{Error, Result};
use crate::multiple::{Edge, MultipleProblem, fix_gauge};
use crate::so3::{Rotation, exp, hat, nearest_rotation};
use crate::termination::{SolverReport, Termination};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Two view graphs over the same `n` nodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimultaneousProblem {
    /// Number of nodes.
    pub num_nodes: usize,
    /// Right graph: `R_ij` with `R_ij R_i = R_j`.
    pub right: Vec<Edge>,
    /// Left graph: `L_ij ~ S R_ij S^T`.
    pub left: Vec<Edge>,
}

/// A joint estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimultaneousSolution {
    /// `R_0..R_{n-1}` with `R_0 = I`.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub rotations: Vec<Rotation>,
    /// `S`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub s: Rotation,
    /// The joint cost `J`.
    pub cost: f64,
    /// Solver report.
    pub report: SolverReport,
}

impl SimultaneousProblem {
    fn validate(&self) -> Result<()> {
        if self.num_nodes < 2 {
            return Err(Error::Empty {
                what: "the simultaneous problem (fewer than 2 nodes)".into(),
            });
        }
        for (k, e) in self.right.iter().chain(&self.left).enumerate() {
            let idx = e.i.max(e.j);
            if idx >= self.num_nodes {
                return Err(Error::IndexOutOfRange {
                    edge: k,
                    index: idx,
                    num_rotations: self.num_nodes,
                });
            }
            if e.i == e.j {
                return Err(Error::SelfLoop { edge: k, node: e.i });
            }
            if !(e.weight.is_finite() && e.weight > 0.0) {
                return Err(Error::InvalidWeight {
                    item: format!("edge {k}"),
                    weight: e.weight,
                });
            }
        }
        Ok(())
    }

    /// The joint cost `J(R, S)`.
    pub fn cost(&self, rs: &[Rotation], s: &Rotation) -> f64 {
        let (sm, mut c) = (s.matrix(), 0.0);
        for e in &self.right {
            c += right_term(e, rs);
        }
        for e in &self.left {
            c += e.weight
                * (sm * rs[e.j].matrix() - e.rotation.matrix() * sm * rs[e.i].matrix())
                    .norm_squared();
        }
        c
    }
}

/// The term `w ||R_j - R_ij R_i||_F^2` of a right edge.
fn right_term(e: &Edge, rs: &[Rotation]) -> f64 {
    e.weight * (rs[e.j].matrix() - e.rotation.matrix() * rs[e.i].matrix()).norm_squared()
}

/// Which blocks a Gauss-Newton run optimises.
#[derive(Clone, Copy)]
enum Terms {
    Right,
    Joint,
}

/// Spanning-tree (BFS) initialisation of absolutes from one graph, `X_0 = I`; each product
/// replaced by its nearest rotation (the measurements are rotations only to the validation
/// tolerance, and the start must be on SO(3), contract section 1).
fn spanning_tree(n: usize, edges: &[Edge]) -> Result<Vec<Rotation>> {
    let mut adj = vec![Vec::new(); n];
    for e in edges {
        adj[e.i].push((e.j, e.rotation));
        adj[e.j].push((e.i, e.rotation.inverse()));
    }
    let mut out: Vec<Option<Rotation>> = vec![None; n];
    out[0] = Some(Rotation::identity());
    let mut queue = std::collections::VecDeque::from([0usize]);
    while let Some(i) = queue.pop_front() {
        let ri = out[i].unwrap_or_else(Rotation::identity);
        for &(j, rij) in &adj[i] {
            if out[j].is_none() {
                out[j] = Some(nearest_rotation(&(rij * ri)));
                queue.push_back(j);
            }
        }
    }
    let sizes = out.iter().filter(|x| x.is_some()).count();
    if sizes < n {
        return Err(Error::Disconnected {
            component_sizes: vec![sizes, n - sizes],
        });
    }
    Ok(out
        .into_iter()
        .map(|x| x.unwrap_or_else(Rotation::identity))
        .collect())
}

/// Dense Gauss-Newton on the chosen terms; variables `R_1..R_{n-1}` (and `S` for `Joint`).
/// Returns the last iterate, its cost, the iterations and why it stopped.
fn gauss_newton(
    p: &SimultaneousProblem,
    terms: Terms,
    mut rs: Vec<Rotation>,
    mut s: Rotation,
    (max_iter, deadline): (usize, Option<Deadline>),
) -> (Vec<Rotation>, Rotation, f64, usize, Termination) {
    let total_w: f64 = p.right.iter().chain(&p.left).map(|e| e.weight).sum();
    let gtol = 1e-12 * total_w;
    let mut cost = terms_cost(p, terms, &rs, &s);
    let mut it = 0;
    let term = loop {
        let (mut h, b) = normal_equations(p, terms, &rs, &s);
        let gnorm = 2.0 * b.norm();
        if gnorm < gtol {
            break Termination::Converged {
                measure: "gradient norm".into(),
                value: gnorm,
                threshold: gtol,
            };
        }
        if let Some(limit) = limit_reached(it, max_iter, deadline, (gnorm, gtol)) {
            break limit;
        }
        it += 1;
        let damp = 1e-12 * h.trace().abs() + 1e-300;
        for k in 0..h.nrows() {
            h[(k, k)] += damp;
        }
        let delta = match h.cholesky() {
            Some(c) => -c.solve(&b),
            None => -b.clone(),
        };
        let slope = 2.0 * b.dot(&delta);
        match armijo(p, terms, (&rs, &s), cost, &delta, slope) {
            Some((r2, s2, c)) => {
                rs = r2;
                s = s2;
                cost = c;
            }
            None => {
                let res = 1e3 * f64::EPSILON * cost.abs();
                if -slope <= res {
                    break Termination::Converged {
                        measure: "predicted decrease (cost rounding level)".into(),
                        value: -slope,
                        threshold: res,
                    };
                }
                break Termination::Stalled {
                    value: gnorm,
                    threshold: gtol,
                };
            }
        }
    };
    (rs, s, cost, it, term)
}

/// The cost of the terms a Gauss-Newton run optimises: the right graph's, or `J(R, S)`.
fn terms_cost(p: &SimultaneousProblem, terms: Terms, rs: &[Rotation], s: &Rotation) -> f64 {
    match terms {
        Terms::Right => p.right.iter().map(|e| right_term(e, rs)).sum(),
        Terms::Joint => p.cost(rs, s),
    }
}

/// The Gauss-Newton normal equations `(J^T W J, J^T W r)` of the chosen terms at `(rs, s)`,
/// in the right-perturbation chart of `R_1..R_{n-1}` (and `S` for `Joint`, last 3 variables).
fn normal_equations(
    p: &SimultaneousProblem,
    terms: Terms,
    rs: &[Rotation],
    s: &Rotation,
) -> (DMatrix<f64>, DVector<f64>) {
    let n = p.num_nodes;
    let nv = 3 * (n - 1) + if matches!(terms, Terms::Joint) { 3 } else { 0 };
    let basis = [Vector3::x(), Vector3::y(), Vector3::z()];
    let mut h = DMatrix::<f64>::zeros(nv, nv);
    let mut b = DVector::<f64>::zeros(nv);
    // accumulate one 9-residual term with Jacobian blocks (var offset, 3 columns)
    let mut add = |res: Matrix3<f64>, blocks: &[(Option<usize>, [Matrix3<f64>; 3])], w: f64| {
        let cols: Vec<(usize, DVector<f64>)> = blocks
            .iter()
            .filter_map(|(off, m)| off.map(|o| (o, m)))
            .flat_map(|(o, m)| {
                (0..3).map(move |k| (o + k, DVector::from_column_slice(m[k].as_slice())))
            })
            .collect();
        let rv = DVector::from_column_slice(res.as_slice());
        for (a, ca) in &cols {
            b[*a] += w * ca.dot(&rv);
            for (c, cc) in &cols {
                h[(*a, *c)] += w * ca.dot(cc);
            }
        }
    };
    let off = |i: usize| if i == 0 { None } else { Some(3 * (i - 1)) };
    let s_off = Some(3 * (n - 1));
    let sm = *s.matrix();
    for e in &p.right {
        let (ri, rj, rij) = (rs[e.i].matrix(), rs[e.j].matrix(), e.rotation.matrix());
        let res = rj - rij * ri;
        let jj = basis.map(|v| rj * hat(&v));
        let ji = basis.map(|v| -(rij * ri * hat(&v)));
        add(res, &[(off(e.j), jj), (off(e.i), ji)], e.weight);
    }
    if matches!(terms, Terms::Joint) {
        for e in &p.left {
            let (ri, rj, lij) = (rs[e.i].matrix(), rs[e.j].matrix(), e.rotation.matrix());
            let res = sm * rj - lij * sm * ri;
            let jj = basis.map(|v| sm * rj * hat(&v));
            let ji = basis.map(|v| -(lij * sm * ri * hat(&v)));
            let js = basis.map(|v| sm * hat(&v) * rj - lij * sm * hat(&v) * ri);
            add(
                res,
                &[(off(e.j), jj), (off(e.i), ji), (s_off, js)],
                e.weight,
            );
        }
    }
    (h, b)
}

/// Backtracking along `R_i exp(t delta_i)` (and `S exp(t delta_S)`) from `t = 1`, halved at most
/// 40 times, until the Armijo condition `cost(t) <= cost + 1e-4 t slope` holds.
fn armijo(
    p: &SimultaneousProblem,
    terms: Terms,
    (rs, s): (&[Rotation], &Rotation),
    cost: f64,
    delta: &DVector<f64>,
    slope: f64,
) -> Option<(Vec<Rotation>, Rotation, f64)> {
    let block = |o: usize| Vector3::new(delta[o], delta[o + 1], delta[o + 2]);
    let mut t = 1.0;
    for _ in 0..40 {
        let mut rs2 = rs.to_vec();
        for (i, r) in rs2.iter_mut().enumerate().skip(1) {
            *r *= exp(&(block(3 * (i - 1)) * t));
        }
        let mut s2 = *s;
        if matches!(terms, Terms::Joint) {
            s2 *= exp(&(block(3 * (p.num_nodes - 1)) * t));
        }
        let c = terms_cost(p, terms, &rs2, &s2);
        if c <= cost + 1e-4 * t * slope {
            return Some((rs2, s2, c));
        }
        t *= 0.5;
    }
    None
}

/// The joint estimate `(rs, s)` as returned (contract section 1): every rotation replaced by its
/// nearest rotation (the last iterate carries the rounding of its steps), the gauge `R_0 = I`
/// exactly, the cost `J` at exactly that estimate.
fn on_so3(
    p: &SimultaneousProblem,
    rs: &[Rotation],
    s: &Rotation,
    report: SolverReport,
) -> SimultaneousSolution {
    let mut rotations: Vec<Rotation> = rs.iter().map(nearest_rotation).collect();
    fix_gauge(&mut rotations);
    if let Some(r0) = rotations.first_mut() {
        *r0 = Rotation::identity();
    }
    let s = nearest_rotation(s);
    SimultaneousSolution {
        cost: p.cost(&rotations, &s),
        rotations,
        s,
        report,
    }
}

/// Baseline: average each graph separately (spanning tree + chordal Gauss-Newton, gauge
/// `X_0 = I`), then solve the conjugate problem on `(L_i, R_i)`, `i >= 1`.
pub fn average_then_conjugate(p: &SimultaneousProblem) -> Result<SimultaneousSolution> {
    p.validate()?;
    let start = Instant::now();
    let n = p.num_nodes;
    let avg = |edges: &[Edge]| -> Result<Vec<Rotation>> {
        let init = spanning_tree(n, edges)?;
        let q = SimultaneousProblem {
            num_nodes: n,
            right: edges.to_vec(),
            left: vec![],
        };
        let rs = gauss_newton(&q, Terms::Right, init, Rotation::identity(), (100, None)).0;
        Ok(rs.iter().map(nearest_rotation).collect())
    };
    let rs = avg(&p.right)?;
    let ls = avg(&p.left)?;
    let pairs: Vec<_> = (1..n).map(|i| ConjugatePair::new(ls[i], rs[i])).collect();
    let conj = solve_conjugate(
        &ConjugateProblem::new(pairs)?,
        &ConjugateSettings::default(),
    )?;
    let report = SolverReport {
        name: "average-then-conjugate".into(),
        iterations: 0,
        termination: conj.report.termination,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(on_so3(p, &rs, &conj.estimate, report))
}

/// Joint Gauss-Newton on `J(R, S)` initialised by [`average_then_conjugate`] (so its cost is
/// never higher than the baseline's).
///
/// ```
/// use rotavg::pipeline::simultaneous::{solve_simultaneous, SimultaneousProblem};
/// use rotavg::multiple::Edge;
/// use rotavg::so3::{angle_between, exp};
/// use nalgebra::Vector3;
/// // Planted absolute rotations (R_0 = I) and S; exact edges on a 4-cycle plus a chord.
/// let rs: Vec<_> = [[0.0, 0.0, 0.0], [0.4, 0.0, 0.1], [0.0, 0.6, -0.2], [0.3, -0.3, 0.8]]
///     .iter()
///     .map(|v| exp(&Vector3::from(*v)))
///     .collect();
/// let s = exp(&Vector3::new(0.2, -0.5, 0.4));
/// let pairs = [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)];
/// let edge = |i: usize, j: usize, rotation| Edge { i, j, rotation, weight: 1.0 };
/// let right: Vec<_> = pairs.iter().map(|&(i, j)| edge(i, j, rs[j] * rs[i].inverse())).collect();
/// let left: Vec<_> = right.iter().map(|e| edge(e.i, e.j, s * e.rotation * s.inverse())).collect();
/// let p = SimultaneousProblem { num_nodes: 4, right, left };
/// let sol = solve_simultaneous(&p, 50)?;
/// assert!(sol.cost < 1e-18);
/// assert!(angle_between(&sol.s, &s) < 1e-8 && angle_between(&sol.rotations[3], &rs[3]) < 1e-8);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn solve_simultaneous(
    p: &SimultaneousProblem,
    max_iterations: usize,
) -> Result<SimultaneousSolution> {
    let start = Instant::now();
    let base = average_then_conjugate(p)?;
    let mut solution = solve_simultaneous_from(p, &base.rotations, &base.s, max_iterations)?;
    solution.report.seconds = start.elapsed().as_secs_f64();
    Ok(solution)
}

/// A seeded synthetic rig with a planted truth: the right graph of
/// [`crate::multiple::synthetic::SyntheticGraph`] (spanning tree plus random edges, Gaussian
/// noise, outliers) and a left graph on the same pairs measuring `S R_ij S^T` with its own
/// noise and outliers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SyntheticRig {
    /// The right graph's parameters (nodes, edges, noise, outliers, seed); the left graph uses
    /// the same pairs, noise level and outlier fraction, drawn independently.
    pub graph: crate::multiple::synthetic::SyntheticGraph,
}

impl SyntheticRig {
    /// `(problem, R_0..R_{n-1} with R_0 = I, S)`. Unit weights.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// use rotavg::pipeline::simultaneous::SyntheticRig;
    /// let graph = SyntheticGraph { num_rotations: 8, num_edges: 14, noise_sigma: 0.0, ..Default::default() };
    /// let (p, rs, s) = SyntheticRig { graph }.generate();
    /// assert!(p.cost(&rs, &s) < 1e-20);
    /// ```
    pub fn generate(&self) -> (SimultaneousProblem, Vec<Rotation>, Rotation) {
        use rand::{Rng, SeedableRng};
        let (right, truth) = self.graph.generate();
        let mut rng = rand::rngs::StdRng::seed_from_u64(self.graph.seed ^ 0x5eed_0f1e_f7a1);
        let s = crate::so3::random_rotation(&mut rng);
        let left = right
            .edges()
            .iter()
            .map(|e| {
                let exact = s * truth[e.j] * truth[e.i].inverse() * s.inverse();
                let rotation = if rng.random::<f64>() < self.graph.outlier_fraction {
                    crate::so3::random_rotation(&mut rng)
                } else {
                    crate::so3::perturb_gaussian(&exact, self.graph.noise_sigma, &mut rng)
                };
                Edge { rotation, ..*e }
            })
            .collect();
        let problem = SimultaneousProblem {
            num_nodes: right.num_rotations(),
            right: right.edges().to_vec(),
            left,
        };
        (problem, truth, s)
    }
}

/// Joint Gauss-Newton on `J(R, S)` from a given start (`rotations` re-gauged to `R_0 = I`):
/// the local solver behind [`solve_simultaneous`], for many-start searches and for polishing
/// another tool's estimate. Errors: an invalid problem, a start of the wrong length.
pub fn solve_simultaneous_from(
    p: &SimultaneousProblem,
    rotations: &[Rotation],
    s: &Rotation,
    max_iterations: usize,
) -> Result<SimultaneousSolution> {
    joint_from(p, rotations, s, max_iterations, None)
}

/// [`solve_simultaneous_from`] within `max_seconds` (checked before each iteration).
fn joint_from(
    p: &SimultaneousProblem,
    rotations: &[Rotation],
    s: &Rotation,
    max_iterations: usize,
    max_seconds: Option<f64>,
) -> Result<SimultaneousSolution> {
    p.validate()?;
    if rotations.len() != p.num_nodes {
        return Err(Error::InvalidSettings {
            name: "start".into(),
            reason: format!("{} rotations for {} nodes", rotations.len(), p.num_nodes),
        });
    }
    let start = Instant::now();
    // the start on SO(3) (a given estimate is a rotation only to the validation tolerance)
    let mut rs: Vec<Rotation> = rotations.iter().map(nearest_rotation).collect();
    fix_gauge(&mut rs);
    let limits = (
        max_iterations,
        Deadline::after(remaining(max_seconds, start)),
    );
    let (rs, s, _, it, term) = gauss_newton(p, Terms::Joint, rs, nearest_rotation(s), limits);
    let report = SolverReport {
        name: "simultaneous-gauss-newton".into(),
        iterations: it,
        termination: term,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(on_so3(p, &rs, &s, report))
}

/// The most nodes the dense dual certificate `[H15]` is used for; larger rigs are bounded by the
/// decoupled bound `[H16]`.
pub use crate::certify::simultaneous::dual::DENSE_MAX_NODES;

/// The most nodes the dense joint Gauss-Newton polishes the sparse alternation `[H17]` on (its
/// `3n x 3n` normal equations: 23 s at 1000 nodes, against 0.1 s of alternation).
pub const POLISH_MAX_NODES: usize = 500;

/// Settings of the joint local solver (dense Gauss-Newton, or the sparse alternation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SimultaneousSettings {
    /// Gauss-Newton iterations at most (default 100).
    pub max_iterations: usize,
    /// Largest memory the dense solve may need, bytes (default 4 GiB, as
    /// [`crate::certify::Budget`]): its dense normal equations are predicted by
    /// [`predict_simultaneous_solve_bytes`]; over it (or above [`POLISH_MAX_NODES`] nodes) the
    /// sparse alternation runs alone.
    pub max_memory_bytes: u64,
    /// Time limit of the solve, seconds (`None`, the default: no limit; the command line's
    /// `--max-seconds`). The alternation's passes, the view-graph solves and conjugate solves
    /// inside them, and the dense polish share one clock, each checked before its next
    /// iteration; when it is reached the solve ends with
    /// [`Termination::TimeLimit`] at its last iterate.
    pub max_seconds: Option<f64>,
}

impl Default for SimultaneousSettings {
    fn default() -> Self {
        SimultaneousSettings {
            max_iterations: 100,
            max_memory_bytes: crate::certify::Budget::default().max_memory_bytes,
            max_seconds: None,
        }
    }
}

/// The memory of the joint Gauss-Newton on `n` nodes, bytes: its dense `(3n) x (3n)` normal
/// matrix and the Cholesky factor made from it (the matrix is consumed), twice `8 (3n)^2`, plus
/// `O(n)` vectors. 10^4 nodes: about 14 GiB.
///
/// ```
/// use rotavg::pipeline::simultaneous::predict_simultaneous_solve_bytes;
/// assert!(predict_simultaneous_solve_bytes(200) < 1e7);
/// assert!(predict_simultaneous_solve_bytes(10_000) > 4.0 * (1u64 << 30) as f64);
/// ```
pub fn predict_simultaneous_solve_bytes(n: usize) -> f64 {
    let nv = 3.0 * n as f64;
    2.0 * 8.0 * nv * nv + 64.0 * 8.0 * n as f64
}

/// Settings of [`average_simultaneous`].
pub type AverageSimultaneousSettings = AverageSettings<SimultaneousSettings>;

impl SimultaneousProblem {
    /// The frames' view graph at a fixed `s` (`[H17]`, `[H18]`): the right edges, and each left
    /// edge as `S^T L_ij S`. For a rotation `S`, `||S R_j - L_ij S R_i||_F = ||R_j - S^T L_ij S
    /// R_i||_F`, so its chordal cost at `R` is the joint cost `J(R, S)`.
    pub fn frame_graph(&self, s: &Rotation) -> Result<MultipleProblem> {
        self.validate()?;
        let st = s.inverse();
        let left = self.left.iter().map(|e| Edge {
            rotation: st * e.rotation * s,
            ..e.clone()
        });
        MultipleProblem::new(
            self.num_nodes,
            self.right.iter().cloned().chain(left).collect(),
        )
    }

    /// The two view graphs as multiple-averaging problems on the same `n` nodes.
    pub fn graphs(&self) -> Result<(MultipleProblem, MultipleProblem)> {
        self.validate()?;
        Ok((
            MultipleProblem::new(self.num_nodes, self.right.clone())?,
            MultipleProblem::new(self.num_nodes, self.left.clone())?,
        ))
    }
}

impl PipelineSolution for SimultaneousSolution {
    fn certified_cost(&self) -> f64 {
        self.cost
    }
    fn report_mut(&mut self) -> &mut SolverReport {
        &mut self.report
    }
}

impl PipelineProblem for SimultaneousProblem {
    type Settings = SimultaneousSettings;
    type Solution = SimultaneousSolution;
    const NAME: &'static str = "simultaneous";
    const MODES: &'static [CertifyMode] = &[
        CertifyMode::Auto,
        CertifyMode::Dual,
        CertifyMode::Sdp,
        CertifyMode::None,
    ];
    fn validate(settings: &SimultaneousSettings) -> Result<()> {
        if settings.max_iterations == 0 {
            return Err(Error::InvalidSettings {
                name: "max_iterations".into(),
                reason: "must be at least 1".into(),
            });
        }
        if settings.max_memory_bytes == 0 {
            return Err(Error::InvalidSettings {
                name: "max_memory_bytes".into(),
                reason: "must be at least 1".into(),
            });
        }
        crate::deadline::validate_max_seconds(settings.max_seconds)
    }
    fn uncertifiable(&self, _mode: CertifyMode) -> Option<String> {
        None
    }
    /// The sparse alternation ([`alternating`], `[H17]`: 0.1 s at 300 nodes where the dense
    /// Gauss-Newton takes 4 s), polished by the dense joint Gauss-Newton (20 iterations at
    /// most) up to [`POLISH_MAX_NODES`] nodes when its normal equations fit
    /// `max_memory_bytes`: the better of the two is returned.
    fn solve(&self, settings: &SimultaneousSettings) -> Result<SimultaneousSolution> {
        let start = Instant::now();
        let sparse =
            alternating::solve_within(self, settings.max_iterations, settings.max_seconds)?;
        let predicted = predict_simultaneous_solve_bytes(self.num_nodes);
        let timed_out = matches!(sparse.report.termination, Termination::TimeLimit { .. });
        if self.num_nodes > POLISH_MAX_NODES
            || predicted > settings.max_memory_bytes as f64
            || timed_out
        {
            return Ok(sparse);
        }
        let left = remaining(settings.max_seconds, start);
        let mut polished = joint_from(self, &sparse.rotations, &sparse.s, 20, left)?;
        if polished.cost > sparse.cost {
            return Ok(sparse);
        }
        // the alternation's stopping test decided; the polish only refines
        polished.report.name = "simultaneous-alternating + gauss-newton polish".into();
        if !polished.report.termination.is_converged() {
            polished.report.termination = sparse.report.termination.clone();
        }
        Ok(sparse.adopt(polished))
    }
    /// The dual certificate at the estimate `[H15]`, then the SDP `[H14]`; a cheaper rounding of
    /// the SDP is polished by the joint Gauss-Newton and offered
    /// as the improvement when it beats the solution.
    fn certify(
        &self,
        solution: &SimultaneousSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<SimultaneousSolution>> {
        let start = Instant::now();
        let (right, left) = self.graphs()?;
        let c = certify_simultaneous(&right, &left, &solution.rotations, &solution.s, settings)?;
        let improvement = match c.improvement {
            Some(r) => {
                // within what the certificate left of its budget
                let left = remaining(settings.budget.max_seconds, start);
                let mut polished = joint_from(self, &r.rotations, &r.s, 100, left)?;
                polished.report.name = "sdp-rounding+simultaneous-gauss-newton".into();
                Some(polished)
            }
            None => None,
        };
        Ok(Certification {
            certificate: c.certificate,
            details: c.details,
            improvement: improvement.filter(|p| p.cost < solution.cost),
        })
    }
}

/// The simultaneous pipeline: the joint local solve ([`solve_simultaneous`]), then (modes
/// `auto`, `dual`, `sdp`) the dual certificate at the estimate `[H15]` and the SDP `[H14]`, verified by
/// [`crate::certify::simultaneous::certify_simultaneous`]; a cheaper SDP rounding, polished,
/// replaces the local solution.
///
/// ```
/// use rotavg::pipeline::simultaneous::{average_simultaneous, SimultaneousProblem};
/// use rotavg::multiple::Edge;
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// let rs: Vec<_> = [[0.0, 0.0, 0.0], [0.4, 0.0, 0.1], [0.0, 0.6, -0.2], [0.3, -0.3, 0.8], [-0.5, 0.2, 0.3]]
///     .iter()
///     .map(|v| exp(&Vector3::from(*v)))
///     .collect();
/// let s = exp(&Vector3::new(0.2, -0.5, 0.4));
/// let noise = |k: usize| exp(&Vector3::new(0.01 * (k % 3) as f64, -0.01, 0.005 * k as f64));
/// let pairs = [(0, 1), (1, 2), (2, 3), (3, 4), (4, 0), (0, 2), (1, 3)];
/// let e = |i: usize, j: usize, rotation| Edge { i, j, rotation, weight: 1.0 };
/// let right: Vec<_> = pairs.iter().enumerate()
///     .map(|(k, &(i, j))| e(i, j, noise(k) * rs[j] * rs[i].inverse())).collect();
/// let left: Vec<_> = pairs.iter().enumerate()
///     .map(|(k, &(i, j))| e(i, j, noise(k + 1) * s * rs[j] * rs[i].inverse() * s.inverse())).collect();
/// let p = SimultaneousProblem { num_nodes: 5, right, left };
/// let avg = average_simultaneous(&p, &Default::default())?;
/// // a verified bound on the joint minimum (paper-notes/conjugate.md [H14]): at this noise
/// // the relaxation is tight and the joint estimate is proven globally optimal
/// let c = avg.certificate.unwrap();
/// assert!(c.lower_bound.unwrap() <= avg.solution.cost);
/// assert!(c.is_certified());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_simultaneous(
    problem: &SimultaneousProblem,
    settings: &AverageSimultaneousSettings,
) -> Result<Averaged<SimultaneousSolution>> {
    average(problem, settings)
}
