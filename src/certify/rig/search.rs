//! A search over a small rig's within-frame couplings (`paper-notes/conjugate.md` `[H21]`, "The
//! search"): where the least-norm couplings leave the augmented graph's `S` indefinite, a
//! proximal spectral bundle (Helmberg and Rendl) moves each frame's pairs' sums by circulations
//! of their flows and by symmetric parts, both summing to zero over the frames, towards the
//! largest `lambda_min(S)`. Only a choice: whatever it returns is handed to the augmented graph's
//! ladder, which proves its bound or does not ([`super::couplings`]: any pseudo-edges give a
//! sound bound).

use super::couplings::{Coupled, PairSum, local_pairs};
use super::traces::Traces;
use crate::certify::multiple::multipliers::{FirstOrder, certificate_matrix};
use crate::deadline::Deadline;
use crate::error::Result;
use crate::linalg::cholesky::to_dense;
use crate::linalg::dense::symmetric_eigen;
use crate::relax::clarabel::{Cone, csc, solve_quadratic_conic};
use crate::relax::settings::SdpSettings;
use crate::relax::svec::{svec_index, svec_len, svec_weight};
use crate::so3::{Rotation, vee};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Most images a rig's search takes: a dense `3N x 3N` eigen-decomposition and a Clarabel model
/// per round (30 frames and 6 sensors, `3N = 540`: 17.9 s for four rigs' solves and
/// certificates, `docs/benchmarks.md` "Small rigs along a path").
pub(crate) const SEARCH_MAX_IMAGES: usize = 300;

/// Most rounds of the bundle (the rigs of `docs/benchmarks.md` "Small rigs along a path" that
/// it certifies: `S` positive definite after 3-42 rounds, 0.1-3.3 s of certify each).
const SEARCH_ROUNDS: usize = 60;

/// Bottom eigenvectors kept in the bundle, and the candidate's added each round.
const BUNDLE: usize = 8;
const CANDIDATE: usize = 3;

/// The search stops once `lambda_min(S)` is this fraction of its start's magnitude above zero:
/// the margin the augmented graph's own proof then works with.
const MARGIN: f64 = 0.05;

/// The search stops when [`STALL_ROUNDS`] rounds gained less than this fraction of the start's
/// `|lambda_min|` (30 frames, 4 sensors, seed 11 of `[H21]` "The search": it crawls from -9.7
/// to -2.8 over 60 rounds, where the within-frame couplings likely cannot certify).
const STALL: f64 = 1e-2;
const STALL_ROUNDS: usize = 10;

/// The search also stops when [`OPTIMISM`] times its rate over the last [`RATE_ROUNDS`] rounds,
/// kept up for every round left, would not bring `lambda_min` to zero (`[H21]` "When the
/// search stops": the rig soundness campaign's small rigs that it cannot certify plateau after
/// 3-5 serious steps, far below zero; those it certifies gain 10-60 % of `|lambda_min|` per
/// serious step, after slower steps too, so a geometric extrapolation of the gains would stop
/// some of them).
const OPTIMISM: f64 = 2.0;
const RATE_ROUNDS: usize = 3;

/// What the search is given: the time, the memory and the rig's allowed gap.
#[derive(Clone, Copy)]
pub(crate) struct Limits {
    pub deadline: Option<Deadline>,
    pub max_bytes: u64,
    pub gap: f64,
}

/// What the search found: the sums, the trace couplings, and `lambda_min(S)` (gauge apart)
/// before and after.
pub(crate) struct Searched {
    pub sums: Vec<Vec<PairSum>>,
    pub traces: Traces,
    pub start: f64,
    pub reached: f64,
    pub rounds: usize,
}

/// Dense `3N x 3N` matrices the search holds at once (`S` at the start, at the point and at the
/// candidate, the two eigenvector matrices and the one being formed), charged against the
/// memory budget.
const DENSE_COPIES: u64 = 6;

