//! The scalar comparison `[D13]` with node groups (`paper-notes/certificates.md` `[D13]`,
//! "Groups"): the edges between groups are dropped from the factorised Laplacian (charged as
//! dropped edges), each component `g` of what is left proves its own pencil (exactly one
//! negative pivot per component), so `x1^T M x1 >= zeta |x1|^2` on the space `U` where every
//! coordinate slice has `w_g^T y_g = 0` in every component. The rest of `x` is `3k` coarse
//! directions (a vector `a_g` per component, its `w`-weighted mean), whose cross terms with
//! `U` are made small by a correction computed with conjugate gradients on `U` and then
//! bounded rigorously: `x^T M x >= min(0, lambda_G - rho^2 / zeta) kappa^2 |x|^2`.
//!
//! Made for a rig's augmented view graph (`[H21]`): one group per sensor, where the whole
//! graph's comparison fails with one negative pivot per estimated sensor (its constant
//! directions are charged by the comparison though `M` is positive on them).

use super::analysis::ScalarAnalysis;
use super::charges::{
    EdgeCharges, PRODUCT_ERROR, edge_charges, edge_product, orthogonality_defect,
};
use super::forecast::sparsest_regions_forecast;
use super::inertia::prove_charged;
use super::split::PencilWeights;
use super::{Proven, ScalarComparison, ScalarFailure};
use crate::certify::budget::Budget;
use crate::certify::multiple::block_operator::BlockOperator;
#[cfg(test)]
use crate::certify::multiple::coarse::{COARSE_GRAM_SHARE, coarse_terms_gauged_sharing};
use crate::certify::multiple::coarse::{
    COARSE_RELATIVE_RESIDUAL, CoarseSpace, GaugeBounds, Layout, coarse_terms, coarse_terms_gauged,
};
use crate::certify::multiple::deflated::{Column, RegionSpace, scaled_to_constant};
use crate::certify::multiple::multipliers::{GaugeSource, TraceBound, gauge_terms};
use crate::error::{Error, Result};
use crate::linalg::UNIT_ROUNDOFF as U;
use crate::linalg::cholesky::gamma;
use crate::linalg::ldlt::NegativeColumn;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// Try to prove `lambda_min(S) >= mu` by the grouped comparison (`group[i]`: node `i`'s group):
/// as [`super::scalar_comparison`], with the factorisation of the groups' own edges only.
/// `Ok(Err(why))` when it does not prove, or when its factor is predicted above `max_values`
/// or, by its counted multiply-adds, past `seconds` (the time left); the conjugate gradients
/// stop at that time, which weakens the bound, never its proof.
pub(crate) fn grouped_comparison(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    group: &[usize],
    target: f64,
    (max_values, seconds): (usize, Option<f64>),
) -> Result<std::result::Result<ScalarComparison, String>> {
    let clock = std::time::Instant::now();
    let n = problem.num_rotations();
    if rotations.len() != n || lambdas.len() != n || group.len() != n || problem.is_anisotropic() {
        return Err(Error::InvalidSettings {
            name: "groups".into(),
            reason: "the grouped comparison needs scalar weights and one rotation, multiplier \
                     and group per node"
                .into(),
        });
    }
    let analysis = match ScalarAnalysis::grouped(problem, group, max_values)? {
        Ok(a) => a,
        Err(predicted) => {
            return Ok(Err(format!(
                "its factor is predicted at {predicted:.1e} values, above the {max_values:.1e} \
                 allowed"
            )));
        }
    };
    let values = analysis.factor_len();
    let time = Budget {
        max_memory_bytes: u64::MAX,
        max_seconds: seconds,
    };
    if let Err(why) =
        time.counted_factorisations_fit(values, analysis.factor_multiply_adds(), values)
    {
        return Ok(Err(why));
    }
    let stop_at =
        seconds.and_then(|s| clock.checked_add(std::time::Duration::try_from_secs_f64(s).ok()?));
    Ok(compare_grouped(
        problem,
        &analysis,
        (rotations, lambdas),
        &|| gauge_terms(problem, rotations, lambdas),
        (stop_at, false),
    )
    .map_err(|f| super::failure_text(target, Err(f), analysis.expected_negative_pivots())))
}

/// The dual bound `[D4]` of the estimate's own multipliers proven by the grouped comparison
/// (`sum tr(Lambda_i) + 3n min(mu, 0)`, less its rounding and the data defect) and the proof;
/// `Ok(Err(why))` when the comparison does not prove.
pub(crate) fn grouped_dual_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    group: &[usize],
    target: f64,
    limits: (usize, Option<f64>),
) -> Result<std::result::Result<(f64, ScalarComparison), String>> {
    let lambdas = crate::certify::multiple::multipliers::multipliers(problem, rotations)?;
    let proof = match grouped_comparison(problem, rotations, &lambdas, group, target, limits)? {
        Ok(p) => p,
        Err(why) => return Ok(Err(why)),
    };
    let bound = TraceBound::new(problem, &lambdas).at_mu(proof.verified_min_eigenvalue);
    Ok(Ok((bound, proof)))
}

/// Steps 1 to 5 of the grouped comparison (its `zeta` and the coarse correction's residual
/// are fixed fractions: no target enters), the conjugate gradients stopping at `stop_at`;
/// with `forecast`, not factorised where the charges forecast its failure
/// ([`sparsest_regions_forecast`]).
pub(super) fn compare_grouped(
    problem: &MultipleProblem,
    analysis: &ScalarAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    gauge: GaugeSource<'_>,
    (stop_at, forecast): (Option<std::time::Instant>, bool),
) -> std::result::Result<ScalarComparison, ScalarFailure> {
    let coarse = (COARSE_RELATIVE_RESIDUAL, stop_at);
    compare_grouped_to(
        problem,
        analysis,
        (rotations, lambdas),
        gauge,
        coarse,
        forecast,
    )
}

