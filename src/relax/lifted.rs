//! The rank-`p` Burer-Monteiro factorisation of the multiple-averaging SDP
//! (`paper-notes/certificates.md` `[D11]`): minimise `F(Y) = tr(Y^T Q Y)` over `Y = [Y_1; ...;
//! Y_n]`, each `Y_i` a `3 x p` matrix with orthonormal rows (`Y_i Y_i^T = I_3`), by a Riemannian
//! trust-region method with truncated conjugate gradients (Absil, Baker & Gallivan, "Trust-region
//! methods on Riemannian manifolds", FoCM 2007; the solver of SE-Sync and Shonan averaging).
//!
//! With `Lambda_i = sym((Q Y)_i Y_i^T)` and `S = Q - blkdiag(Lambda)`:
//! - the tangent space at `Y` is `{Z : sym(Z_i Y_i^T) = 0}`, its projection
//!   `P_Y(Z)_i = Z_i - sym(Z_i Y_i^T) Y_i`;
//! - the Riemannian gradient is `grad F = 2 S Y` (`= P_Y(2 Q Y)`);
//! - the Riemannian Hessian is `Hess F(Y)[Z] = P_Y(2 S Z)`;
//! - the retraction is the polar factor of each block, `(M M^T)^{-1/2} M`.
//!
//! Nothing here is a bound: the certificate verifies the final point's multipliers exactly like
//! any other ([`crate::certify::multiple::lower_bound_from_multipliers`]). The solver reports
//! why it stopped.

use crate::multiple::MultipleProblem;
use nalgebra::{Matrix3, Matrix3xX, SymmetricEigen};
use serde::{Deserialize, Serialize};

/// One node's block of a lifted point: `3 x p`, orthonormal rows.
pub type Block = Matrix3xX<f64>;

/// `(Q Y)_i` for every node (edge-wise, as `[D3]`; anisotropic edges: `[A2]`).
pub fn lifted_qy(problem: &MultipleProblem, y: &[Block]) -> Vec<Block> {
    let p = y.first().map_or(3, |b| b.ncols());
    let mut qy = vec![Block::zeros(p); y.len()];
    if let Some(info) = problem.information() {
        // node i: 2M Y_i - 2M R_ij^T Y_j; node j: 2M Y_j - 2 R_ij M Y_i
        for (e, h) in problem.edges().iter().zip(info) {
            let (m2, r) = (h.twice_chordal_matrix(), e.rotation.matrix());
            let (yi, yj) = (&y[e.i], &y[e.j]);
            qy[e.i] += m2 * (yi - r.transpose() * yj);
            qy[e.j] += m2 * yj - r * (m2 * yi);
        }
        return qy;
    }
    for e in problem.edges() {
        let r = e.rotation.matrix();
        let (yi, yj) = (&y[e.i], &y[e.j]);
        qy[e.i] += e.weight * (yi - r.transpose() * yj);
        qy[e.j] += e.weight * (yj - r * yi);
    }
    qy
}

/// `F(Y) = sum_e w ||Y_j - R_ij Y_i||_F^2` (anisotropic edges: `tr(Y^T Q Y)`, `[A2]`).
pub fn lifted_cost(problem: &MultipleProblem, y: &[Block]) -> f64 {
    if problem.is_anisotropic() {
        return lifted_qy(problem, y)
            .iter()
            .zip(y)
            .map(|(q, yi)| q.dot(yi))
            .sum();
    }
    problem
        .edges()
        .iter()
        .map(|e| e.weight * (&y[e.j] - e.rotation.matrix() * &y[e.i]).norm_squared())
        .sum()
}

/// The multipliers `Lambda_i = sym((Q Y)_i Y_i^T)` of a lifted point.
pub fn lifted_multipliers(problem: &MultipleProblem, y: &[Block]) -> Vec<Matrix3<f64>> {
    lifted_qy(problem, y)
        .iter()
        .zip(y)
        .map(|(g, yi)| sym(&(g * yi.transpose())))
        .collect()
}

fn sym(m: &Matrix3<f64>) -> Matrix3<f64> {
    0.5 * (m + m.transpose())
}

/// `2 S Z` with `S = Q - blkdiag(Lambda)`: `2 ((Q Z)_i - Lambda_i Z_i)`.
fn twice_s_times(problem: &MultipleProblem, lambdas: &[Matrix3<f64>], z: &[Block]) -> Vec<Block> {
    let mut qz = lifted_qy(problem, z);
    for ((q, l), zi) in qz.iter_mut().zip(lambdas).zip(z) {
        *q -= l * zi;
        *q *= 2.0;
    }
    qz
}

