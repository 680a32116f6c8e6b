//! The couplings' search's engine (`paper-notes/conjugate.md` `[H21]`, "The search"): a
//! proximal spectral bundle (Helmberg and Rendl) over each frame's pairs' sums (circulations of
//! their flows and symmetric parts, both summing to zero over the frames) and the trace
//! couplings between frames, towards the largest `lambda_min(S)`; `S`'s bottom eigenpairs come
//! from a [`Spectrum`]: [`Dense`] here, [`super::wide::Wide`] for large rigs.

use super::couplings::{PairSum, local_pairs};
use super::traces::Traces;
use crate::deadline::Deadline;
use crate::linalg::dense::{orthonormal_columns as columns, symmetric_eigen};
use crate::relax::spectral_bundle::{Model, Rules, Step, serious_step};
use crate::relax::svec::{svec_entry, svec_len, svec_weight};
use crate::so3::{Rotation, vee};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// The bundle's rules: 60 rounds at most (the rigs of `docs/benchmarks.md` "Small rigs along a
/// path" that it certifies: `S` positive definite after 3-42 rounds, 0.1-3.3 s of certify
/// each); 8 bottom eigenvectors kept and 3 of the candidate's added; stopped when 10 rounds
/// gained less than `1e-2` of the start's `|lambda_min|` (30 frames, 4 sensors, seed 11 of
/// `[H21]` "The search": it crawls from -9.7 to -2.8 over 60 rounds, where the within-frame
/// couplings likely cannot certify).
pub(super) const RULES: Rules = Rules {
    rounds: 60,
    widths: (8, 3),
    stall: (1e-2, 10),
};

/// The search stops once `lambda_min(S)` is this fraction of its start's magnitude above zero:
/// the margin the augmented graph's own proof then works with.
const MARGIN: f64 = 0.05;

/// The search also stops when [`OPTIMISM`] times its rate over the last [`RATE_ROUNDS`] rounds,
/// kept up for every round left, would not bring `lambda_min` to zero (`[H21]` "When the
/// search stops": the rig soundness campaign's small rigs that it cannot certify plateau after
/// 3-5 serious steps, far below zero; those it certifies gain 10-60 % of `|lambda_min|` per
/// serious step, after slower steps too, so a geometric extrapolation of the gains would stop
/// some of them).
const OPTIMISM: f64 = 2.0;
const RATE_ROUNDS: usize = 3;

/// `S`'s bottom eigenvalues (ascending) and eigenvectors (the columns) at a point, and what
/// `V^T S V` is formed from there.
pub(super) type Eigen<A> = (Vec<f64>, DMatrix<f64>, A);

/// Where the bundle gets the bottom eigenpairs of `S` at a point of the space, and `V^T S V`:
/// the dense `S` of a small rig ([`Dense`]) or a large rig's sparse one ([`Wide`]).
pub(super) trait Spectrum {
    /// What `V^T S V` is formed from at a point.
    type At;
    /// The first round's proximal weight times `|lambda_min|` at the start.
    const FIRST_RHO: f64;
    /// The bottom eigenvalues of `S` at `moves` (ascending, estimates for [`Wide`]), their
    /// eigenvectors (the columns) and `S`; `None` when they cannot be had.
    fn at(&self, space: &Space<'_>, moves: &Moves) -> Option<Eigen<Self::At>>;
    /// `V^T S V`.
    fn restricted(&self, at: &Self::At, v: &DMatrix<f64>) -> DMatrix<f64>;
}

/// A small rig's dense `S` at the least-norm couplings, gauged ([`gauged`]).
pub(super) struct Dense(pub DMatrix<f64>);

impl Spectrum for Dense {
    type At = DMatrix<f64>;
    const FIRST_RHO: f64 = 1.0;

    fn at(&self, space: &Space<'_>, moves: &Moves) -> Option<Eigen<Self::At>> {
        let s = space.matrix(&self.0, moves);
        let (values, vectors) = symmetric_eigen(&s)?;
        Some((values, vectors, s))
    }

