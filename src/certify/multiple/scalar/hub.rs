//! The scalar comparison `[D13]` with a **hub** (`paper-notes/gravity.md` `[G13]`): an
//! isotropic view graph on nodes `0..h` plus one node `h` (soft gravity priors' world node,
//! `[G10]`; proven at `R_h = I`, the point turned by `R_h^T` otherwise) joined to some of them
//! by *spokes*, edges of information `W diag(1, 1, 0)`, which see only the hub's third
//! coordinate. Their certificate matrix has
//! two rows of the hub that no edge touches, so the block comparison and the grounded bound
//! cannot prove it, and the `3n` factor it leaves fills on expander view graphs (10^4 cameras:
//! 7.5 s). Here `lambda_min(S)` is proven from two scalar factorisations instead: the view
//! graph's Laplacian for the first two coordinates of every camera, the same with the hub and
//! its spokes for the third.
//!
//! With `D = blkdiag(R_i, I)`, `M = D^T S D`, a spoke `(h, c)` of weight `W` (`omega = 2W`) and
//! direction `g = F e_3` has `M_hc = -omega e_3 p^T`, `p = R_c^T g`, exactly; so
//! `x^T M x = [the view graph's terms with Lambda''] + sum omega (z - p^T x_c)^2
//!           - x_h^T sym(Lambda_h) x_h`,
//! `Lambda''_c = Lambda_c - omega e_3 e_3^T + omega g g^T` (`z` the hub's third coordinate).
//! Each spoke keeps `W (z - x_c3)^2` and charges `omega |p - e_3|^2 |x_c|^2` (second order in
//! the prior's residual); the hub's rows 1 and 2 (`x_D`) and `Lambda_h` are charged to `z` and
//! to `x_D`. Steps 3 to 5 of `[D13]` then run per coordinate slice, the third with the hub's
//! node; `v0^T M v0` is the net torque (the cameras' blocks and the hub's third row), zero by
//! the gauge symmetry up to rounding.

use super::analysis::{ScalarAnalysis, fro};
use super::charges::{edge_charges, orthogonality_defect};
use super::inertia::prove_inertia;
use super::residuals::node_residuals;
use super::split::{PencilWeights, kappa};
use super::{ScalarComparison, ScalarFailure};
use crate::error::Result;
use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma};
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::Rotation;
use nalgebra::{Matrix3, Vector3};

/// One spoke: its weight `W` (information `W diag(1, 1, 0)`) and direction `g = F e_3`.
#[derive(Debug, Clone, Copy)]
struct Spoke {
    weight: f64,
    direction: Vector3<f64>,
}

/// A problem of hub shape, with both scalar patterns analysed.
pub(in crate::certify::multiple) struct HubGraph {
    /// The view graph on the nodes other than the hub (the last node), each edge's weight
    /// its information's `w` (`H = w I`).
    cameras: MultipleProblem,
    /// Per camera, its spoke.
    spokes: Vec<Option<Spoke>>,
    /// The analysis of `cameras` (coordinates 1 and 2).
    camera_analysis: ScalarAnalysis,
    /// The analysis of the whole problem's graph (coordinate 3, hub included).
    hub_analysis: ScalarAnalysis,
}

/// The spokes and the isotropic edges of `problem` when it has hub shape: each edge either
/// `H = w I` between nodes other than the last or `(hub, c)` with `H = W diag(1, 1, 0)` (the
/// hub the last node), at most one spoke per node; `None` otherwise.
fn hub_shape(problem: &MultipleProblem) -> Option<(Vec<Edge>, Vec<Option<Spoke>>)> {
    let info = problem.information()?;
    let h = problem.num_rotations().checked_sub(1)?;
    let (mut graph, mut spokes) = (Vec::new(), vec![None; h]);
    for (e, info) in problem.edges().iter().zip(info) {
        let m = info.matrix();
        let w = m[(0, 0)];
        let off_diagonal = (0..3).all(|a| (0..3).all(|b| a == b || m[(a, b)] == 0.0));
        if !(off_diagonal && w > 0.0 && w.is_finite() && m[(1, 1)] == w) {
            return None;
        }
        if e.i == h && e.j != h && m[(2, 2)] == 0.0 {
            let direction = e.rotation.matrix().column(2).into_owned();
            let slot = spokes.get_mut(e.j)?;
            if slot
                .replace(Spoke {
                    weight: w,
                    direction,
                })
                .is_some()
            {
                return None;
            }
        } else if e.i != h && e.j != h && m[(2, 2)] == w {
            graph.push(Edge { weight: w, ..*e });
        } else {
            return None;
        }
    }
    spokes
        .iter()
        .any(Option::is_some)
        .then_some((graph, spokes))
}