/// The tangent projection `P_Y(Z)_i = Z_i - sym(Z_i Y_i^T) Y_i`.
fn project(y: &[Block], z: &mut [Block]) {
    for (zi, yi) in z.iter_mut().zip(y) {
        let s = sym(&(&*zi * yi.transpose()));
        *zi -= s * yi;
    }
}

/// `<A, B> = sum_i tr(A_i^T B_i)`.
fn inner(a: &[Block], b: &[Block]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

/// `a + t b`, block-wise.
fn axpy(a: &[Block], t: f64, b: &[Block]) -> Vec<Block> {
    a.iter().zip(b).map(|(x, y)| x + t * y).collect()
}

/// Polar retraction of one block: `(M M^T)^{-1/2} M` (orthonormal rows); `None` when `M` has
/// rank below 3 (or is not finite).
pub fn polar(m: &Block) -> Option<Block> {
    let g: Matrix3<f64> = m * m.transpose();
    let eig = SymmetricEigen::new(g);
    if eig.eigenvalues.iter().any(|&v| v.is_nan() || v <= 1e-300) {
        return None;
    }
    let d = Matrix3::from_diagonal(&eig.eigenvalues.map(|v| 1.0 / v.sqrt()));
    let inv_sqrt = eig.eigenvectors * d * eig.eigenvectors.transpose();
    Some(inv_sqrt * m)
}

/// `R_Y(Z)`: the polar retraction of `Y + Z`, block-wise.
pub fn retract(y: &[Block], z: &[Block]) -> Option<Vec<Block>> {
    y.iter().zip(z).map(|(yi, zi)| polar(&(yi + zi))).collect()
}

/// Settings of the trust-region solver.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TrustRegionSettings {
    /// Outer (trust-region) iterations at most.
    pub max_iterations: usize,
    /// Conjugate-gradient steps per subproblem at most.
    pub max_inner: usize,
    /// Converged when `||grad F|| <= gradient_tolerance (w_min + F)` (`w_min` the smallest weight: invariant under scaling every weight).
    pub gradient_tolerance: f64,
    /// Converged when a step decreases `F` by less than this times `w_min + F` (twice running).
    pub decrease_tolerance: f64,
}

impl Default for TrustRegionSettings {
    fn default() -> Self {
        TrustRegionSettings {
            max_iterations: 500,
            max_inner: 200,
            gradient_tolerance: 1e-9,
            decrease_tolerance: 1e-14,
        }
    }
}

/// Why the trust-region solver stopped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum TrustRegionStop {
    /// The gradient norm met its tolerance.
    Gradient {
        /// `||grad F|| / (w_min + F)`.
        value: f64,
    },
    /// Two accepted steps in a row decreased `F` by less than the tolerance.
    Decrease {
        /// The last relative decrease.
        value: f64,
    },
    /// The iteration limit.
    IterationLimit {
        /// `||grad F|| / (w_min + F)` left.
        value: f64,
    },
    /// The trust region shrank below rounding: no representable progress.
    Radius {
        /// `||grad F|| / (w_min + F)` left.
        value: f64,
    },
    /// The time limit passed (checked before each iteration: one iteration past it at most).
    TimeLimit {
        /// `||grad F|| / (w_min + F)` left.
        value: f64,
    },
}

/// A local minimiser of the rank-`p` problem found by [`trust_region`].
#[derive(Debug, Clone, PartialEq)]
pub struct TrustRegionResult {
    /// The point.
    pub y: Vec<Block>,
    /// `F(y)`.
    pub cost: f64,
    /// Outer iterations.
    pub iterations: usize,
    /// Hessian-vector products (the work).
    pub hessian_products: usize,
    /// Why it stopped.
    pub stop: TrustRegionStop,
}