    fn restricted(&self, s: &DMatrix<f64>, v: &DMatrix<f64>) -> DMatrix<f64> {
        v.transpose() * s * v
    }
}

/// A progress line for why the search stopped without certifying.
pub(super) fn stopped(why: &str) {
    crate::progress::emit(|| crate::progress::Event::Phase {
        phase: crate::progress::Phase::Certify,
        detail: format!("the couplings' search [H21] stopped: {why}"),
    });
}

/// `Some(why)` when `history` (`lambda_min` after each round, the start first) gains too slowly
/// for the rounds left to bring it to zero at [`OPTIMISM`] times its recent rate.
fn too_slow(history: &[f64]) -> Option<String> {
    let round = history.len() - 1;
    if round <= RATE_ROUNDS {
        return None;
    }
    let now = history[round];
    let rate = (now - history[round - RATE_ROUNDS]) / RATE_ROUNDS as f64;
    let left = RULES.rounds.saturating_sub(round) as f64;
    (now + OPTIMISM * rate * left < 0.0).then(|| {
        format!(
            "at its rate of the last {RATE_ROUNDS} rounds ({rate:.1e} per round) lambda_min(S) \
             {now:.2e} would stay below zero for the {left} rounds left"
        )
    })
}

/// The search's space: moves of each frame's pairs' sums (`u` a circulation of the frame's
/// flows, `k` symmetric), both summing to zero over the frames for every pair, and trace
/// couplings between frames (`[H21]` "Trace couplings"; zero sum over the sensors), whose
/// torques flows within each frame balance.
pub(super) struct Space<'a> {
    per_frame: &'a [Vec<(usize, usize)>],
    sensors: &'a [Rotation],
    k: usize,
    x: &'a [Rotation],
    traces: Traces,
    tau: Vec<Vector3<f64>>,
}

/// A point of the search's space: the pairs' sums' circulations and symmetric parts, and the
/// trace couplings (their balancing flows not included).
#[derive(Clone)]
pub(super) struct Moves {
    pub sums: Vec<Vec<PairSum>>,
    pub traces: Traces,
}

/// What [`Space::bundle`] found: the moves, `lambda_min` of `S` before and after, the rounds.
pub(super) struct Run {
    pub moves: Moves,
    pub start: f64,
    pub reached: f64,
    pub rounds: usize,
}

/// The variables of one pair's move: `u` (3), then `k`'s upper triangle (6).
const PAIR_VARIABLES: usize = 9;
const UPPER: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

impl<'a> Space<'a> {
    /// The space of the frames `per_frame` (`k` sensors in every frame; `(sensor, image)`):
    /// trace couplings between the frames one of `edges` within one sensor joins.
    pub(super) fn new(
        per_frame: &'a [Vec<(usize, usize)>],
        edges: impl Iterator<Item = (usize, usize)>,
        (x, sensors): (&'a [Rotation], &'a [Rotation]),
        k: usize,
    ) -> Self {
        let mut image = vec![(0, 0); x.len()];
        for (f, images) in per_frame.iter().enumerate() {
            for (i, &(_, a)) in images.iter().enumerate() {
                image[a] = (f, i);
            }
        }
        let traces = Traces::between(edges, &image, k);
        Space {
            per_frame,
            sensors,
            k,
            x,
            tau: traces.torques(per_frame, x, sensors),
            traces,
        }
    }

    /// The most pseudo-edges the couplings of a point of the space make: 9 per pair (3 for a
    /// sum's skew part, 6 for its symmetric part), 3 per trace coupling's scalar.
    pub(super) fn pseudo_edges_at_most(&self) -> usize {
        self.per_frame.len() * self.k * (self.k - 1) / 2 * 9 + self.traces.pairs.len() * self.k * 3
    }

    /// The most image pairs those pseudo-edges join: each frame's pairs of sensors, and each
    /// trace coupling's pair of one sensor's images.
    pub(super) fn pseudo_pairs_at_most(&self) -> usize {
        self.per_frame.len() * self.k * (self.k - 1) / 2 + self.traces.pairs.len() * self.k
    }

