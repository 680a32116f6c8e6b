//! Initialisations of the local solvers (`paper-notes/multiple.md`, `[M4]`, `[M5]`): the
//! shortest-path spanning tree from a central node, and the spectral relaxation (bottom-3
//! eigenvectors of the connection Laplacian by sparse block inverse iteration, rounded to
//! SO(3)).

use crate::deadline::Deadline;
use crate::error::{Error, Result};
use crate::linalg::block_pattern::BlockPattern;
use crate::linalg::linear_solver::{Factor, LinearSolver, SolverKind};
use crate::multiple::MultipleProblem;
use crate::multiple::chordal::{choose_solver, laplacian_solver};
use crate::multiple::problem::Adjacency;
use crate::multiple::solve::Initialisation;
use crate::so3::{Rotation, nearest_rotation, project_to_so3};
use faer::Mat;
use nalgebra::{Matrix3, SymmetricEigen};

/// Compute a starting estimate (one rotation per node; gauge not fixed), in SO(3) to rounding
/// (a given estimate is replaced by its nearest rotations, [`nearest_rotation`]: a start read
/// from a file is a rotation only to the validation tolerance). The graph must be
/// connected ([`Error::Disconnected`]); a given estimate must have one rotation per node.
///
/// ```
/// use rotavg::multiple::{initialise, Initialisation, synthetic::SyntheticGraph};
/// let (p, _) = SyntheticGraph { noise_sigma: 0.0, ..Default::default() }.generate();
/// for init in [Initialisation::SpanningTree, Initialisation::Spectral] {
///     let r = initialise(&p, &init).unwrap();
///     assert!(p.chordal_cost(&r) < 1e-16);
/// }
/// ```
pub fn initialise(problem: &MultipleProblem, init: &Initialisation) -> Result<Vec<Rotation>> {
    problem.require_connected()?;
    match init {
        Initialisation::SpanningTree => Ok(spanning_tree(problem)),
        Initialisation::Spectral => spectral_with(problem, None),
        Initialisation::Given(r) | Initialisation::L1Start(r) => {
            problem.check_estimate(r)?;
            Ok(r.iter().map(nearest_rotation).collect())
        }
    }
}

/// Spanning-tree initialisation `[M4]`: the shortest-path tree, with edge length `1 / w_ij`
/// (the variance of a measurement up to a common factor), from a central node `c` (the middle
/// of a long shortest path found by two breadth-first sweeps); rotations are propagated from
/// `R_c = I` along the tree by `R_j = R_ij R_i` (edges used in either direction), then the
/// gauge is fixed by `R_0 = I` (with information, `w_ij` is
/// [`crate::multiple::anisotropic::Information::start_weight`], the inverse of the mean
/// variance, `[A17]`). Every node's rotation is the product of the measurements on
/// its tree path, so the tree that minimises each path's summed variance from a central root
/// minimises the drift of the start (a 10^6-node grid sweep: paths of about 10^3 edges, where
/// the sweep's own odometry chain has 10^6). Each product is replaced by its nearest rotation
/// ([`nearest_rotation`]): measurements accepted within the validation tolerance (1DSfM files
/// are orthonormal to ~2.5e-6) would otherwise compose their defects along the path, and the
/// solvers would iterate off SO(3) (contract section 1). Nodes not reached (only if the graph is
/// disconnected) keep the identity.
///
/// ```
/// use rotavg::multiple::{spanning_tree, synthetic::SyntheticGraph};
/// use rotavg::so3::angle_between;
/// // Noise-free measurements: propagating along any spanning tree recovers the truth (R_0 = I).
/// let (p, truth) = SyntheticGraph { num_rotations: 20, num_edges: 40, noise_sigma: 0.0, ..Default::default() }.generate();
/// let r = spanning_tree(&p);
/// assert!(r.iter().zip(&truth).all(|(a, b)| angle_between(a, b) < 1e-12));
/// ```
pub fn spanning_tree(problem: &MultipleProblem) -> Vec<Rotation> {
    let start = problem.start_graph();
    let problem = start.as_ref();
    let n = problem.num_rotations();
    if n == 0 {
        return Vec::new();
    }
    let edges = problem.edges();
    let adjacency = problem.adjacency();
    let centre = central_node(adjacency);
    // Dijkstra from the centre with lengths 1 / w (ties by node index: deterministic)
    let mut dist = vec![f64::INFINITY; n];
    let mut via: Vec<Option<usize>> = vec![None; n];
    let mut done = vec![false; n];
    let mut heap = std::collections::BinaryHeap::new();
    dist[centre] = 0.0;
    heap.push(std::cmp::Reverse((TotalF64(0.0), centre)));
    let mut order = Vec::with_capacity(n);
    while let Some(std::cmp::Reverse((_, u))) = heap.pop() {
        if done[u] {
            continue;
        }
        done[u] = true;
        order.push(u);
        for &(v, k) in adjacency.neighbours(u) {
            let w = edges[k].weight;
            let length = if w > 0.0 { 1.0 / w } else { f64::INFINITY };
            let d = dist[u] + length;
            if !done[v] && d < dist[v] {
                dist[v] = d;
                via[v] = Some(k);
                heap.push(std::cmp::Reverse((TotalF64(d), v)));
            }
        }
    }
    let mut r = vec![Rotation::identity(); n];
    // `order` lists every reached node after its tree parent
    for &v in order.iter().skip(1) {
        let Some(k) = via[v] else { continue };
        let e = &edges[k];
        // R_ij R_i = R_j  =>  R_j = R_ij R_i,  R_i = R_ij^T R_j
        r[v] = nearest_rotation(&if e.j == v {
            e.rotation * r[e.i]
        } else {
            e.rotation.inverse() * r[e.j]
        });
    }
    // gauge: R_0 = I (the start does not depend on which node was the root)
    let g = r[0].inverse();
    r.iter().map(|ri| *ri * g).collect()
}