impl HubGraph {
    /// The hub shape of `problem` with both patterns analysed: `Ok(None)` when `problem` has no
    /// hub shape, `Ok(Some(Err(predicted)))` when a factor is predicted above `max_values`.
    pub(in crate::certify::multiple) fn new(
        problem: &MultipleProblem,
        max_values: usize,
    ) -> Result<Option<std::result::Result<Self, usize>>> {
        let Some((graph, spokes)) = hub_shape(problem) else {
            return Ok(None);
        };
        let Ok(cameras) = MultipleProblem::new(spokes.len(), graph) else {
            return Ok(None);
        };
        let camera_analysis = match ScalarAnalysis::new(&cameras, max_values)? {
            Ok(a) => a,
            Err(predicted) => return Ok(Some(Err(predicted))),
        };
        let hub_analysis = match ScalarAnalysis::new(problem, max_values)? {
            Ok(a) => a,
            Err(predicted) => return Ok(Some(Err(predicted))),
        };
        Ok(Some(Ok(HubGraph {
            cameras,
            spokes,
            camera_analysis,
            hub_analysis,
        })))
    }

    /// The two analyses (coordinates 1 and 2, then 3).
    pub(in crate::certify::multiple) fn analyses(&self) -> [&ScalarAnalysis; 2] {
        [&self.camera_analysis, &self.hub_analysis]
    }

    /// `lambda_min(S) >= mu` for the multipliers `lambdas` of `problem` (the one this hub
    /// shape was found in) at `rotations`, with the comparison's `target` as in `[D13]`.
    pub(in crate::certify::multiple) fn compare(
        &self,
        problem: &MultipleProblem,
        rotations: &[Rotation],
        lambdas: &[Matrix3<f64>],
        target: f64,
    ) -> std::result::Result<ScalarComparison, ScalarFailure> {
        let h = self.spokes.len();
        if rotations.len() != h + 1 || lambdas.len() != h + 1 {
            return Err(ScalarFailure::Numerical);
        }
        let turned = hub_at_identity(rotations);
        let rotations = turned.as_deref().unwrap_or(rotations);
        let t_max = orthogonality_defect(rotations)?;
        let c = self.comparison(problem, rotations, lambdas, target)?;
        let rho = self.residuals(&rotations[..h], lambdas, &c.deg_n[..h]);
        let k0 = kappa(&c.delta, 0.0).max(kappa(&c.with_hub, 0.0));
        let zeta = if target > 0.0 && target.is_finite() {
            (4.0 * rho.live * rho.live * k0 * k0 / target).max(1e-12 * c.d_max)
        } else {
            1e-12 * c.d_max
        };
        let pencils = self.pencils(problem, &c, zeta)?;
        let mu_m = cross_terms(h + 1, pencils.kappa, pencils.zeta_free, &rho, c.dead);
        let mu = super::charges::ostrowski(mu_m, t_max).ok_or(ScalarFailure::Numerical)?;
        Ok(ScalarComparison {
            verified_min_eigenvalue: mu,
            max_delta: c.with_hub.iter().copied().fold(0.0, f64::max),
            second_order_edges: c.second_order_edges,
            dropped_edges: 0,
            parts: 2,
            shared_edges: 0,
            split_defect: 0.0,
            zeta,
            headroom: pencils.headroom,
            backward_error: pencils.backward_error,
            factor_nonzeros: self.camera_analysis.factor_len() + self.hub_analysis.factor_len(),
            kappa: pencils.kappa,
            residual_bound: rho.live.hypot(rho.dead),
            deflated: 0,
        })
    }