    /// The number of the space's variables.
    pub(super) fn variables(&self) -> usize {
        self.per_frame.len() * self.k * (self.k - 1) / 2 * PAIR_VARIABLES
            + self.traces.pairs.len() * self.k
    }

    pub(super) fn zero(&self) -> Moves {
        let pairs = self.k * (self.k - 1) / 2;
        let zero = PairSum {
            u: Vector3::zeros(),
            k: Matrix3::zeros(),
        };
        Moves {
            sums: vec![vec![zero; pairs]; self.per_frame.len()],
            traces: self.traces.clone(),
        }
    }

    /// `moves` with the trace couplings' balancing flows added to the sums: in each frame the
    /// least-norm flow `(d_i - d_j) / k` of the couplings' demands `d` (they sum to zero over
    /// the frames: a pair's torques at its two frames are opposite).
    pub(super) fn with_flows(&self, moves: &Moves) -> Moves {
        let demands = moves.traces.demands(self.per_frame.len(), &self.tau);
        let mut out = moves.clone();
        let local = local_pairs(self.k);
        for (frame, d) in out.sums.iter_mut().zip(&demands) {
            for (m, &(i, j)) in frame.iter_mut().zip(&local) {
                m.u += (d[i] - d[j]) / self.k as f64;
            }
        }
        out
    }