/// The scalar pencils' `zeta` (added to every charge) as a fraction of the largest weighted
/// degree `d_max` (`[D13]`, "Groups"): small against the charges (the pencils' inertia), large
/// enough that the coarse correction's residual, which enters as `R^T R / zeta`, and the gauge
/// directions' cross terms `rho1^2 / zeta` need not be small. Measured (2026-12-06, `rotavg
/// multiple` on `gen_graph.py expander` graphs of 10^5 nodes at 0.1 rad): at 10 edges per node
/// the regions' factor showed the same 17 negative pivots from `1e-7` to `1e-4` and 21 at `1e-3`
/// (more than it deflates: a denser subgraph then, 16 s of certify against 10); the deflated
/// bound's conjugate gradients took 6 iterations at `1e-7`, 5 at `1e-6`, 4 at `1e-5` to `1e-4`;
/// at 3 edges per node 11 at `1e-7`, 8 at `1e-5`. (The block comparison's regions keep
/// `coarse::ZETA_FRACTION` as their margin.)
pub(super) const PENCIL_ZETA_FRACTION: f64 = 1e-5;

/// A one-region comparison's (`[D13]`, "Deflated components", "One region") least `zeta` (the
/// grouped pencil's, a fixed fraction of the largest diagonal) and the most negative pivots its
/// factor may show: up to [`DEFLATION_EXTRA`] beyond the gauge's one.
pub(super) fn one_region_pencil(analysis: &ScalarAnalysis, d_max: f64) -> (f64, usize) {
    let most = analysis.expected_negative_pivots() + DEFLATION_EXTRA;
    (PENCIL_ZETA_FRACTION * d_max, most)
}

/// The deflated bound `(mu_m, kappa, residual)` of a plain comparison's factor whose `columns`
/// are at its negative pivots, every node in one component (`[D13]`, "One region"): the
/// statement of "Deflated components" with `k = 1`, `U` the complement of the constant
/// directions and the columns, the gauge directions bounded apart (`gauge`, at `rotations`).
pub(super) fn one_region_bound(
    problem: &MultipleProblem,
    (rotations, lambdas, gauge): (&[Rotation], &[Matrix3<f64>], GaugeBounds),
    c: &EdgeCharges,
    columns: Vec<NegativeColumn>,
    (zeta_free, stop_at): (f64, Option<std::time::Instant>),
) -> std::result::Result<(f64, f64, f64), ScalarFailure> {
    // the plain pencil keeps a nonpositive `zeta_free` for one part; its cross terms divide by it
    if !(zeta_free > 0.0 && zeta_free.is_finite()) {
        return Err(ScalarFailure::Numerical);
    }
    let m = scalar_operator(problem, rotations, lambdas, &c.deg_n);
    let one = vec![0; problem.num_rotations()];
    let coarse = (zeta_free, COARSE_RELATIVE_RESIDUAL, stop_at);
    deflated_bound(&m, (&one, columns), gauge, coarse)
}

/// [`compare_grouped`] with the coarse correction's relative residual `rel` (any: a looser one
/// weakens the bound, never its proof).
fn compare_grouped_to(
    problem: &MultipleProblem,
    analysis: &ScalarAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    gauge: GaugeSource<'_>,
    (rel, stop_at): (f64, Option<std::time::Instant>),
    forecast: bool,
) -> std::result::Result<ScalarComparison, ScalarFailure> {
    let of = &analysis.components;
    let t_max = orthogonality_defect(rotations)?;
    let c = edge_charges(problem, rotations, lambdas, &analysis.copies, analysis.beta)?;
    if forecast && let Some(f) = sparsest_regions_forecast(problem, &c.reduced, &c.delta) {
        return Err(f);
    }
    let pencil = grouped_pencil(&c)?;
    let zeta_free = pencil.zeta_free;
    let most = analysis.expected_negative_pivots() + DEFLATION_EXTRA;
    let (headroom, backward, deflated) = prove_charged(analysis, problem, &c, &pencil, most)?;
    let m = scalar_operator(problem, rotations, lambdas, &c.deg_n);
    let coarse = (zeta_free, rel, stop_at);
    let negative = deflated.len();
    let (mu_m, kappa, residual) = if deflated.is_empty() {
        let groups = Groups::new(of, &pencil.weights);
        let coarse = coarse_terms(&m, &groups, coarse).ok_or(ScalarFailure::Numerical)?;
        (coarse.mu(groups.kappa()), groups.kappa(), coarse.rho)
    } else {
        let gauge = GaugeBounds::of(&gauge(), t_max);
        deflated_bound(&m, (of, deflated), gauge, coarse)?
    };
    let proven = Proven {
        mu_m,
        t_max,
        inertia: (headroom, backward),
        kappa,
        residual,
        deflated: negative,
    };
    proven.outcome(&c, analysis, &pencil)
}

/// The pencils' weights `w = delta + zeta`, `zeta` a fixed fraction of the largest diagonal,
/// and what is left of `zeta` after their rounding.
fn grouped_pencil(c: &EdgeCharges) -> std::result::Result<PencilWeights, ScalarFailure> {
    let zeta = PENCIL_ZETA_FRACTION * c.d_max;
    let weights: Vec<f64> = c.delta.iter().map(|d| d + zeta).collect();
    let w_max = weights.iter().copied().fold(0.0, f64::max);
    // fl(delta_i + zeta) >= delta_i + zeta - u w_i (twice that for safety)
    let zeta_free = (zeta - 2.0 * U * w_max) * (1.0 - 4.0 * U);
    if zeta_free <= 0.0 || !zeta_free.is_finite() {
        return Err(ScalarFailure::Numerical);
    }
    Ok(PencilWeights {
        weights,
        shares: Vec::new(),
        zeta,
        defect: 0.0,
        zeta_free,
    })
}

/// The coarse bound `(mu_m, kappa, residual)` of deflated components (`[D13]`, "Deflated
/// components"): [`deflated_space`] with the gauge directions bounded apart
/// ([`coarse_terms_gauged`], by the estimate's `gauge` bounds). Away from a critical point the
/// gauge's residual makes it vacuous: below Gershgorin's `-max row sum` it is reported as the
/// inertia's failure.
fn deflated_bound(
    m: &BlockOperator,
    (of, columns): (&[usize], Vec<NegativeColumn>),
    gauge: GaugeBounds,
    coarse: (f64, f64, Option<std::time::Instant>),
) -> std::result::Result<(f64, f64, f64), ScalarFailure> {
    let negative = columns.len();
    let space = deflated_space(of, columns).ok_or(ScalarFailure::Numerical)?;
    let bound = coarse_terms_gauged(m, &space, gauge, coarse).ok_or(ScalarFailure::Numerical)?;
    let mu = bound.mu(space.kappa());
    if mu < -m.row_abs() {
        return Err(ScalarFailure::Inertia {
            negative_pivots: negative,
        });
    }
    Ok((mu, space.kappa(), bound.rho))
}