/// The search from `coupled` (the least-norm couplings at the image rotations `x`), or `None`
/// when it does not apply (more than [`SEARCH_MAX_IMAGES`] images, or dense matrices over half
/// of `max_bytes`, frames photographed by different sensors, `S` already positive
/// semidefinite, an estimate too far from critical for any couplings: [`hopeless`]) or finds
/// no positive `lambda_min`.
pub(crate) fn search(
    coupled: &Coupled,
    (x, sensors): (&[Rotation], &[Rotation]),
    limits: Limits,
) -> Result<Option<Searched>> {
    let per_frame = &coupled.layout.per_frame;
    let Some(k) = uniform(per_frame) else {
        return Ok(None);
    };
    let dense = DENSE_COPIES * 8 * (3 * x.len() as u64).pow(2);
    if x.len() > SEARCH_MAX_IMAGES || dense > limits.max_bytes / 2 {
        return Ok(None);
    }
    let first = FirstOrder::at(&coupled.graph, x)?;
    let s = to_dense(certificate_matrix(&coupled.graph, &first.lambdas)?.as_ref());
    if let Some(why) = hopeless(first.stationarity, s.trace(), x.len(), limits.gap) {
        stopped(&why);
        return Ok(None);
    }
    let space = Space::new(
        coupled,
        (x, sensors),
        k,
        gauged(0.5 * (&s + s.transpose()), x),
    );
    let Some(start) = symmetric_eigen(&space.s0) else {
        return Ok(None);
    };
    let lambda0 = start.0[0];
    if lambda0 >= 0.0 {
        return Ok(None);
    }
    Ok(space
        .bundle(start, limits.deadline)
        .map(|(delta, reached, rounds)| Searched {
            sums: added_sums(&coupled.sums, &space.with_flows(&delta).sums),
            traces: delta.traces,
            start: lambda0,
            reached,
            rounds,
        }))
}

/// `Some(why)` when no couplings can certify the estimate: the moves keep `S Y` (its norm the
/// stationarity residual `rho`, `[D3]`) and `tr(S)` (their symmetric parts sum to zero over
/// the frames, circulations are traceless), and a bound within `gap` needs `lambda_min` of `S`
/// without a node at least `3 rho^2 / gap` (`[D15]`'s deficit, `multiple::grounded`), which
/// no `S` with diagonal blocks near positive semidefinite reaches above its mean eigenvalue
/// `tr(S) / (3 N - 3)` (`[H21]` "When the search stops"). A diagnosis: it decides what runs.
fn hopeless(rho: f64, trace: f64, images: usize, gap: f64) -> Option<String> {
    let mean = trace / (3.0 * images.saturating_sub(1).max(1) as f64);
    let needed = 3.0 * rho * rho / gap;
    (gap > 0.0 && mean.is_finite() && needed > mean).then(|| {
        format!(
            "not a critical point: the stationarity residual {rho:.1e} needs lambda_min(S              without a node) >= {needed:.1e}, above tr(S) / (3N - 3) = {mean:.1e}"
        )
    })
}

/// A progress line for why the search stopped without certifying.
fn stopped(why: &str) {
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
    let left = SEARCH_ROUNDS.saturating_sub(round) as f64;
    (now + OPTIMISM * rate * left < 0.0).then(|| {
        format!(
            "at its rate of the last {RATE_ROUNDS} rounds ({rate:.1e} per round) lambda_min(S) \
             {now:.2e} would stay below zero for the {left} rounds left"
        )
    })
}

/// The sensors every frame is photographed by, when they are the same for every frame (their
/// number `k >= 2`).
fn uniform(per_frame: &[Vec<(usize, usize)>]) -> Option<usize> {
    let first: Vec<usize> = per_frame.first()?.iter().map(|p| p.0).collect();
    let same = per_frame
        .iter()
        .all(|f| f.len() == first.len() && f.iter().zip(&first).all(|(p, s)| p.0 == *s));
    (same && first.len() >= 2).then_some(first.len())
}