    /// Step 2 with the hub: `M >= sum_k y_k^T (L_k - diag(delta_k)) y_k - dead |x_D|^2`, the
    /// first two coordinates' `L_k` the view graph's kept weights, the third's with the
    /// spokes' `W` and the hub's node.
    fn comparison(
        &self,
        problem: &MultipleProblem,
        rotations: &[Rotation],
        lambdas: &[Matrix3<f64>],
        target: f64,
    ) -> std::result::Result<HubCharges, ScalarFailure> {
        let h = self.spokes.len();
        let cams = &rotations[..h];
        let (shifted, spoke_charges) = self.spoke_terms(cams, &lambdas[..h]);
        let analysis = &self.camera_analysis;
        let c = edge_charges(
            &self.cameras,
            cams,
            &shifted,
            &analysis.copies,
            analysis.beta,
        )?;
        let mut delta = c.delta;
        for (d, s) in delta.iter_mut().zip(&spoke_charges) {
            *d = (*d + s) * (1.0 + 4.0 * UNIT_ROUNDOFF);
        }
        let hub = HubBlock::new(&lambdas[h], target);
        let floor = 1e-14 * c.d_max.max(f64::MIN_POSITIVE);
        let mut with_hub = delta.clone();
        with_hub.push(hub.charge.max(floor));
        let kept = self.kept_weights(problem, &c.reduced);
        Ok(HubCharges {
            delta,
            with_hub,
            dead: hub.dead,
            reduced: c.reduced,
            kept,
            deg_n: degrees(problem),
            d_max: c.d_max,
            second_order_edges: c.second_order_edges,
        })
    }

    /// Steps 4 and 5 per coordinate slice: "exactly one negative eigenvalue" of the view
    /// graph's `L - diag(delta + zeta)` and of the third slice's, with the hub.
    fn pencils(
        &self,
        problem: &MultipleProblem,
        c: &HubCharges,
        zeta: f64,
    ) -> std::result::Result<Pencils, ScalarFailure> {
        let h = self.spokes.len();
        let slices = [
            (
                &self.camera_analysis,
                &self.cameras,
                &c.reduced,
                &c.delta,
                &c.deg_n[..h],
            ),
            (
                &self.hub_analysis,
                problem,
                &c.kept,
                &c.with_hub,
                &c.deg_n[..],
            ),
        ];
        let mut out = Pencils {
            headroom: 0.0,
            backward_error: 0.0,
            zeta_free: f64::INFINITY,
            kappa: 0.0,
        };
        for (analysis, graph, reduced, delta, deg_n) in slices {
            let pencil = pencil(delta, zeta);
            let (hr, be) = prove_inertia(analysis, graph, reduced, &pencil, deg_n, c.d_max)?;
            out.headroom = out.headroom.max(hr);
            out.backward_error = out.backward_error.max(be);
            out.zeta_free = out.zeta_free.min(pencil.zeta_free);
            out.kappa = out.kappa.max(kappa(delta, zeta));
        }
        Ok(out)
    }

    /// Per camera, `fl(Lambda''_c)` and the charge of its spoke: `omega |p - e_3|^2` (the
    /// spoke's second-order split) plus the rounding of `Lambda''_c` (`3 gamma_4 (|Lambda|max +
    /// 2 omega)` in the 2-norm, conjugated by `R_c`: `(1 + t)^2 <= 1.01`).
    fn spoke_terms(
        &self,
        cams: &[Rotation],
        lambdas: &[Matrix3<f64>],
    ) -> (Vec<Matrix3<f64>>, Vec<f64>) {
        let mut shifted = lambdas.to_vec();
        let mut charges = vec![0.0; cams.len()];
        for (c, s) in self.spokes.iter().enumerate() {
            let Some(s) = s else { continue };
            let omega = 2.0 * s.weight;
            let l = &mut shifted[c];
            let rounding = 3.0 * gamma(4) * (l.amax() + 2.0 * omega) * 1.01;
            l[(2, 2)] -= omega;
            *l += (s.direction * s.direction.transpose()) * omega;
            let q = tilt_bound(&cams[c], &s.direction);
            charges[c] = (omega * q * q + rounding) * (1.0 + 4.0 * UNIT_ROUNDOFF);
        }
        (shifted, charges)
    }