    /// `(f, s, a, t, b)` of every frame's local pairs, in the order of the moves.
    fn pairs(&self) -> impl Iterator<Item = (usize, usize, (usize, usize), (usize, usize))> + '_ {
        self.per_frame.iter().enumerate().flat_map(|(f, images)| {
            local_pairs(images.len())
                .into_iter()
                .enumerate()
                .map(move |(p, (i, j))| (f, p, images[i], images[j]))
        })
    }

    /// The gradient of `tr(W S)` in each pair's sum `T` for `W = sym(v w^T)`: `S_s^T W_aa S_s +
    /// S_t^T W_bb S_t - 2 S_t^T W_ba S_s`, as the variables of the moves, projected on the
    /// search's space.
    fn gradient(
        &self,
        v: nalgebra::DVectorView<'_, f64>,
        w: nalgebra::DVectorView<'_, f64>,
    ) -> Vec<f64> {
        let mut g = self.zero();
        let part = |x: nalgebra::DVectorView<'_, f64>, r: usize| -> Vector3<f64> {
            x.fixed_rows::<3>(3 * r).into()
        };
        let block = |r: usize, c: usize| -> Matrix3<f64> {
            0.5 * (part(v, r) * part(w, c).transpose() + part(w, r) * part(v, c).transpose())
        };
        for (f, p, (ss, a), (st, b)) in self.pairs() {
            let (rs, rt) = (self.sensors[ss].matrix(), self.sensors[st].matrix());
            let d = rs.transpose() * block(a, a) * rs + rt.transpose() * block(b, b) * rt
                - 2.0 * rt.transpose() * block(b, a) * rs;
            // <d, hat(u) + k>: u's part vee(d - d^T), k's the symmetric part (both triangles)
            g.sums[f][p] = PairSum {
                u: vee(&(d - d.transpose())),
                k: d + d.transpose() - Matrix3::from_diagonal(&d.diagonal()),
            };
        }
        g.traces.mu = self.traces.gradient(self.per_frame, self.x, block);
        self.through_flows(&mut g);
        self.project(&mut g);
        flatten(&g)
    }

    /// Adds to the trace couplings' gradient in `g` their balancing flows' part: the adjoint of
    /// [`Self::with_flows`] applied to the flows' gradient `g.sums[..].u` (before projection).
    fn through_flows(&self, g: &mut Moves) {
        let k = self.k as f64;
        let local = local_pairs(self.k);
        // the gradient in each frame's demand of local sensor i: sum over its pairs of +-g_u / k
        let adjoint: Vec<Vec<Vector3<f64>>> = g
            .sums
            .iter()
            .map(|frame| {
                let mut d = vec![Vector3::zeros(); self.k];
                for (m, &(i, j)) in frame.iter().zip(&local) {
                    d[i] += m.u / k;
                    d[j] -= m.u / k;
                }
                d
            })
            .collect();
        let traces = &mut g.traces;
        for ((&(f, h), mu), t) in traces.pairs.iter().zip(&mut traces.mu).zip(&self.tau) {
            for (i, m) in mu.iter_mut().enumerate() {
                *m += t.dot(&(adjoint[h][i] - adjoint[f][i]));
            }
        }
    }

    /// The orthogonal projection on the search's space: each frame's flows on the circulations
    /// of its complete graph of `k` sensors (`u - B B^T u / k`), then every pair's mean over the
    /// frames removed (`u` and `k`). In the variables' Euclidean inner product.
    fn project(&self, moves: &mut Moves) {
        moves.traces.project();
        let moves = &mut moves.sums;
        let k = self.k;
        let local = local_pairs(k);
        for frame in moves.iter_mut() {
            let mut divergence = vec![Vector3::zeros(); k];
            for ((i, j), m) in local.iter().zip(frame.iter()) {
                divergence[*i] += m.u;
                divergence[*j] -= m.u;
            }
            for ((i, j), m) in local.iter().zip(frame.iter_mut()) {
                m.u -= (divergence[*i] - divergence[*j]) / k as f64;
            }
        }
        let frames = moves.len().max(1) as f64;
        for p in 0..local.len() {
            let (mut u, mut kk) = (Vector3::zeros(), Matrix3::zeros());
            for frame in moves.iter() {
                u += frame[p].u;
                kk += frame[p].k;
            }
            for frame in moves.iter_mut() {
                frame[p].u -= u / frames;
                frame[p].k -= kk / frames;
            }
        }
    }

    /// The moves of the variables `y` (projected on the space).
    fn moves(&self, y: &[f64]) -> Moves {
        let mut m = self.zero();
        let pairs = m.sums.iter().map(Vec::len).sum::<usize>();
        let (y, mu) = y.split_at(pairs * PAIR_VARIABLES);
        for (to, from) in m.traces.mu.iter_mut().zip(mu.chunks(self.k)) {
            to.copy_from_slice(from);
        }
        for (frame, chunk) in m
            .sums
            .iter_mut()
            .flat_map(|f| f.iter_mut())
            .zip(y.chunks(PAIR_VARIABLES))
        {
            frame.u = Vector3::new(chunk[0], chunk[1], chunk[2]);
            let mut k = Matrix3::zeros();
            for (&(r, c), v) in UPPER.iter().zip(&chunk[3..]) {
                k[(r, c)] = *v;
                k[(c, r)] = *v;
            }
            frame.k = k;
        }
        self.project(&mut m);
        m
    }

    /// The proximal bundle: each round maximises `t - rho |y|^2 / 2` with `V^T S(T + y) V >= t I`
    /// (`V` the bundle), moves when the true `lambda_min` gains a tenth of the model's
    /// prediction (`rho` halved), else only enriches the bundle (`rho` doubled). Stops at
    /// [`MARGIN`], [`RULES`]' rounds, a stall, a rate too slow for the rounds left
    /// ([`too_slow`]) or the deadline: the moves,
    /// `lambda_min` and rounds when it became positive.
    pub(super) fn bundle<O: Spectrum>(
        &self,
        oracle: &O,
        start: Eigen<O::At>,
        deadline: Option<Deadline>,
    ) -> Option<Run> {
        let (kept, added_columns) = RULES.widths;
        let (mut at, (values, mut vectors, mut s_at)) = (self.zero(), start);
        let (lambda0, mut lambda) = (values[0], values[0]);
        if lambda0 >= 0.0 {
            return None;
        }
        let mut bundle = columns(&vectors, kept, None);
        let mut rho = O::FIRST_RHO / lambda0.abs();
        let (mut rounds, mut history, mut nulls) = (0, vec![lambda0], 0);
        for round in 1..=RULES.rounds {
            if deadline.is_some_and(|d| d.passed()) {
                break;
            }
            rounds = round;
            let c = oracle.restricted(&s_at, &bundle);
            let (y, predicted) = self.model_step(&bundle, &c, rho, deadline)?;
            // the point's spectrum is the round's other half (a factorisation and its solves)
            if deadline.is_some_and(|d| d.passed()) {
                break;
            }
            let candidate = added(&at, &self.moves(&y));
            let (values, new_vectors, s_candidate) = oracle.at(self, &candidate)?;
            let serious = serious_step(values[0] - lambda, predicted - lambda, &mut rho);
            bundle = columns(&vectors, kept, Some((&new_vectors, added_columns)));
            if serious {
                (at, lambda, vectors, s_at) = (candidate, values[0], new_vectors, s_candidate);
                bundle = columns(&vectors, kept, None);
            }
            crate::progress::emit(|| crate::progress::Event::Phase {
                phase: crate::progress::Phase::Certify,
                detail: format!(
                    "the couplings' search [H21]: round {round}, lambda_min(S) {lambda:.3e}"
                ),
            });
            if lambda >= MARGIN * lambda0.abs() {
                return Some(Run {
                    moves: at,
                    start: lambda0,
                    reached: lambda,
                    rounds: round,
                });
            }
            history.push(lambda);
            if RULES.stalled(&history, lambda0.abs()) {
                let (fraction, rounds) = RULES.stall;
                stopped(&format!(
                    "{rounds} rounds gained less than {fraction} of |lambda_min|"
                ));
                break;
            }
            nulls += usize::from(!serious);
            // while every step is serious the proximal weight halves each round: a ramp
            if let Some(why) = too_slow(&history).filter(|_| nulls > 0) {
                stopped(&why);
                break;
            }
        }
        (lambda > 0.0).then_some(Run {
            moves: at,
            start: lambda0,
            reached: lambda,
            rounds,
        })
    }

    /// One round's model: `max t - rho |y|^2 / 2` s.t. `C + A(y) - t I` positive semidefinite
    /// (`C = V^T S(T) V`, `s_at = S(T)`, `A(y) = V^T D(y) V`), solved through its dual in the
    /// bundle's own dimension (`[H21]` "The model's dual", [`Model::step`] with `tr W = 1`)
    /// within the deadline: `(y, t)`.
    fn model_step(
        &self,
        v: &DMatrix<f64>,
        c: &DMatrix<f64>,
        rho: f64,
        deadline: Option<Deadline>,
    ) -> Option<(Vec<f64>, f64)> {
        let len = svec_len(v.ncols());
        // `svec(A(y)) = G y`: row `svec_index(i, j)` the weighted derivative of entry `(i, j)`,
        // held as `G^T` (each derivative a contiguous column)
        let mut gt = DMatrix::zeros(self.variables(), len);
        for (row, mut column) in gt.column_iter_mut().enumerate() {
            let (i, j) = svec_entry(row);
            let gradient = self.gradient(v.column(i).as_view(), v.column(j).as_view());
            let weight = svec_weight(i, j);
            for (out, d) in column.iter_mut().zip(gradient) {
                *out = weight * d;
            }
        }
        let model = Model {
            derivatives: &gt,
            restricted: c,
            linear: None,
            metric: None,
            weight: 1.0,
        };
        let Step { y, t } = model.step(rho, deadline.and_then(|d| d.left()))?;
        Some((y, t))
    }

    /// `S` with the moves' pseudo-edges: for a pair's sum `T` (`sum c N`), `S_s sym(T) S_s^T`
    /// and `S_t sym(T) S_t^T` on the diagonal blocks of `a = (f, s)`, `b = (f, t)`, `-S_t T
    /// S_s^T` in block `(b, a)` (the pseudo-edges' Laplacian less the multipliers they add).
    fn matrix(&self, s0: &DMatrix<f64>, moves: &Moves) -> DMatrix<f64> {
        let mut s = s0.clone();
        moves.traces.add_to(&mut s, self.per_frame, self.x);
        let moves = self.with_flows(moves).sums;
        for (f, p, (ss, a), (st, b)) in self.pairs() {
            let t = moves[f][p].matrix();
            let (rs, rt) = (self.sensors[ss].matrix(), self.sensors[st].matrix());
            let sym = 0.5 * (t + t.transpose());
            let off = -(rt * t * rs.transpose());
            for (r, c, m) in [
                (a, a, rs * sym * rs.transpose()),
                (b, b, rt * sym * rt.transpose()),
                (b, a, off),
                (a, b, off.transpose()),
            ] {
                let mut view = s.fixed_view_mut::<3, 3>(3 * r, 3 * c);
                view += m;
            }
        }
        s
    }
}