/// The truncated conjugate-gradient solution of the trust-region subproblem
/// `min <g, eta> + <eta, H eta> / 2`, `|eta| <= radius` (Steihaug-Toint): stops at the boundary,
/// on negative curvature, or when the residual falls below `|g| min(|g|^0.5, 0.1)`. Returns the
/// step, its model decrease and the Hessian products used.
fn truncated_cg(
    hess: &dyn Fn(&[Block]) -> Vec<Block>,
    g: &[Block],
    radius: f64,
    max_inner: usize,
) -> (Vec<Block>, f64, usize) {
    let zero: Vec<Block> = g.iter().map(|b| Block::zeros(b.ncols())).collect();
    let (mut eta, mut h_eta) = (zero.clone(), zero);
    let mut r = g.to_vec();
    let mut delta: Vec<Block> = r.iter().map(|b| -b).collect();
    let r0 = inner(&r, &r).sqrt();
    let target = r0 * r0.sqrt().min(0.1);
    let mut products = 0;
    for _ in 0..max_inner {
        let hd = hess(&delta);
        products += 1;
        let dhd = inner(&delta, &hd);
        let rr = inner(&r, &r);
        let alpha = rr / dhd;
        let next = axpy(&eta, alpha, &delta);
        if dhd <= 0.0 || inner(&next, &next).sqrt() >= radius {
            // to the boundary along delta: |eta + tau delta| = radius
            let (ee, ed, dd) = (
                inner(&eta, &eta),
                inner(&eta, &delta),
                inner(&delta, &delta),
            );
            let tau = (-ed + (ed * ed + dd * (radius * radius - ee)).max(0.0).sqrt()) / dd;
            eta = axpy(&eta, tau, &delta);
            h_eta = axpy(&h_eta, tau, &hd);
            break;
        }
        eta = next;
        h_eta = axpy(&h_eta, alpha, &hd);
        r = axpy(&r, alpha, &hd);
        let rr_next = inner(&r, &r);
        if rr_next.sqrt() <= target {
            break;
        }
        delta = axpy(
            &r.iter().map(|b| -b).collect::<Vec<_>>(),
            rr_next / rr,
            &delta,
        );
    }
    let model = -(inner(g, &eta) + 0.5 * inner(&eta, &h_eta));
    (eta, model, products)
}

/// Minimise `F` over the rank-`p` manifold from `y` (already on it) by the Riemannian
/// trust-region method (acceptance at `rho > 0.1`; the radius quartered below `rho = 0.25`,
/// doubled above `0.75` at the boundary).
pub fn trust_region(
    problem: &MultipleProblem,
    y: Vec<Block>,
    settings: &TrustRegionSettings,
) -> TrustRegionResult {
    trust_region_until(problem, y, settings, None)
}