    /// Bounds on `M v0` (`v0`: the gauge columns, with the hub's third coordinate in the
    /// third and its first two coordinates 0): the Frobenius norms of its rows other than the
    /// hub's first two (`live`) and of those two (`dead`), and `rho0 >= ||v0^T M v0||_F`
    /// (the sum of the cameras' blocks and the hub's third row: the net torque, zero by the
    /// gauge symmetry up to rounding, wherever the estimate is).
    fn residuals(&self, cams: &[Rotation], lambdas: &[Matrix3<f64>], deg_n: &[usize]) -> Residuals {
        let h = cams.len();
        let extra = |c: usize| -> Option<(Matrix3<f64>, f64)> {
            let s = self.spokes[c]?;
            let omega = 2.0 * s.weight;
            // omega (e_3 e_3^T R_c - g e_3^T): the spoke's diagonal and its coupling to z
            let mut e = Matrix3::zeros();
            e.set_row(2, &(cams[c].matrix().row(2) * omega));
            let column = e.column(2) - s.direction * omega;
            e.set_column(2, &column);
            Some((e, gamma(4) * omega * 2.1))
        };
        let nodes = node_residuals(&self.cameras, cams, &lambdas[..h], deg_n, &extra);
        let row = self.hub_row(cams, &lambdas[h]);
        let g = gamma(h + 8);
        let live = (nodes.rho1_sq + row.bound.norm_squared()).sqrt() * (1.0 + g);
        let mut sum = nodes.sum;
        let sum_row = sum.row(2) + row.value.transpose();
        sum.set_row(2, &sum_row);
        let rho0 = (fro(&sum)
            + nodes.err_sum
            + (row.bound - row.value.abs()).norm()
            + g * (nodes.abs_sum + row.value.norm()))
            * (1.0 + 8.0 * UNIT_ROUNDOFF);
        Residuals {
            live,
            rho0,
            dead: HubBlock::new(&lambdas[h], 0.0).coupling,
        }
    }

    /// The hub's third row of `M v0`: `-sum omega q_c^T - Lambda_h(3,3) e_3^T`, `q_c = R_c^T g_c
    /// - e_3` (floating point, and each entry's magnitude rounded up by its error bound).
    fn hub_row(&self, cams: &[Rotation], lambda: &Matrix3<f64>) -> HubRow {
        let mut value = Vector3::zeros();
        let (mut magnitude, mut err) = (Vector3::zeros(), 0.0f64);
        for (c, s) in self.spokes.iter().enumerate() {
            let Some(s) = s else { continue };
            let omega = 2.0 * s.weight;
            let q = cams[c].matrix().transpose() * s.direction - Vector3::z();
            value -= q * omega;
            magnitude += q.abs() * omega;
            err += omega * gamma(4) * 2.0;
        }
        let l33 = lambda[(2, 2)];
        value[2] -= l33;
        magnitude[2] += l33.abs();
        let g = gamma(cams.len() + 3);
        let bound = value.abs() + Vector3::repeat(err * (1.0 + g)) + magnitude * g;
        HubRow { value, bound }
    }

    /// The weights of the third slice's Laplacian, in `problem`'s edge order: each view-graph
    /// edge's kept weight (the cameras' comparison), each spoke's `W = omega / 2`.
    fn kept_weights(&self, problem: &MultipleProblem, reduced: &[f64]) -> Vec<f64> {
        let h = self.spokes.len();
        let mut graph = reduced.iter();
        problem
            .edges()
            .iter()
            .map(|e| match (e.i == h, self.spokes.get(e.j)) {
                (true, Some(Some(s))) => s.weight,
                _ => graph.next().copied().unwrap_or(0.0),
            })
            .collect()
    }
}

/// Step 2's comparison with the hub ([`HubGraph::comparison`]).
struct HubCharges {
    /// The cameras' charges (every coordinate).
    delta: Vec<f64>,
    /// The same and the hub's (its third coordinate).
    with_hub: Vec<f64>,
    /// The charge of the hub's first two coordinates.
    dead: f64,
    /// The view graph's kept weights (its edge order).
    reduced: Vec<f64>,
    /// The third slice's kept weights (the problem's edge order).
    kept: Vec<f64>,
    /// Each node's number of edges in the problem (hub last).
    deg_n: Vec<usize>,
    /// The view graph's largest weighted degree.
    d_max: f64,
    second_order_edges: usize,
}

/// What the two slices' inertia proofs give ([`HubGraph::pencils`]).
struct Pencils {
    headroom: f64,
    backward_error: f64,
    zeta_free: f64,
    kappa: f64,
}

/// What step 3 needs of `M v0` ([`HubGraph::residuals`]).
struct Residuals {
    live: f64,
    rho0: f64,
    dead: f64,
}

/// The hub's third row of `M v0` and entrywise upper bounds on its magnitudes.
struct HubRow {
    value: Vector3<f64>,
    bound: Vector3<f64>,
}

/// The hub's block `-sym(Lambda_h)` seen from its coordinates: rows 1 and 2 meet no edge.
struct HubBlock {
    /// `|c|`, `c` = `sym(Lambda_h)`'s first two entries of the third column, rounded up.
    coupling: f64,
    /// The charge of `z`: `|Lambda_h(3,3)| + |c| / t`.
    charge: f64,
    /// The charge of the first two coordinates: `||B||_F + |c| t`, `B` their `2 x 2` block.
    dead: f64,
}