/// An `f64` ordered by `total_cmp` (for the binary heap of [`spanning_tree`]).
#[derive(Clone, Copy, PartialEq)]
struct TotalF64(f64);
impl Eq for TotalF64 {}
impl PartialOrd for TotalF64 {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for TotalF64 {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// A central node of the component of node 0: breadth-first search from node 0 to the
/// farthest node `a`, from `a` to the farthest node `b`, and the middle of that `a`-`b`
/// path (hop counts; `O(m)`).
fn central_node(adjacency: &Adjacency) -> usize {
    let a = adjacency.breadth_first(0).last;
    let far = adjacency.breadth_first(a);
    let (b, parent) = (far.last, far.parent);
    let mut path = vec![b];
    let mut u = b;
    while u != a {
        u = parent[u];
        path.push(u);
    }
    path[path.len() / 2]
}

/// Residual tolerance of the spectral initialisation, relative to the mean weighted degree:
/// stop when `||Q Y - Y (Y^T Q Y)||_F <= SPECTRAL_TOLERANCE * mean degree` `[M5]`.
pub const SPECTRAL_TOLERANCE: f64 = 1e-3;

/// Relative residual of the inner conjugate-gradient solves of the spectral initialisation on
/// high-fill graphs (inexact inverse iteration, `[M5]`).
pub const SPECTRAL_INNER_TOLERANCE: f64 = 1e-5;

/// Maximum number of block inverse iterations of the spectral initialisation `[M5]`.
pub const SPECTRAL_MAX_ITERATIONS: usize = 50;

/// Spectral initialisation `[M5]`: an orthonormal basis `Y` (3n x 3) of the bottom-3 invariant
/// subspace of the connection Laplacian `Q` (of the scalar weights; with information, each
/// edge's [`crate::multiple::anisotropic::Information::start_weight`], `[A17]`), by block
/// inverse iteration with a sparse
/// Cholesky factorisation of `Q + sigma I` (`sigma = 1e-6` x mean weighted degree; factorised
/// once), started from the spanning-tree estimate; stopped when the residual
/// [`SPECTRAL_TOLERANCE`] x mean degree or after [`SPECTRAL_MAX_ITERATIONS`].
/// Rounding: scale by `sqrt(n)`, flip the sign of the third column if most blocks have negative
/// determinant, project every 3x3 block to SO(3).
///
/// ```
/// use rotavg::multiple::{spanning_tree, spectral, synthetic::SyntheticGraph};
/// // With noise, the spectral estimate uses every edge and beats the spanning tree.
/// let (p, _) = SyntheticGraph { num_rotations: 50, num_edges: 200, noise_sigma: 0.1, ..Default::default() }.generate();
/// let r = spectral(&p)?;
/// assert!(p.chordal_cost(&r) < p.chordal_cost(&spanning_tree(&p)));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn spectral(problem: &MultipleProblem) -> Result<Vec<Rotation>> {
    spectral_with(problem, None)
}

/// [`spectral`] with the linear solver chosen by the caller (`None`: decide here). With the
/// Laplacian preconditioner `[M6b]`, `Q + sigma I` is preconditioned by
/// `D ((L + sigma I) ⊗ I_3) D^T`, `D` the block diagonal of the spanning-tree rotations (equal
/// to `Q + sigma I` on a tree, where the measurements are consistent).
pub(crate) fn spectral_with(
    problem: &MultipleProblem,
    kind: Option<SolverKind>,
) -> Result<Vec<Rotation>> {
    spectral_within(problem, kind, None)
}

/// [`spectral_with`] that stops its inverse iteration at `deadline` (checked before each
/// iteration; the one factorisation and the inner solve under way are not interrupted): the
/// iterate so far is rounded, the spanning tree when no iteration ran.
pub(crate) fn spectral_within(
    problem: &MultipleProblem,
    kind: Option<SolverKind>,
    deadline: Option<Deadline>,
) -> Result<Vec<Rotation>> {
    // with information, the scalar weights of [A17]
    let start = problem.start_graph();
    let problem = start.as_ref();
    let n = problem.num_rotations();
    let tree = spanning_tree(problem);
    if n < 2 {
        return Ok(tree);
    }
    let q = ConnectionLaplacian::new(problem);
    let kind = match kind {
        Some(k) => k,
        None => choose_solver(problem)?.kind,
    };
    let solver = match kind {
        SolverKind::Laplacian => {
            let frames = tree.iter().map(|r| *r.matrix()).collect();
            let sigma = SHIFT * q.mean_degree;
            laplacian_solver(problem, false, 1.0, sigma, Some(frames), None)?
        }
        k => LinearSolver::new(&q.pattern, k == SolverKind::Direct)?,
    };
    let llt = q.shifted_factor(&solver)?;
    let y = q.bottom_subspace(&llt, &tree, deadline)?;
    Ok(round_blocks(&y, &tree))
}

/// The shift `sigma` of the spectral inverse iteration, relative to the mean weighted degree:
/// `Q + sigma I` is positive definite (`Q` is PSD) and its inverse has the bottom eigenvectors
/// of `Q` on top `[M5]`.
const SHIFT: f64 = 1e-6;

/// The connection Laplacian `Q` of [`spectral_with`] (lower triangle on a block pattern) and the
/// mean weighted degree, its scale.
struct ConnectionLaplacian {
    pattern: BlockPattern,
    values: Vec<f64>,
    mean_degree: f64,
}

impl ConnectionLaplacian {
    /// `Q` of the problem's (isotropic) weights `[M2]`.
    fn new(problem: &MultipleProblem) -> Self {
        let n = problem.num_rotations();
        let pattern = BlockPattern::new(n, 3, problem.edges().iter().map(|e| (e.i, e.j)));
        let mut values = vec![0.0; pattern.nnz()];
        let mut degree = vec![0.0; n];
        for e in problem.edges() {
            degree[e.i] += e.weight;
            degree[e.j] += e.weight;
            // [M2]: Q_ji = -w R_ij (block row j, column i)
            let slot = pattern.slot(e.i, e.j);
            let block = -e.weight * e.rotation.matrix();
            pattern.add(&mut values, e.j, e.i, slot, &block);
        }
        for (i, d) in degree.iter().enumerate() {
            pattern.add(&mut values, i, i, 0, &(Matrix3::identity() * *d));
        }
        let mean_degree = degree.iter().sum::<f64>() / n as f64;
        ConnectionLaplacian {
            pattern,
            values,
            mean_degree,
        }
    }