/// `s + sigma X X^T / N` (`X` the stacked `x_a`, `S X = 0` up to the estimate's residual, kept
/// by every move; `sigma = ||s||_F >= lambda_max(s)`): the gauge's three directions, of eigenvalue
/// `sigma`, moved to the top of the spectrum.
fn gauged(mut s: DMatrix<f64>, x: &[Rotation]) -> DMatrix<f64> {
    let per_image = s.norm() / x.len() as f64;
    for (a, xa) in x.iter().enumerate() {
        for (b, xb) in x.iter().enumerate() {
            let block = per_image * xa.matrix() * xb.matrix().transpose();
            let mut view = s.fixed_view_mut::<3, 3>(3 * a, 3 * b);
            view += block;
        }
    }
    s
}

/// The search's space: moves of each frame's pairs' sums (`u` a circulation of the frame's
/// flows, `k` symmetric), both summing to zero over the frames for every pair, and trace
/// couplings between frames (`[H21]` "Trace couplings"; zero sum over the sensors), whose
/// torques flows within each frame balance.
struct Space<'a> {
    per_frame: &'a [Vec<(usize, usize)>],
    sensors: &'a [Rotation],
    k: usize,
    x: &'a [Rotation],
    traces: Traces,
    tau: Vec<Vector3<f64>>,
    s0: DMatrix<f64>,
}

/// A point of the search's space: the pairs' sums' circulations and symmetric parts, and the
/// trace couplings (their balancing flows not included).
#[derive(Clone)]
struct Moves {
    sums: Vec<Vec<PairSum>>,
    traces: Traces,
}

/// The variables of one pair's move: `u` (3), then `k`'s upper triangle (6).
const PAIR_VARIABLES: usize = 9;
const UPPER: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

impl<'a> Space<'a> {
    /// The space at `coupled` (`k` sensors in every frame), `s0` its gauged `S`: trace
    /// couplings between the frames an edge within one sensor joins.
    fn new(
        coupled: &'a Coupled,
        (x, sensors): (&'a [Rotation], &'a [Rotation]),
        k: usize,
        s0: DMatrix<f64>,
    ) -> Self {
        let per_frame = &coupled.layout.per_frame;
        let mut image = vec![(0, 0); x.len()];
        for (f, images) in per_frame.iter().enumerate() {
            for (i, &(_, a)) in images.iter().enumerate() {
                image[a] = (f, i);
            }
        }
        let edges = coupled.graph.edges().iter().map(|e| (e.i, e.j));
        let traces = Traces::between(edges, &image, k);
        Space {
            per_frame,
            sensors,
            k,
            x,
            tau: traces.torques(per_frame, x, sensors),
            traces,
            s0,
        }
    }