impl HubBlock {
    /// The charges with `2 |z c^T x_D| <= |c| (t |x_D|^2 + z^2 / t)`, `t` such that `|c| t` is
    /// at most a sixteenth of `target` (the first two coordinates have no other term to
    /// absorb it; at most 1).
    fn new(lambda: &Matrix3<f64>, target: f64) -> Self {
        let u = UNIT_ROUNDOFF;
        let sym = 0.5 * (lambda + lambda.transpose());
        let coupling = sym[(0, 2)].hypot(sym[(1, 2)]) * (1.0 + 4.0 * u);
        let b = sym.fixed_view::<2, 2>(0, 0).norm() * (1.0 + 4.0 * u);
        let t = if coupling > 0.0 {
            (target / (16.0 * coupling)).clamp(f64::MIN_POSITIVE.sqrt(), 1.0)
        } else {
            1.0
        };
        HubBlock {
            coupling,
            charge: (sym[(2, 2)].abs() + coupling / t) * (1.0 + 4.0 * u),
            dead: (b + coupling * t) * (1.0 + 4.0 * u),
        }
    }
}

/// The congruence `D` with the hub's block exactly `I` (`None`: it is already): `S` does not
/// depend on the gauge (`Lambda` is the same at `R_i Q`), and the comparison holds for any `D`
/// (step 1 charges its orthogonality defect), so a point whose hub is turned (a refinement's)
/// is proven at `R_c R_h^T` and `I`.
fn hub_at_identity(rotations: &[Rotation]) -> Option<Vec<Rotation>> {
    let (hub, cams) = rotations.split_last()?;
    if hub.matrix() == &Matrix3::identity() {
        return None;
    }
    let back = hub.inverse();
    let mut turned: Vec<Rotation> = cams.iter().map(|r| r * back).collect();
    turned.push(Rotation::identity());
    Some(turned)
}

/// `|p - e_3|` rounded up, `p = R^T g` (entries of the product err by `gamma_3 1.8`).
fn tilt_bound(r: &Rotation, g: &Vector3<f64>) -> f64 {
    let q = r.matrix().transpose() * g - Vector3::z();
    q.norm() * (1.0 + 4.0 * UNIT_ROUNDOFF) + 3.0f64.sqrt() * gamma(4) * 2.0
}

/// Each node's number of edges in `problem`.
fn degrees(problem: &MultipleProblem) -> Vec<usize> {
    let mut d = vec![0usize; problem.num_rotations()];
    for e in problem.edges() {
        d[e.i] += 1;
        d[e.j] += 1;
    }
    d
}

/// Step 4's weights `delta + zeta` of one slice (no split).
fn pencil(delta: &[f64], zeta: f64) -> PencilWeights {
    let u = UNIT_ROUNDOFF;
    let weights: Vec<f64> = delta.iter().map(|d| d + zeta).collect();
    let w_max = weights.iter().copied().fold(0.0, f64::max);
    PencilWeights {
        weights,
        shares: Vec::new(),
        zeta,
        defect: 0.0,
        zeta_free: (zeta - 2.0 * u * w_max) * (1.0 - 4.0 * u),
    }
}

/// `lambda_min(M)` from the split `x = v0 a + x1` (`[G13]`): the better of the plain bound and
/// the one whose cross terms `zeta_free` absorbs, less the hub's first two coordinates' charge
/// `dead` (their rows of `M v0`, `rho.dead`, charged `2 rho.dead |a| |x_D| <= rho.dead (|a|^2 /
/// kappa + kappa |x_D|^2)`).
fn cross_terms(nodes: usize, kappa: f64, zeta_free: f64, rho: &Residuals, dead: f64) -> f64 {
    let root = (nodes as f64).sqrt();
    let rho1 = rho.live.hypot(rho.dead) * (1.0 + 4.0 * UNIT_ROUNDOFF);
    let plain = -(2.0 * kappa * (1.0 + root * kappa) * rho1 + kappa * kappa * rho.rho0) - dead;
    let absorbed = if zeta_free > 0.0 {
        -((rho.live * rho.live / zeta_free + rho.rho0) * kappa * kappa
            + 2.0 * rho.dead * kappa
            + dead)
    } else {
        f64::NEG_INFINITY
    };
    plain.max(absorbed) * (1.0 + 1e-10)
}

#[cfg(test)]
#[path = "hub_tests.rs"]
mod tests;