/// The most negative pivots beyond one per component that the deflation takes (the factor's
/// columns at all of them, three coarse columns each).
pub(super) const DEFLATION_EXTRA: usize = 12;

/// The deflated components' coarse space (`[D13]`, "Deflated components"): per component its
/// constant directions and, for each of the factor's columns `l_k` at a negative pivot in it,
/// `l_k (x) e_c` for the three coordinates (each scaled by a power of two to about the
/// constant directions' norm). `U = {x : F_g^T x_g = 0}` lies in the set where every
/// coordinate slice is orthogonal to every `l_k`, where the factorised pencil is positive
/// semidefinite; `None` when the columns are not proven independent.
fn deflated_space(of: &[usize], columns: Vec<NegativeColumn>) -> Option<RegionSpace<'_>> {
    let count = of.iter().max().map_or(1, |m| m + 1);
    let mut size = vec![0usize; count];
    of.iter().for_each(|&g| size[g] += 1);
    let mut extra: Vec<Vec<Column>> = vec![Vec::new(); count];
    for column in columns {
        let g = of[column.entries.first()?.0];
        let scalar = scaled_to_constant(column.entries, size[g]);
        for c in 0..3 {
            extra[g].push(scalar.iter().map(|&(i, v)| (3 * i + c, v)).collect());
        }
    }
    RegionSpace::new(of, extra)
}

/// The components and the weights of the pencils: the projector `Pi` onto `U` and `kappa`.
struct Groups<'a> {
    /// The components; `kappa = max_g ||w_g||_2 / sum_g w` rounded up (`|a|^2 <= kappa^2
    /// |x|^2`), the last group's the same.
    layout: Layout<'a>,
    weights: &'a [f64],
    /// Per component, `sum w_i^2` and `sum w_i`.
    sq: Vec<f64>,
    /// The most nodes in a component.
    largest: usize,
}

impl<'a> Groups<'a> {
    fn new(of: &'a [usize], weights: &'a [f64]) -> Self {
        let count = of.iter().max().map_or(1, |m| m + 1);
        let (mut sq, mut sum, mut size) = (vec![0.0; count], vec![0.0; count], vec![0; count]);
        for (&g, &w) in of.iter().zip(weights) {
            sq[g] += w * w;
            sum[g] += w;
            size[g] += 1;
        }
        let largest = size.iter().copied().max().unwrap_or(0);
        let g = gamma(largest + 2);
        let kappa = sq
            .iter()
            .zip(&sum)
            .map(|(q, s)| (q * (1.0 + g)).sqrt() / (s * (1.0 - g)))
            .fold(0.0, f64::max)
            * (1.0 + 4.0 * U);
        Groups {
            layout: Layout {
                of,
                count,
                kappa,
                kappa_last: kappa,
            },
            weights,
            sq,
            largest,
        }
    }
}

impl CoarseSpace for Groups<'_> {
    fn layout(&self) -> &Layout<'_> {
        &self.layout
    }

    /// `z <- Pi z` in floating point (every coordinate slice less its `w`-projection in every
    /// component, the orthogonal projector onto `U`).
    fn project(&self, z: &mut [f64]) {
        let mut dots = vec![[0.0f64; 3]; self.layout.count];
        for (i, &g) in self.layout.of.iter().enumerate() {
            for (j, d) in dots[g].iter_mut().enumerate() {
                *d += self.weights[i] * z[3 * i + j];
            }
        }
        for (i, &g) in self.layout.of.iter().enumerate() {
            for j in 0..3 {
                z[3 * i + j] -= dots[g][j] / self.sq[g] * self.weights[i];
            }
        }
    }

    /// `fl(Pi y)` is within `2 gamma(largest + 3) ||y|| + u ||Pi y||` of the exact.
    fn projection_error(&self, y: &[f64], p: &[f64]) -> f64 {
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt() * (1.0 + gamma(v.len()));
        2.0 * gamma(self.largest + 3) * norm(y) + U * norm(p)
    }

    /// A bound on `||(I - Pi) x||_F` for the columns `x = z - E` (`E` the coarse directions):
    /// each component's weighted sums with their rounding, over `||w_g||`.
    fn off_space(&self, z: &[Vec<f64>]) -> f64 {
        let g = gamma(self.largest + 3);
        let mut total = 0.0f64;
        for (col, zc) in z.iter().enumerate() {
            let mut dots = vec![[0.0f64; 3]; self.layout.count];
            let mut mags = vec![[0.0f64; 3]; self.layout.count];
            for (i, &grp) in self.layout.of.iter().enumerate() {
                for j in 0..3 {
                    let x = zc[3 * i + j] - f64::from(u8::from(col == 3 * grp + j));
                    dots[grp][j] += self.weights[i] * x;
                    mags[grp][j] += (self.weights[i] * x).abs();
                }
            }
            for grp in 0..self.layout.count {
                for j in 0..3 {
                    let d = dots[grp][j].abs() + g * mags[grp][j];
                    total += d * d / (self.sq[grp] * (1.0 - g));
                }
            }
        }
        total.sqrt() * (1.0 + 4.0 * g)
    }
}