    fn zero(&self) -> Moves {
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
    fn with_flows(&self, moves: &Moves) -> Moves {
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
    /// [`MARGIN`], [`SEARCH_ROUNDS`], a stall ([`STALL`]), a rate too slow for the rounds left
    /// ([`too_slow`]) or the deadline: the moves,
    /// `lambda_min` and rounds when it became positive.
    fn bundle(
        &self,
        start: (Vec<f64>, DMatrix<f64>),
        deadline: Option<Deadline>,
    ) -> Option<(Moves, f64, usize)> {
        let lambda0 = start.0[0];
        let (mut at, mut lambda, mut vectors) = (self.zero(), lambda0, start.1);
        let mut s_at = self.s0.clone();
        let mut bundle = columns(&vectors, BUNDLE, None);
        let mut rho = 1.0 / lambda0.abs();
        let (mut rounds, mut history, mut nulls) = (0, vec![lambda0], 0);
        for round in 1..=SEARCH_ROUNDS {
            if deadline.is_some_and(|d| d.passed()) {
                break;
            }
            rounds = round;
            let (y, predicted) = self.model_step(&bundle, &s_at, rho, deadline)?;
            let candidate = added(&at, &self.moves(&y));
            let s_candidate = self.matrix(&candidate);
            let (values, new_vectors) = symmetric_eigen(&s_candidate)?;
            let serious = values[0] - lambda >= 0.1 * (predicted - lambda);
            bundle = columns(&vectors, BUNDLE, Some((&new_vectors, CANDIDATE)));
            if serious {
                (at, lambda, vectors, s_at) = (candidate, values[0], new_vectors, s_candidate);
                bundle = columns(&vectors, BUNDLE, None);
                rho *= 0.5;
            } else {
                rho *= 2.0;
            }
            crate::progress::emit(|| crate::progress::Event::Phase {
                phase: crate::progress::Phase::Certify,
                detail: format!(
                    "the couplings' search [H21]: round {round}, lambda_min(S) {lambda:.3e}"
                ),
            });
            if lambda >= MARGIN * lambda0.abs() {
                return Some((at, lambda, round));
            }
            history.push(lambda);
            if round > STALL_ROUNDS
                && lambda - history[round - STALL_ROUNDS] < STALL * lambda0.abs()
            {
                stopped(&format!(
                    "{STALL_ROUNDS} rounds gained less than {STALL} of |lambda_min|"
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
        (lambda > 0.0).then_some((at, lambda, rounds))
    }

    /// One round's model: `max t - rho |y|^2 / 2` s.t. `C + A(y) - t I` positive semidefinite
    /// (`C = V^T S(T) V`, `s_at = S(T)`, `A(y) = V^T D(y) V`), solved through its dual in the
    /// bundle's own dimension (`[H21]` "The model's dual"): `min <W, C> + |A*(W)|^2 / (2 rho)`
    /// over `W >= 0`, `tr W = 1` (`r (r + 1) / 2` variables, by Clarabel within the deadline),
    /// then `y = A*(W) / rho` and `t = lambda_min(C + A(y))`: `(y, t)`.
    fn model_step(
        &self,
        v: &DMatrix<f64>,
        s_at: &DMatrix<f64>,
        rho: f64,
        deadline: Option<Deadline>,
    ) -> Option<(Vec<f64>, f64)> {
        let r = v.ncols();
        let len = svec_len(r);
        let c = v.transpose() * s_at * v;
        // `svec(A(y)) = G y`: row `svec_index(i, j)` the weighted derivative of entry `(i, j)`
        let ny = self.per_frame.len() * self.k * (self.k - 1) / 2 * PAIR_VARIABLES
            + self.traces.pairs.len() * self.k;
        let mut g = DMatrix::zeros(len, ny);
        for row in 0..len {
            let (i, j) = svec_entry(row);
            let gradient = self.gradient(v.column(i).as_view(), v.column(j).as_view());
            for (k, d) in gradient.into_iter().enumerate() {
                g[(row, k)] = svec_weight(i, j) * d;
            }
        }
        let m = (&g * g.transpose()) / rho;
        let upper = (0..len).flat_map(|b| (0..=b).map(move |a| (a, b)));
        let p = csc(len, len, upper.map(|(a, b)| (a, b, m[(a, b)])).collect());
        let q: Vec<f64> = (0..len)
            .map(|row| {
                let (i, j) = svec_entry(row);
                svec_weight(i, j) * 0.5 * (c[(i, j)] + c[(j, i)])
            })
            .collect();
        // `1 - tr W = 0`, then `0 - (-w)` in the PSD cone
        let mut triplets: Vec<(usize, usize, f64)> =
            (0..r).map(|i| (0, svec_index(i, i), 1.0)).collect();
        triplets.extend((0..len).map(|row| (1 + row, row, -1.0)));
        let mut b = vec![0.0; 1 + len];
        b[0] = 1.0;
        let settings = SdpSettings {
            chordal_decomposition: false,
            time_limit_seconds: deadline.and_then(|d| d.left()).map(|l| l.max(0.0)),
            ..SdpSettings::default()
        };
        let solution = solve_quadratic_conic(
            (&p, &q),
            csc(1 + len, len, triplets),
            &b,
            &[Cone::Zero(1), Cone::Psd(r)],
            &settings,
            "none",
        )
        .ok()?;
        if !solution.status.converged() {
            return None;
        }
        let y: Vec<f64> = (g.transpose() * DVector::from_column_slice(&solution.x) / rho)
            .iter()
            .copied()
            .collect();
        let ay = &g * DVector::from_column_slice(&y);
        let model = DMatrix::from_fn(r, r, |i, j| {
            0.5 * (c[(i, j)] + c[(j, i)]) + ay[svec_index(i, j)] / svec_weight(i, j)
        });
        let t = crate::linalg::dense::symmetric_eigenvalues(&model)?[0];
        Some((y, t))
    }

    /// `S` with the moves' pseudo-edges: for a pair's sum `T` (`sum c N`), `S_s sym(T) S_s^T`
    /// and `S_t sym(T) S_t^T` on the diagonal blocks of `a = (f, s)`, `b = (f, t)`, `-S_t T
    /// S_s^T` in block `(b, a)` (the pseudo-edges' Laplacian less the multipliers they add).
    fn matrix(&self, moves: &Moves) -> DMatrix<f64> {
        let mut s = self.s0.clone();
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

/// The moves `a + b`.
fn added(a: &Moves, b: &Moves) -> Moves {
    Moves {
        sums: added_sums(&a.sums, &b.sums),
        traces: a.traces.added(&b.traces),
    }
}

/// `(i, j)`, `i <= j`, of `svec` row `row` (the inverse of [`svec_index`]).
fn svec_entry(row: usize) -> (usize, usize) {
    let mut j = 0;
    while (j + 1) * (j + 2) / 2 <= row {
        j += 1;
    }
    (row - j * (j + 1) / 2, j)
}

/// The sums `a + b`, pair by pair.
fn added_sums(a: &[Vec<PairSum>], b: &[Vec<PairSum>]) -> Vec<Vec<PairSum>> {
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

/// An orthonormal basis of the first `first` columns of `a` and, with `more`, the first columns
/// of another matrix (a thin QR; nearly dependent columns are kept: the model only needs a
/// spanning set of orthonormal columns, which Householder's `Q` is).
fn columns(a: &DMatrix<f64>, first: usize, more: Option<(&DMatrix<f64>, usize)>) -> DMatrix<f64> {
    let first = first.min(a.ncols());
    let extra = more.map_or(0, |(m, k)| k.min(m.ncols()));
    let mut stacked = DMatrix::zeros(a.nrows(), first + extra);
    stacked
        .columns_mut(0, first)
        .copy_from(&a.columns(0, first));
    if let Some((m, _)) = more {
        stacked
            .columns_mut(first, extra)
            .copy_from(&m.columns(0, extra));
    }
    stacked.qr().q()
}

#[cfg(test)]
mod tests {
    use super::search;
    use crate::certify::multiple::multipliers::{
        certificate_matrix, multipliers, stationarity_residual,
    };
    use crate::certify::rig::couplings::{couple, coupled};
    use crate::multiple::MultipleProblem;
    use crate::rig::{RigScene, RigSettings, polish_passes, solve_rig};
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
        let space = super::Space::new(&c, (&x, &sensors), 3, nalgebra::DMatrix::zeros(n, n));
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
            let actual = sym.component_mul(&space.matrix(&moves)).sum();
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
        let space = super::Space::new(&c, (&x, &sensors), 3, &s0 + s0.transpose());
        let v = nalgebra::DMatrix::from_fn(n, 8, |_, _| rng.random::<f64>() - 0.5)
            .qr()
            .q();
        let rho = 0.3;
        let value = |y: &[f64]| {
            let m = v.transpose() * space.matrix(&space.moves(y)) * &v;
            let t = crate::linalg::dense::symmetric_eigenvalues(&m).unwrap()[0];
            (t, t - 0.5 * rho * y.iter().map(|a| a * a).sum::<f64>())
        };
        let (y, t) = space.model_step(&v, &space.s0, rho, None).unwrap();
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

    /// The criticality diagnosis: a critical point always searches; a residual whose deficit
    /// `3 rho^2 / gap` exceeds the mean eigenvalue does not; the boundary is the mean itself.
    #[test]
    fn a_point_far_from_critical_is_not_searched() {
        // 10 images: mean eigenvalue tr / 27
        assert_eq!(super::hopeless(0.0, 27.0, 10, 1e-6), None);
        assert!(super::hopeless(1e-2, 27.0, 10, 1e-6).is_some());
        // 3 rho^2 / gap = 0.3 against a mean of 1
        assert_eq!(super::hopeless(1e-4, 27.0, 10, 1e-7), None);
        assert!(super::hopeless(1e-4, 27.0, 10, 2e-8).is_some());
        assert_eq!(super::hopeless(1.0, 27.0, 10, 0.0), None);
    }

    /// `lambda_min` of the augmented graph's `S` off the gauge, from its own multipliers and
    /// `certificate_matrix` (not from the search's formula), the gauge's directions lifted by
    /// `10^3 ||S||_F`.
    fn dense_min(graph: &MultipleProblem, x: &[Rotation]) -> f64 {
        let lambdas = multipliers(graph, x).unwrap();
        let mut s = crate::linalg::cholesky::to_dense(
            certificate_matrix(graph, &lambdas).unwrap().as_ref(),
        );
        let lift = 1e3 * s.norm() / x.len() as f64;
        for (a, xa) in x.iter().enumerate() {
            for (b, xb) in x.iter().enumerate() {
                let mut view = s.fixed_view_mut::<3, 3>(3 * a, 3 * b);
                view += lift * xa.matrix() * xb.matrix().transpose();
            }
        }
        crate::linalg::dense::symmetric_eigenvalues(&(0.5 * (&s + s.transpose()))).unwrap()[0]
    }

    /// A 30-frame rig of 4 estimated sensors with each sensor's pairs within 10 frames (`[H21]`
    /// "The search"), with information matrices and with scalar weights: the least-norm couplings leave `S` indefinite; the search's sums make it
    /// positive definite (checked on the augmented graph rebuilt from them, with its own
    /// multipliers), keep the estimate critical and sum to zero over the frames (no charge).
    #[test]
    fn the_search_makes_s_positive_definite_where_the_least_norm_couplings_do_not() {
        for scalar in [false, true] {
            let scene = RigScene {
                frames: 30,
                sensors: 4,
                noise_sigma: 0.01,
                anisotropy: 9.0,
                extra_edge_span: 10,
                seed: 1,
                ..Default::default()
            };
            let (p, _) = scene.generate();
            // with scalar weights `tr(H) / 3`: the isotropic rung's graph
            let p = if scalar { p.scalar() } else { p };
            let s = solve_rig(&p, &RigSettings::default()).unwrap();
            let (frames, sensors) = polish_passes(&p, (s.frames, s.sensors), 10, None).unwrap();
            let c = couple(&p, &frames, &sensors, u64::MAX).unwrap().unwrap();
            let x = p.image_rotations(&frames, &sensors);
            let before = dense_min(&c.graph, &x);
            assert!(before < 0.0, "{before}");
            let limits = super::Limits {
                deadline: None,
                max_bytes: u64::MAX,
                gap: 1e-6 * p.cost(&frames, &sensors),
            };
            let found = search(&c, (&x, &sensors), limits)
                .unwrap()
                .expect("a positive lambda_min");
            assert!(
                (found.start - before).abs() <= 1e-6 * before.abs(),
                "{} {before}",
                found.start
            );
            // the trace couplings moved (`[H21]` "Trace couplings")
            assert!(found.traces.mu.iter().flatten().any(|m| m.abs() > 0.0));
            let again = coupled(
                &p.image_graph().unwrap(),
                c.layout.clone(),
                (found.sums, found.traces),
                &sensors,
            )
            .unwrap();
            let after = dense_min(&again.graph, &x);
            assert!(after > 0.0, "{before} -> {after}");
            assert!(
                (after - found.reached).abs() <= 1e-6 * before.abs(),
                "{after} {}",
                found.reached
            );
            let critical = stationarity_residual(&again.graph, &x).unwrap();
            let least_norm = stationarity_residual(&c.graph, &x).unwrap();
            assert!(
                critical <= 10.0 * least_norm + 1e-9 * again.offset,
                "{critical} {least_norm}"
            );
            assert!(
                again.charge <= 10.0 * c.charge + 1e-9 * again.offset,
                "{} {}",
                again.charge,
                c.charge
            );
        }
    }
}