/// [`trust_region`] that also stops ([`TrustRegionStop::TimeLimit`]) once `until` has passed,
/// checked before each iteration (one iteration, at most `max_inner` Hessian products, past
/// it).
pub fn trust_region_until(
    problem: &MultipleProblem,
    mut y: Vec<Block>,
    settings: &TrustRegionSettings,
    until: Option<std::time::Instant>,
) -> TrustRegionResult {
    let mut f = lifted_cost(problem, &y);
    // the cost's unit, so that scaling every weight scales nothing else: the smallest weight
    // (the tolerance's absolute part, contract section 3; 1 for unit weights)
    let unit = problem.min_weight().max(f64::MIN_POSITIVE);
    let mut radius = (y.len() as f64).sqrt();
    let max_radius = 10.0 * radius;
    let (mut iterations, mut products, mut small) = (0, 0, 0);
    let stop = loop {
        let lambdas = lifted_multipliers(problem, &y);
        let mut g = twice_s_times(problem, &lambdas, &y);
        project(&y, &mut g);
        let gn = inner(&g, &g).sqrt() / (unit + f);
        if gn <= settings.gradient_tolerance {
            break TrustRegionStop::Gradient { value: gn };
        }
        if iterations >= settings.max_iterations {
            break TrustRegionStop::IterationLimit { value: gn };
        }
        if radius < 1e-14 * (1.0 + max_radius) {
            break TrustRegionStop::Radius { value: gn };
        }
        if until.is_some_and(|t| std::time::Instant::now() >= t) {
            break TrustRegionStop::TimeLimit { value: gn };
        }
        iterations += 1;
        crate::progress::emit(|| crate::progress::Event::Iteration {
            phase: crate::progress::Phase::Staircase,
            iteration: iterations,
            cost: f,
            measure: gn,
        });
        let hess = |z: &[Block]| {
            let mut h = twice_s_times(problem, &lambdas, z);
            project(&y, &mut h);
            h
        };
        let (eta, model, used) = truncated_cg(&hess, &g, radius, settings.max_inner);
        products += used;
        let candidate = retract(&y, &eta);
        let fc = candidate
            .as_ref()
            .map_or(f64::INFINITY, |c| lifted_cost(problem, c));
        let rho = if model > 0.0 { (f - fc) / model } else { -1.0 };
        let step = inner(&eta, &eta).sqrt();
        if rho < 0.25 {
            radius *= 0.25;
        } else if rho > 0.75 && step >= 0.99 * radius {
            radius = (2.0 * radius).min(max_radius);
        }
        if rho > 0.1
            && let Some(c) = candidate
        {
            let decrease = (f - fc) / (unit + f);
            small = if decrease < settings.decrease_tolerance {
                small + 1
            } else {
                0
            };
            (y, f) = (c, fc);
            if small >= 2 {
                break TrustRegionStop::Decrease { value: decrease };
            }
        }
    };
    TrustRegionResult {
        y,
        cost: f,
        iterations,
        hessian_products: products,
        stop,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multiple::synthetic::SyntheticGraph;
    use crate::so3::random_rotation;
    use rand::SeedableRng;

    /// The Hessian is that of `F` on the manifold: along a retraction curve `c(t) = R_Y(t Z)`,
    /// `F(c(t)) = F + t <grad, Z> + t^2 <Z, Hess Z> / 2 + O(t^3)` (the polar retraction is second
    /// order), checked by finite differences at a random point of rank 5.
    #[test]
    fn gradient_and_hessian_match_finite_differences() {
        let (p, _) = SyntheticGraph {
            num_rotations: 12,
            num_edges: 30,
            noise_sigma: 0.3,
            seed: 11,
            ..Default::default()
        }
        .generate();
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let random_block = |rng: &mut rand::rngs::StdRng| {
            let r = random_rotation(rng);
            let s = random_rotation(rng);
            let m = Block::from_fn(5, |a, b| {
                if b < 3 {
                    r.matrix()[(a, b)]
                } else {
                    s.matrix()[(a, b - 3)] * 0.3
                }
            });
            polar(&m).unwrap()
        };
        let y: Vec<Block> = (0..12).map(|_| random_block(&mut rng)).collect();
        let mut z: Vec<Block> = (0..12).map(|_| random_block(&mut rng)).collect();
        project(&y, &mut z);
        let lambdas = lifted_multipliers(&p, &y);
        let mut g = twice_s_times(&p, &lambdas, &y);
        project(&y, &mut g);
        let mut hz = twice_s_times(&p, &lambdas, &z);
        project(&y, &mut hz);
        let f = |t: f64| {
            lifted_cost(
                &p,
                &retract(
                    &y,
                    &axpy(
                        &z.iter()
                            .map(|b| Block::zeros(b.ncols()))
                            .collect::<Vec<_>>(),
                        t,
                        &z,
                    ),
                )
                .unwrap(),
            )
        };
        let h = 1e-4;
        let first = (f(h) - f(-h)) / (2.0 * h);
        let second = (f(h) - 2.0 * f(0.0) + f(-h)) / (h * h);
        assert!(
            (first - inner(&g, &z)).abs() < 1e-6 * (1.0 + first.abs()),
            "{first} vs {}",
            inner(&g, &z)
        );
        assert!(
            (second - inner(&z, &hz)).abs() < 1e-4 * (1.0 + second.abs()),
            "{second} vs {}",
            inner(&z, &hz)
        );
    }

    /// From a noisy start the trust-region method reaches a point whose gradient meets its
    /// tolerance, and its cost is at most that of the start.
    #[test]
    fn trust_region_converges() {
        let (p, truth) = SyntheticGraph {
            num_rotations: 40,
            num_edges: 120,
            noise_sigma: 0.1,
            seed: 3,
            ..Default::default()
        }
        .generate();
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let y: Vec<Block> = truth
            .iter()
            .map(|r| {
                let m = crate::so3::perturb_gaussian(r, 0.3, &mut rng);
                Block::from_column_slice(m.matrix().as_slice())
            })
            .collect();
        let start = lifted_cost(&p, &y);
        let r = trust_region(&p, y, &TrustRegionSettings::default());
        assert!(r.cost <= start, "{} > {start}", r.cost);
        assert!(
            matches!(
                r.stop,
                TrustRegionStop::Gradient { .. } | TrustRegionStop::Decrease { .. }
            ),
            "{:?}",
            r.stop
        );
        println!(
            "{} iterations, {} Hessian products, {:?}",
            r.iterations, r.hessian_products, r.stop
        );
    }
}