fn added(a: &Moves, b: &Moves) -> Moves {
    Moves {
        sums: added_sums(&a.sums, &b.sums),
        traces: a.traces.added(&b.traces),
    }
}

/// The sums `a + b`, pair by pair.
pub(super) fn added_sums(a: &[Vec<PairSum>], b: &[Vec<PairSum>]) -> Vec<Vec<PairSum>> {
    (a.iter().zip(b))
        .map(|(a, b)| {
            (a.iter().zip(b))
                .map(|(a, b)| PairSum {
                    u: a.u + b.u,
                    k: a.k + b.k,
                })
                .collect()
        })
        .collect()
}

/// The moves as the variables (`u`, then `k`'s upper triangle, pair by pair; then the trace
/// couplings' scalars).
fn flatten(moves: &Moves) -> Vec<f64> {
    let mut y = Vec::new();
    for m in moves.sums.iter().flatten() {
        y.extend(m.u.iter());
        y.extend(UPPER.iter().map(|&(r, c)| m.k[(r, c)]));
    }
    y.extend(moves.traces.mu.iter().flatten());
    y
}

#[cfg(test)]
mod tests {
    use crate::certify::rig::couplings::couple;
    use crate::rig::{RigScene, RigSettings, solve_rig};
    use crate::so3::Rotation;