/// `M = D^T S D` of a problem with scalar weights as `3 x 3` blocks (`M_ii = R_i^T (d_i I - sym
/// Lambda_i) R_i`, `-w P_e` on the edges), with its forming errors.
fn scalar_operator(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    deg_n: &[usize],
) -> BlockOperator {
    let n = rotations.len();
    let mut degree = vec![0.0f64; n];
    let mut form_rows = vec![0.0f64; n];
    let mut edges = Vec::with_capacity(problem.num_edges());
    for e in problem.edges() {
        let block = -e.weight * edge_product(e, rotations);
        // fl(P_e) within PRODUCT_ERROR (Frobenius), one more rounding for the weight
        let err = e.weight * (PRODUCT_ERROR + 2.0 * U * 3.5);
        for v in [e.i, e.j] {
            degree[v] += e.weight;
            form_rows[v] += err;
        }
        edges.push((e.i, e.j, block));
    }
    let mut diag = Vec::with_capacity(n);
    for i in 0..n {
        let r = rotations[i].matrix();
        let l = lambdas[i];
        let inner = Matrix3::identity() * degree[i] - 0.5 * (l + l.transpose());
        // two 3 x 3 products of entries <= 1.001 with inner's, the degree's sum of deg terms
        let mag = 3.0 * (degree[i] + l.abs().sum());
        form_rows[i] += gamma(deg_n[i] + 12) * 4.0 * mag;
        diag.push(r.transpose() * inner * r);
    }
    let max_degree = deg_n.iter().copied().max().unwrap_or(0);
    BlockOperator::new(diag, edges, &form_rows, max_degree)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::multiple::multipliers::{certificate_matrix, multipliers};
    use crate::multiple::{Edge, MultipleSettings, solve_multiple};
    use crate::so3::{perturb_gaussian, random_rotation};
    use rand::{Rng, SeedableRng};

    /// A rig-like graph: `groups` groups of `size` nodes, each a random graph of about 3
    /// edges per node, and node `t` of every group joined to node `t` of the next for a
    /// fraction `cross` of the `t` (the frames), at noise `sigma`; with the planted truth.
    fn grouped_graph(
        groups: usize,
        size: usize,
        cross: f64,
        sigma: f64,
        seed: u64,
    ) -> (MultipleProblem, Vec<usize>) {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let n = groups * size;
        let truth: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
        let mut edges = Vec::new();
        let mut push = |i: usize, j: usize, w: f64, rng: &mut rand::rngs::StdRng| {
            let exact =
                Rotation::from_matrix_unchecked(truth[j].matrix() * truth[i].matrix().transpose());
            edges.push(Edge {
                i,
                j,
                rotation: perturb_gaussian(&exact, sigma, rng),
                weight: w,
            });
        };
        for g in 0..groups {
            let base = g * size;
            // a cycle keeps each group connected; chords make it an expander
            for t in 0..size {
                push(base + t, base + (t + 1) % size, 1.0, &mut rng);
                let other = rng.random_range(0..size);
                if other != t {
                    push(base + t, base + other, rng.random_range(0.5..2.0), &mut rng);
                }
            }
            for t in 0..size {
                if g + 1 < groups && rng.random::<f64>() < cross {
                    push(base + t, base + size + t, 1.0, &mut rng);
                }
            }
        }
        let p = MultipleProblem::new(n, edges).unwrap();
        let group = (0..n).map(|i| i / size).collect();
        (p, group)
    }

    /// A proven `mu` at most the dense `lambda_min(S)` `exact` (to `1e-12` relative).
    fn assert_at_most_dense(mu: f64, exact: f64, context: &str) {
        assert!(
            mu <= exact + 1e-12 * (1.0 + exact.abs()),
            "{context}: proven {mu:e} above the dense {exact:e}"
        );
    }

    fn dense_lambda_min(p: &MultipleProblem, lambdas: &[Matrix3<f64>]) -> f64 {
        let s = certificate_matrix(p, lambdas).unwrap();
        crate::linalg::cholesky::to_dense(s.as_ref())
            .symmetric_eigenvalues()
            .min()
    }

    /// Every proven `mu` is at most the dense `lambda_min(S)`, at local solutions and at
    /// perturbed (non-critical) points, and at the solutions of low noise the grouped
    /// comparison proves what the gap budget needs (it is not vacuous).
    #[test]
    fn grouped_comparisons_are_below_the_dense_spectrum() {
        let (mut proofs, mut tight) = (0, 0);
        for seed in 0..24u64 {
            let groups = 2 + (seed % 3) as usize;
            let sigma = [0.01, 0.05, 0.2][(seed / 3 % 3) as usize];
            let (p, group) = grouped_graph(groups, 12, 0.5, sigma, seed);
            let solved = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed + 100);
            let perturbed: Vec<Rotation> = solved
                .rotations
                .iter()
                .map(|r| perturb_gaussian(r, 0.05, &mut rng))
                .collect();
            for (at, critical) in [(&solved.rotations, true), (&perturbed, false)] {
                let lambdas = multipliers(&p, at).unwrap();
                let exact = dense_lambda_min(&p, &lambdas);
                let target = 1e-6 * p.cost(at).max(1e-12) / p.num_rotations() as f64;
                let r = grouped_comparison(&p, at, &lambdas, &group, target, (usize::MAX, None))
                    .unwrap();
                if let Ok(proof) = r {
                    proofs += 1;
                    let mu = proof.verified_min_eigenvalue;
                    assert_at_most_dense(mu, exact, &format!("seed {seed}"));
                    if critical && sigma <= 0.05 && mu >= -target {
                        tight += 1;
                    }
                    if !critical && exact < -1e-3 {
                        // not vacuous where S is clearly indefinite (3x measured at most)
                        assert!(mu >= 5.0 * exact, "seed {seed}: {mu:e} against {exact:e}");
                    }
                }
            }
        }
        assert!(proofs >= 16, "{proofs} proofs");
        assert!(tight >= 8, "{tight} proofs within the target at low noise");
    }

    /// One region (`[D13]`, "One region"): the whole graph's plain comparison with the grouped
    /// pencil's `zeta` and its deflation, at solutions and points turned by 0.02 rad of noisy
    /// random graphs of about 3 edges per node (any target: every bound kept): never above
    /// the dense spectrum, and it proves where the factor shows extra negative pivots (fails
    /// without the deflation: `deflated > 0`).
    #[test]
    fn one_region_is_below_the_dense_spectrum() {
        let (mut deflated, mut attempts) = (0, 0);
        for seed in 0..24u64 {
            let sigma = [0.15, 0.25, 0.35][(seed % 3) as usize];
            let (p, _) = grouped_graph(1, 20 + (seed % 4) as usize * 10, 0.0, sigma, seed);
            let solved = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed + 500);
            let turned: Vec<Rotation> = (solved.rotations.iter())
                .map(|r| perturb_gaussian(r, 0.02, &mut rng))
                .collect();
            let analysis = ScalarAnalysis::new(&p, usize::MAX).unwrap().unwrap();
            for at in [&solved.rotations, &turned] {
                attempts += 1;
                let lambdas = multipliers(&p, at).unwrap();
                let plain = (f64::INFINITY, None);
                let gauge = || gauge_terms(&p, at, &lambdas);
                let estimate = (at.as_slice(), lambdas.as_slice());
                let Ok(proof) =
                    super::super::compare_plain(&p, &analysis, estimate, plain, Some(&gauge))
                else {
                    continue;
                };
                deflated += usize::from(proof.deflated > 0);
                let (mu, exact) = (
                    proof.verified_min_eigenvalue,
                    dense_lambda_min(&p, &lambdas),
                );
                assert_at_most_dense(mu, exact, &format!("seed {seed}, one region"));
            }
        }
        println!("{deflated} deflated one-region proofs of {attempts} attempts");
        assert!(deflated >= 3, "{deflated} deflated of {attempts}");
    }

    /// Deflated components (`[D13]`, "Deflated components"): where a component's pencil shows
    /// more negative pivots than one, the factor's columns at all of them join the coarse
    /// space; every such proof at most the dense `lambda_min(S)`, at solutions of noisy grouped
    /// graphs and at points turned by 0.02 rad, and some within the target at solutions. Fails
    /// when one column is left out (checked).
    #[test]
    fn deflated_components_are_below_the_dense_spectrum() {
        let (mut deflated, mut tight, mut attempts) = (0, 0, 0);
        for seed in 0..48u64 {
            let groups = 2 + (seed % 3) as usize;
            let sigma = [0.15, 0.25, 0.35][(seed / 3 % 3) as usize];
            let (p, group) = grouped_graph(groups, 10, 0.5, sigma, seed);
            let solved = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed + 300);
            let turned: Vec<Rotation> = (solved.rotations.iter())
                .map(|r| perturb_gaussian(r, 0.02, &mut rng))
                .collect();
            for (at, critical) in [(&solved.rotations, true), (&turned, false)] {
                attempts += 1;
                let lambdas = multipliers(&p, at).unwrap();
                let target = 1e-6 * p.cost(at).max(1e-12) / p.num_rotations() as f64;
                let r = grouped_comparison(&p, at, &lambdas, &group, target, (usize::MAX, None))
                    .unwrap();
                let Ok(proof) = r else { continue };
                if proof.deflated == 0 {
                    continue;
                }
                deflated += 1;
                let (mu, exact) = (
                    proof.verified_min_eigenvalue,
                    dense_lambda_min(&p, &lambdas),
                );
                assert_at_most_dense(mu, exact, &format!("seed {seed}, deflated"));
                tight += usize::from(critical && mu >= -target);
            }
        }
        println!("{deflated} deflated proofs of {attempts} attempts, {tight} within the target");
        assert!(
            deflated >= 6 && tight >= 3,
            "{deflated} deflated, {tight} within the target"
        );
    }

    /// The deflated space of the factor's `columns` on the components `of` (`[D13]`, "Deflated
    /// components"): its extra columns span exactly the columns times each axis, and the dense
    /// `M` is positive semidefinite (to `1e-9 d_max`) off them and the constant directions.
    fn assert_deflated_space(
        p: &MultipleProblem,
        (at, lambdas): (&[Rotation], &[Matrix3<f64>]),
        of: &[usize],
        columns: Vec<NegativeColumn>,
        (d_max, seed): (f64, u64),
    ) {
        let n = p.num_rotations();
        let lifted: Vec<nalgebra::DVector<f64>> = (columns.iter())
            .flat_map(|l| {
                (0..3).map(move |k| {
                    let mut v = nalgebra::DVector::zeros(3 * n);
                    l.entries.iter().for_each(|&(i, x)| v[3 * i + k] = x);
                    v
                })
            })
            .collect();
        let space = deflated_space(of, columns).unwrap();
        // the space's extra columns span exactly the factor's columns times each axis
        let extra = nalgebra::DMatrix::from_columns(
            &(space.extra_columns().into_iter())
                .map(nalgebra::DVector::from_vec)
                .collect::<Vec<_>>(),
        );
        assert_eq!(
            extra.ncols(),
            lifted.len(),
            "seed {seed}: a column left out"
        );
        let basis = extra.svd(true, false).u.unwrap();
        for v in &lifted {
            let off = v - &basis * (basis.transpose() * v);
            assert!(
                off.norm() <= 1e-9 * v.norm(),
                "seed {seed}: a column not in the space"
            );
        }
        let mut f: Vec<nalgebra::DVector<f64>> = space
            .extra_columns()
            .into_iter()
            .map(nalgebra::DVector::from_vec)
            .collect();
        let components = of.iter().max().map_or(0, |m| m + 1);
        for g in 0..components {
            for k in 0..3 {
                let mut e = nalgebra::DVector::zeros(3 * n);
                (0..n)
                    .filter(|&i| of[i] == g)
                    .for_each(|i| e[3 * i + k] = 1.0);
                f.push(e);
            }
        }
        let f = nalgebra::DMatrix::from_columns(&f);
        let low = min_off_columns(p, (at, lambdas), &f);
        assert!(
            low >= -1e-9 * d_max,
            "seed {seed}: {low:e} off the deflated space"
        );
    }

    /// One region's deflated spaces (`[D13]`, "One region"): the plain comparison's pencil with
    /// the grouped `zeta` as its floor, on whole graphs of about 3 edges per node at solutions
    /// and points turned by 0.02 rad, where its factor shows 2 to 13 negative pivots: the space
    /// of the factor's columns and the constant directions leaves the dense `M` positive
    /// semidefinite off it (the premise of its bound, with one component). Fails when a column
    /// is left out of the space (checked); weaker pencil weights are not caught by `M`'s check
    /// (the comparison is loose: only fewer proofs, checked).
    #[test]
    fn one_region_spaces_leave_m_positive_off_their_columns() {
        let mut checked = 0;
        for seed in 0..24u64 {
            let sigma = [0.15, 0.25, 0.35][(seed % 3) as usize];
            let (p, _) = grouped_graph(1, 20 + (seed % 4) as usize * 10, 0.0, sigma, seed);
            let turn = [0.0, 0.02][(seed / 3 % 2) as usize];
            let at = turned_solution(&p, turn, seed + 500);
            let lambdas = multipliers(&p, &at).unwrap();
            let analysis = ScalarAnalysis::new(&p, usize::MAX).unwrap().unwrap();
            let c = edge_charges(&p, &at, &lambdas, &analysis.copies, analysis.beta).unwrap();
            let (floor, most) = one_region_pencil(&analysis, c.d_max);
            let (rho1, _) =
                super::super::residuals::residual_bounds(&p, &at, &lambdas, &c.deg_n, 1e-9);
            let Some(pencil) = super::super::split::pencil_weights(
                &analysis,
                &p,
                (&c.reduced, &c.delta),
                (rho1, c.d_max, floor),
                1e-9,
            ) else {
                continue;
            };
            let found = prove_charged(&analysis, &p, &c, &pencil, most);
            let Ok((_, _, columns)) = found else { continue };
            if columns.is_empty() {
                continue;
            }
            checked += 1;
            let one = vec![0; p.num_rotations()];
            let at = (at.as_slice(), lambdas.as_slice());
            assert_deflated_space(&p, at, &one, columns, (c.d_max, seed));
        }
        println!("{checked} one-region deflated spaces");
        assert!(checked >= 3, "{checked} one-region deflated spaces");
    }

    /// The local solution of `p`, each rotation turned by `angle` (random axes, `seed`).
    fn turned_solution(p: &MultipleProblem, angle: f64, seed: u64) -> Vec<Rotation> {
        let solved = solve_multiple(p, &MultipleSettings::default()).unwrap();
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        (solved.rotations.iter())
            .map(|r| perturb_gaussian(r, angle, &mut rng))
            .collect()
    }

    /// `lambda_min` of `M = D^T S D` (dense) on the complement of the columns of `f`.
    fn min_off_columns(
        p: &MultipleProblem,
        (at, lambdas): (&[Rotation], &[Matrix3<f64>]),
        f: &nalgebra::DMatrix<f64>,
    ) -> f64 {
        let n = p.num_rotations();
        let s = crate::linalg::cholesky::to_dense(certificate_matrix(p, lambdas).unwrap().as_ref());
        let mut d = nalgebra::DMatrix::zeros(3 * n, 3 * n);
        for (i, r) in at.iter().enumerate() {
            d.fixed_view_mut::<3, 3>(3 * i, 3 * i).copy_from(r.matrix());
        }
        let m = d.transpose() * s * &d;
        let u = f.clone().svd(true, false).u.unwrap();
        let off = nalgebra::DMatrix::<f64>::identity(3 * n, 3 * n) - &u * u.transpose();
        let e = off.symmetric_eigen();
        let q: Vec<_> = (0..3 * n)
            .filter(|&i| e.eigenvalues[i] > 0.5)
            .map(|i| e.eigenvectors.column(i).into_owned())
            .collect();
        let q = nalgebra::DMatrix::from_columns(&q);
        (q.transpose() * m * &q).symmetric_eigenvalues().min()
    }

    /// The deflated components' space itself: `M = D^T S D` (dense) is positive semidefinite on
    /// the vectors orthogonal to every component's constant directions and the space's deflated
    /// columns, at the solutions of noisy grouped graphs and at points turned by 0.02 and 0.1
    /// rad (where `S` is indefinite) where the pencils show more negative pivots than
    /// components, and its extra columns span exactly the factor's columns times each axis.
    /// Fails when one of the factor's columns is left out of the space (checked), which the
    /// whole bound's test above does not catch (the coarse correction masks it), nor `M` here
    /// (the comparison is loose).
    #[test]
    fn deflated_spaces_leave_m_positive_off_their_columns() {
        let mut checked = 0;
        for seed in 0..48u64 {
            let groups = 2 + (seed % 3) as usize;
            let sigma = [0.15, 0.25, 0.35][(seed / 3 % 3) as usize];
            let (p, group) = grouped_graph(groups, 10, 0.5, sigma, seed);
            let turn = [0.0, 0.02, 0.1][(seed / 9 % 3) as usize];
            let at = turned_solution(&p, turn, seed + 500);
            let lambdas = multipliers(&p, &at).unwrap();
            let analysis = ScalarAnalysis::grouped(&p, &group, usize::MAX)
                .unwrap()
                .unwrap();
            let c = edge_charges(&p, &at, &lambdas, &analysis.copies, analysis.beta).unwrap();
            let pencil = grouped_pencil(&c).unwrap();
            let most = analysis.expected_negative_pivots() + DEFLATION_EXTRA;
            let found = prove_charged(&analysis, &p, &c, &pencil, most);
            let Ok((_, _, columns)) = found else { continue };
            if columns.is_empty() {
                continue;
            }
            checked += 1;
            let at = (at.as_slice(), lambdas.as_slice());
            assert_deflated_space(&p, at, &analysis.components, columns, (c.d_max, seed));
        }
        println!("{checked} deflated spaces");
        assert!(checked >= 6, "{checked} deflated spaces");
    }

    /// The soundness sweep: 60 grouped graphs (2-5 groups of 5-14 nodes, edges between groups
    /// on 20-100 % of the frames, noise 0-0.3 rad), half of them with a rig's pseudo-edge
    /// triples between the groups of each frame ([`super::super::tests::push_pseudo_triple`],
    /// random axes and weights: the point is then not critical), at the local solution, at
    /// points perturbed by 0.05 and 0.5 rad and at random rotations: every proof at most the
    /// dense `lambda_min(S)`.
    #[test]
    fn no_grouped_proof_above_the_dense_spectrum() {
        let (mut proofs, mut with_pseudo) = (0, 0);
        for seed in 0..60u64 {
            let mut rng = rand::rngs::StdRng::seed_from_u64(1000 + seed);
            let groups = 2 + (seed % 4) as usize;
            let size = 5 + (seed % 10) as usize;
            let cross = 0.2 + 0.8 * rng.random::<f64>();
            let sigma = [0.0, 0.02, 0.1, 0.3][(seed / 4 % 4) as usize];
            let (p, group) = grouped_graph(groups, size, cross, sigma, seed);
            let Ok(solved) = solve_multiple(&p, &MultipleSettings::default()) else {
                continue;
            };
            let p = if seed % 2 == 1 {
                let mut edges = p.edges().to_vec();
                for t in 0..size {
                    for g in 0..groups - 1 {
                        let axis = nalgebra::Vector3::new(
                            rng.random::<f64>() - 0.5,
                            rng.random::<f64>() - 0.5,
                            rng.random::<f64>() - 0.5,
                        ) + nalgebra::Vector3::new(1e-3, 0.0, 0.0);
                        let c = 10f64.powf(-3.0 + 2.5 * rng.random::<f64>());
                        let pair = (g * size + t, (g + 1) * size + t);
                        super::super::tests::push_pseudo_triple(
                            &mut edges,
                            &solved.rotations,
                            pair,
                            axis,
                            c,
                        );
                    }
                }
                MultipleProblem::new(p.num_rotations(), edges).unwrap()
            } else {
                p
            };
            let turned = |angle: f64, rng: &mut rand::rngs::StdRng| -> Vec<Rotation> {
                solved
                    .rotations
                    .iter()
                    .map(|r| perturb_gaussian(r, angle, rng))
                    .collect()
            };
            let random: Vec<Rotation> = (0..p.num_rotations())
                .map(|_| random_rotation(&mut rng))
                .collect();
            let points = [
                solved.rotations.clone(),
                turned(0.05, &mut rng),
                turned(0.5, &mut rng),
                random,
            ];
            for at in &points {
                let lambdas = multipliers(&p, at).unwrap();
                let exact = dense_lambda_min(&p, &lambdas);
                let target = 1e-6 * p.cost(at).max(1e-12) / p.num_rotations() as f64;
                let limits = (usize::MAX, None);
                let r = grouped_comparison(&p, at, &lambdas, &group, target, limits).unwrap();
                if let Ok(proof) = r {
                    proofs += 1;
                    with_pseudo += usize::from(seed % 2 == 1);
                    let mu = proof.verified_min_eigenvalue;
                    assert_at_most_dense(mu, exact, &format!("seed {seed}"));
                }
            }
        }
        eprintln!("grouped sweep: {proofs} proofs, {with_pseudo} with pseudo-edges");
        assert!(
            proofs >= 60 && with_pseudo >= 20,
            "{proofs} proofs, {with_pseudo} with pseudo-edges"
        );
    }

    /// Grouped subgraphs (`[D13]`, "Grouped subgraphs") through the public comparison: random
    /// graphs of 240 nodes and 4-10 edges per node in 2-4 regions, subgraphs of 2-4 edges per
    /// node, at the local solution and at points turned by 0.03 and 0.3 rad: every proof at
    /// most the dense `lambda_min(S)`, and at the solutions of low noise within the target
    /// (not vacuous).
    #[test]
    fn grouped_subgraph_proofs_are_below_the_dense_spectrum() {
        use crate::certify::multiple::scalar::{ScalarAnalysis, scalar_comparison};
        use crate::multiple::synthetic::SyntheticGraph;
        let (mut proofs, mut tight) = (0, 0);
        for seed in 0..12u64 {
            let (p, _) = SyntheticGraph {
                num_rotations: 240,
                num_edges: 240 * (4 + 3 * (seed % 3) as usize),
                noise_sigma: [0.01, 0.05][(seed / 3 % 2) as usize],
                seed,
                ..Default::default()
            }
            .generate();
            let solved = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed + 7);
            let turned = |angle: f64, rng: &mut rand::rngs::StdRng| -> Vec<Rotation> {
                let r = &solved.rotations;
                r.iter().map(|r| perturb_gaussian(r, angle, rng)).collect()
            };
            let points = [
                (solved.rotations.clone(), true),
                (turned(0.03, &mut rng), false),
                (turned(0.3, &mut rng), false),
            ];
            let regions = 2 + (seed % 3) as usize;
            for (at, critical) in &points {
                let lambdas = multipliers(&p, at).unwrap();
                let exact = dense_lambda_min(&p, &lambdas);
                let target = 1e-6 * p.cost(at).max(1e-12) / p.num_rotations() as f64;
                for k in [2.0, 3.0, 4.0] {
                    let a = ScalarAnalysis::grouped_subgraph(&p, at, k, regions, usize::MAX)
                        .unwrap()
                        .unwrap();
                    assert_eq!(a.groups(), regions, "seed {seed}: one component per region");
                    let Ok(proof) = scalar_comparison(&p, &a, at, &lambdas, target).unwrap() else {
                        continue;
                    };
                    proofs += 1;
                    let mu = proof.verified_min_eigenvalue;
                    assert_at_most_dense(mu, exact, &format!("seed {seed}, {k} edges per node"));
                    tight += usize::from(*critical && mu >= -target);
                }
            }
        }
        eprintln!("grouped subgraphs: {proofs} proofs, {tight} within the target");
        assert!(
            proofs >= 24 && tight >= 12,
            "{proofs} proofs, {tight} tight"
        );
    }

    /// The sparsest regions' forecast (`forecast.rs`, `sparsest_regions_forecast`) is right
    /// when it speaks: on random graphs of 2000 nodes in 4 regions at their optimum, every
    /// subgraph of 2 edges per node it forecast to fail does fail when factorised (its pencils
    /// show more negative pivots than the deflation takes), within a factor of 3 of the
    /// forecast count, and it speaks on the noisy dense graphs (else the test proves nothing);
    /// on the quiet dense graph it is silent, and that subgraph proves.
    #[test]
    fn the_sparsest_regions_forecast_is_right_when_it_speaks() {
        use super::super::forecast::sparsest_regions_forecast;
        use crate::certify::multiple::scalar::scalar_comparison;
        let mut spoke = 0;
        for (seed, per_node, noise) in [(1u64, 10, 0.1), (2, 10, 0.1), (3, 3, 0.1), (4, 10, 0.02)] {
            let (p, _) = crate::multiple::synthetic::SyntheticGraph {
                num_rotations: 2000,
                num_edges: 2000 * per_node,
                noise_sigma: noise,
                seed,
                ..Default::default()
            }
            .generate();
            let at = solve_multiple(&p, &MultipleSettings::default())
                .unwrap()
                .rotations;
            let lambdas = multipliers(&p, &at).unwrap();
            let a = ScalarAnalysis::grouped_subgraph(&p, &at, 2.0, 4, usize::MAX)
                .unwrap()
                .unwrap();
            let c = edge_charges(&p, &at, &lambdas, &a.copies, a.beta).unwrap();
            let Some(forecast) = sparsest_regions_forecast(&p, &c.reduced, &c.delta) else {
                assert_eq!(noise, 0.02, "seed {seed}: silent on a noisy graph");
                let target = 1e-6 * p.cost(&at) / p.num_rotations() as f64;
                let proof = scalar_comparison(&p, &a, &at, &lambdas, target).unwrap();
                assert!(proof.is_ok(), "seed {seed}: silent, and failed: {proof:?}");
                continue;
            };
            spoke += 1;
            let most = a.expected_negative_pivots() + DEFLATION_EXTRA;
            let pencil = grouped_pencil(&c).unwrap();
            match prove_charged(&a, &p, &c, &pencil, most) {
                Err(ScalarFailure::Inertia { negative_pivots }) => {
                    let forecast = forecast.negative_count().unwrap() as f64;
                    let ratio = forecast / negative_pivots as f64;
                    assert!(
                        (1.0 / 3.0..=3.0).contains(&ratio),
                        "seed {seed}: forecast {forecast}, counted {negative_pivots}"
                    );
                }
                other => panic!(
                    "seed {seed}: forecast to fail, then {:?}",
                    other.map(|_| ())
                ),
            }
        }
        assert_eq!(
            spoke, 3,
            "the forecast spoke on {spoke} of the 3 noisy graphs"
        );
    }

    /// The coarse bound holds for any correction: with the conjugate gradients stopped at a
    /// relative residual of 0.9 (about one iteration), where the residual's term `R^T R /
    /// zeta` carries the bound, every proof on the grouped graphs of the first test is still
    /// at most the dense `lambda_min(S)` (without that term it is not: checked).
    #[test]
    fn a_loose_coarse_correction_weakens_the_bound_only() {
        let mut proofs = 0;
        for seed in 0..12u64 {
            let (p, group) = grouped_graph(2 + (seed % 3) as usize, 12, 0.5, 0.05, seed);
            let solved = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed + 100);
            let turned: Vec<Rotation> = solved
                .rotations
                .iter()
                .map(|r| perturb_gaussian(r, 0.02, &mut rng))
                .collect();
            for at in [&solved.rotations, &turned] {
                let lambdas = multipliers(&p, at).unwrap();
                let exact = dense_lambda_min(&p, &lambdas);
                let a = ScalarAnalysis::grouped(&p, &group, usize::MAX)
                    .unwrap()
                    .unwrap();
                for rel in [0.9, 1e-4] {
                    let gauge = || gauge_terms(&p, at, &lambdas);
                    let estimate = (at.as_slice(), lambdas.as_slice());
                    let Ok(proof) =
                        compare_grouped_to(&p, &a, estimate, &gauge, (rel, None), false)
                    else {
                        continue;
                    };
                    proofs += 1;
                    let mu = proof.verified_min_eigenvalue;
                    assert_at_most_dense(mu, exact, &format!("seed {seed}, rel {rel}"));
                }
            }
        }
        assert!(proofs >= 24, "{proofs} proofs");
    }

    /// The coarse correction's early stop (`coarse.rs`, `solved_bound`) is resumed where it
    /// spoils the bound: with every column stopped at its start (a share no residual
    /// exceeds), `R^T R / zeta` would leave `lambda_f` far below zero and the bound with it
    /// (checked); resumed, the gauged bound is that of the conjugate gradients run to the
    /// relative residual without the stop, to 1e-3 (of it, or of `1e-12 ||M||` where it is
    /// zero to rounding), and so at the default share.
    #[test]
    fn an_early_coarse_stop_that_spoils_the_bound_is_resumed() {
        for seed in 0..6u64 {
            let (p, group) = grouped_graph(2 + (seed % 3) as usize, 12, 0.5, 0.01, seed);
            let at = solve_multiple(&p, &MultipleSettings::default())
                .unwrap()
                .rotations;
            let lambdas = multipliers(&p, &at).unwrap();
            let a = ScalarAnalysis::grouped(&p, &group, usize::MAX)
                .unwrap()
                .unwrap();
            let c = edge_charges(&p, &at, &lambdas, &a.copies, a.beta).unwrap();
            let pencil = grouped_pencil(&c).unwrap();
            let m = scalar_operator(&p, &at, &lambdas, &c.deg_n);
            let groups = Groups::new(&a.components, &pencil.weights);
            let t_max = orthogonality_defect(&at).unwrap();
            let gauge = GaugeBounds::of(&gauge_terms(&p, &at, &lambdas), t_max);
            let stop = (pencil.zeta_free, COARSE_RELATIVE_RESIDUAL, None);
            let bound = |share| coarse_terms_gauged_sharing(&m, &groups, gauge, stop, share);
            let strict = bound(None).unwrap();
            for share in [f64::MAX, COARSE_GRAM_SHARE] {
                let early = bound(Some(share)).unwrap();
                let off = (early.lambda - strict.lambda).abs();
                // relative, or at rounding's scale where the bound is zero to rounding
                let limit = 1e-3 * strict.lambda.abs().max(1e-12 * m.row_abs());
                assert!(off <= limit, "seed {seed}, share {share:e}: {off:e}");
            }
        }
    }

    /// No time left: the factorisation is refused by its prediction, with the reason.
    #[test]
    fn the_grouped_comparison_keeps_to_the_time_left() {
        let (p, group) = grouped_graph(3, 12, 0.5, 0.01, 1);
        let solved = solve_multiple(&p, &MultipleSettings::default()).unwrap();
        let lambdas = multipliers(&p, &solved.rotations).unwrap();
        let at = &solved.rotations;
        let why = grouped_comparison(&p, at, &lambdas, &group, 1e-9, (usize::MAX, Some(0.0)))
            .unwrap()
            .unwrap_err();
        assert!(why.contains("time budget"), "{why}");
        let proof = grouped_comparison(&p, at, &lambdas, &group, 1e-9, (usize::MAX, Some(60.0)));
        assert!(proof.unwrap().is_ok());
    }
}