    /// `Q + sigma I` factorised (or preconditioned) by `solver`, `sigma` from [`SHIFT`] x the
    /// mean degree, multiplied by 100 while the factorisation fails (up to the mean degree).
    fn shifted_factor<'a>(&'a self, solver: &'a LinearSolver) -> Result<Factor<'a>> {
        let mut sigma = SHIFT * self.mean_degree;
        loop {
            let mut val = self.values.clone();
            self.pattern.add_diagonal(&mut val, sigma);
            if let Some(l) = solver.factor(&self.pattern, &val) {
                return Ok(l);
            }
            sigma *= 100.0;
            if sigma > self.mean_degree {
                return Err(Error::Solver {
                    message: "spectral initialisation: Cholesky of Q + sigma I failed".into(),
                });
            }
        }
    }

    /// Block inverse iteration with `llt` from the stacked `start` rotations: an orthonormal
    /// basis (3n x 3) of the bottom-3 invariant subspace of `Q`, to the residual
    /// `||Q Y - Y (Y^T Q Y)||_F <= SPECTRAL_TOLERANCE x mean degree` or after
    /// [`SPECTRAL_MAX_ITERATIONS`] `[M5]`.
    fn bottom_subspace(
        &self,
        llt: &Factor<'_>,
        start: &[Rotation],
        deadline: Option<Deadline>,
    ) -> Result<Mat<f64>> {
        let mut y = Mat::<f64>::from_fn(3 * start.len(), 3, |k, b| start[k / 3][(k % 3, b)]);
        orthonormalise(&mut y);
        for _ in 0..SPECTRAL_MAX_ITERATIONS {
            // the orthonormalised start rounds back to the spanning tree
            if deadline.is_some_and(|d| d.passed()) {
                break;
            }
            if llt.solve(&mut y, SPECTRAL_INNER_TOLERANCE, 5000).is_none() {
                return Err(Error::Solver {
                    message: "spectral initialisation: Q + sigma I not positive definite (CG)"
                        .into(),
                });
            }
            orthonormalise(&mut y);
            let qy = self.pattern.sym_mul(&self.values, &y);
            let m = y.transpose() * &qy;
            let res = (&qy - &y * &m).norm_l2();
            if !res.is_finite() {
                return Err(Error::Solver {
                    message: "spectral initialisation: non-finite iterate".into(),
                });
            }
            if res <= SPECTRAL_TOLERANCE * self.mean_degree {
                break;
            }
        }
        Ok(y)
    }
}

/// The rounding of [`spectral_with`] `[M5]`: the blocks of `Y` scaled by `sqrt(n)`, the third
/// column negated when most blocks have a negative determinant, each block projected to SO(3)
/// (`fallback[i]` when not finite).
fn round_blocks(y: &Mat<f64>, fallback: &[Rotation]) -> Vec<Rotation> {
    let n = fallback.len();
    let scale = (n as f64).sqrt();
    let block = |i: usize| Matrix3::from_fn(|a, b| y[(3 * i + a, b)] * scale);
    let negative = (0..n).filter(|&i| block(i).determinant() < 0.0).count();
    let flip = 2 * negative > n;
    (0..n)
        .map(|i| {
            let mut m = block(i);
            if flip {
                m.column_mut(2).neg_mut();
            }
            project_to_so3(&m).unwrap_or(fallback[i])
        })
        .collect()
}

/// `Y <- Y (Y^T Y)^{-1/2}` (3 columns).
fn orthonormalise(y: &mut Mat<f64>) {
    let g = y.transpose() * &*y;
    let g = Matrix3::from_fn(|a, b| g[(a, b)]);
    let eig = SymmetricEigen::new(g);
    let floor = eig.eigenvalues.max() * 1e-15;
    let inv_sqrt = eig.eigenvectors
        * Matrix3::from_diagonal(&eig.eigenvalues.map(|l| 1.0 / l.max(floor).sqrt()))
        * eig.eigenvectors.transpose();
    let t = Mat::<f64>::from_fn(3, 3, |a, b| inv_sqrt[(a, b)]);
    *y = &*y * &t;
}