    /// A 12-frame rig of 3 estimated sensors along a path, solved: its least-norm couplings,
    /// image rotations and sensors.
    fn short_rig() -> (
        crate::certify::rig::couplings::Coupled,
        Vec<Rotation>,
        Vec<Rotation>,
    ) {
        let scene = RigScene {
            frames: 12,
            sensors: 3,
            noise_sigma: 0.01,
            extra_edge_span: 10,
            seed: 2,
            ..Default::default()
        };
        let (p, _) = scene.generate();
        let s = solve_rig(&p, &RigSettings::default()).unwrap();
        let c = couple(&p, &s.frames, &s.sensors, u64::MAX)
            .unwrap()
            .unwrap();
        (c, p.image_rotations(&s.frames, &s.sensors), s.sensors)
    }

    /// The model's gradient is the derivative of `tr(W S)`: for random moves `y` (projected),
    /// `<gradient, y>` equals `tr(W (S(y) - S(0)))` from [`super::Space::matrix`] (`S` is affine
    /// in the moves), through the trace couplings' balancing flows too.
    #[test]
    fn the_models_gradient_is_the_derivative_of_s() {
        use rand::{Rng, SeedableRng, rngs::StdRng};
        let (c, x, sensors) = short_rig();
        let n = 3 * x.len();
        let space = super::Space::new(
            &c.layout.per_frame,
            c.graph.edges().iter().map(|e| (e.i, e.j)),
            (&x, &sensors),
            3,
        );
        let zero = nalgebra::DMatrix::zeros(n, n);
        assert!(!space.traces.pairs.is_empty());
        let mut rng = StdRng::seed_from_u64(4);
        let v = nalgebra::DVector::from_fn(n, |_, _| rng.random::<f64>() - 0.5);
        let w = nalgebra::DVector::from_fn(n, |_, _| rng.random::<f64>() - 0.5);
        let sym = 0.5 * (&v * w.transpose() + &w * v.transpose());
        let gradient = space.gradient(v.as_view(), w.as_view());
        for _ in 0..5 {
            let y: Vec<f64> = (0..gradient.len())
                .map(|_| rng.random::<f64>() - 0.5)
                .collect();
            let moves = space.moves(&y);
            let flat = super::flatten(&moves);
            let predicted: f64 = gradient.iter().zip(&flat).map(|(g, y)| g * y).sum();
            let actual = sym.component_mul(&space.matrix(&zero, &moves)).sum();
            assert!(
                (predicted - actual).abs() <= 1e-9 * actual.abs().max(1.0),
                "{predicted} {actual}"
            );
        }
    }

    /// The model step through its dual is the primal's maximiser: `t - rho |y|^2 / 2` with `t =
    /// lambda_min(V^T S(y) V)` from [`super::Space::matrix`] (not from the dual) at the step's `y`
    /// is at least its value at nearby points of the space and at `y = 0`, and `t` is that
    /// `lambda_min`.
    #[test]
    fn the_models_dual_gives_the_primal_maximiser() {
        use rand::{Rng, SeedableRng, rngs::StdRng};
        let (c, x, sensors) = short_rig();
        let n = 3 * x.len();
        let mut rng = StdRng::seed_from_u64(6);
        let s0 = nalgebra::DMatrix::from_fn(n, n, |_, _| rng.random::<f64>() - 0.5);
        let s0 = &s0 + s0.transpose();
        let space = super::Space::new(
            &c.layout.per_frame,
            c.graph.edges().iter().map(|e| (e.i, e.j)),
            (&x, &sensors),
            3,
        );
        let v = nalgebra::DMatrix::from_fn(n, 8, |_, _| rng.random::<f64>() - 0.5)
            .qr()
            .q();
        let rho = 0.3;
        let value = |y: &[f64]| {
            let m = v.transpose() * space.matrix(&s0, &space.moves(y)) * &v;
            let t = crate::linalg::dense::symmetric_eigenvalues(&m).unwrap()[0];
            (t, t - 0.5 * rho * y.iter().map(|a| a * a).sum::<f64>())
        };
        let (y, t) = space
            .model_step(&v, &(v.transpose() * &s0 * &v), rho, None)
            .unwrap();
        let (t_y, at) = value(&y);
        assert!((t - t_y).abs() <= 1e-6 * t.abs().max(1.0), "{t} {t_y}");
        let zero = vec![0.0; y.len()];
        assert!(at > value(&zero).1 + 1e-3, "{at}");
        let norm = y.iter().map(|a| a * a).sum::<f64>().sqrt();
        for _ in 0..20 {
            let d: Vec<f64> = (0..y.len()).map(|_| rng.random::<f64>() - 0.5).collect();
            let d = super::flatten(&space.moves(&d));
            let scale = 0.05 * norm / d.iter().map(|a| a * a).sum::<f64>().sqrt();
            let near: Vec<f64> = y.iter().zip(&d).map(|(a, b)| a + scale * b).collect();
            assert!(
                value(&near).1 <= at + 1e-6 * at.abs().max(1.0),
                "{} > {at}",
                value(&near).1
            );
        }
    }

    /// The stopping rules on trajectories of the rig soundness campaign (`[H21]` "When the
    /// search stops"): a plateau far below zero stops at its fifth round, not its fifteenth; a
    /// search that slows down and then accelerates to a positive `lambda_min` (rounds with null
    /// steps repeat a value) is never stopped on its way.
    #[test]
    fn the_search_stops_on_a_plateau_and_not_on_a_slow_start() {
        let plateau = [-4.52, -3.62, -3.29, -3.24, -3.22, -3.22, -3.20];
        let stop = (1..=plateau.len()).find(|&i| super::too_slow(&plateau[..i]).is_some());
        assert_eq!(stop, Some(6), "stops after round 5");
        let certified = [
            -0.166, -0.123, -0.096, -0.096, -0.086, -0.086, -0.071, -0.071, -0.050, -0.021, -0.021,
            0.008,
        ];
        for i in 1..=certified.len() {
            assert_eq!(super::too_slow(&certified[..i]), None, "{i}");
        }
    }
}
