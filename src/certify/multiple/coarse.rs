//! The coarse correction of the grouped comparisons (`paper-notes/certificates.md` `[D13]`,
//! "Groups", and `paper-notes/anisotropic.md` `[A15]`, "Regions"): when every group's pencil
//! is proven, `x1^T M x1 >= zeta |x1|^2` on the space `U` of the vectors whose weighted sums
//! vanish in every group, and the rest of `x` is `3k` coarse directions `E a` (`E = [1_g (x)
//! I_3]_g`). With any `X` and `V' = E + P X` (`P` a projector onto `U`), and any `R` with
//! `y^T M V' = y^T R` for every `y` in `U`,
//! `x^T M x >= a^T (V'^T M V' - R^T R / zeta) a >= min(0, lambda) kappa^2 |x|^2`.
//! The scalar comparison's groups (one weight per node) and the block comparison's (a `3 x 3`
//! weight per node) are the two [`CoarseSpace`]s; the operator, the correction by conjugate
//! gradients and the rigorous bound are shared here.

use crate::certify::multiple::block_operator::BlockOperator;
use crate::certify::multiple::multipliers::GaugeTerms;
use crate::linalg::UNIT_ROUNDOFF as U;
use crate::linalg::cholesky::gamma;
use crate::linalg::pcg::pcg_from;
use nalgebra::{DMatrix, Matrix3};

/// `zeta` of the block comparison's regions (`[A15]`, "Regions"), the margin each region's
/// block is proven above, as a fraction of the largest row sum: small against the regions'
/// headroom, large enough that the coarse correction's residual need not be driven below
/// rounding. (The scalar pencils take their own, `scalar::groups::PENCIL_ZETA_FRACTION`.)
pub(in crate::certify::multiple) const ZETA_FRACTION: f64 = 1e-7;

/// The relative residual the coarse correction's conjugate gradients aim at: its residual
/// `R` enters as `R^T R / zeta` against the coarse Gram matrix, whose non-gauge eigenvalues
/// are the flux between groups (large), and the gauge directions need none (`[D13]`,
/// "Groups").
pub(in crate::certify::multiple) const COARSE_RELATIVE_RESIDUAL: f64 = 1e-4;

/// A coarse column's conjugate gradients stop once its residual's `|r|^2` is at most this
/// share of `zeta` times its Gram entry (`solved_bound`, in the deflated components' bound
/// [`coarse_terms_gauged`]): the residual enters as `R^T R /
/// zeta` against the Gram matrix, and a column's own share of it is then small. At 10^5 nodes
/// in 6 regions (`[D13]`) the shares were about 0.3 after 5 iterations and 1e-3 after 7 (the
/// relative residual 1e-4), the Gram matrix's least eigenvalue kept at 29 % and 99.8 %.
pub(in crate::certify::multiple) const COARSE_GRAM_SHARE: f64 = 0.1;

/// The most conjugate-gradient iterations of the coarse correction.
const CG_MAX_ITERATIONS: usize = 600;

/// What every coarse space states about its groups: each node's group (`0..count`), their
/// number, and the bounds on the coarse coefficients (see [`CoarseSpace::kappa`]).
pub(in crate::certify::multiple) struct Layout<'a> {
    pub of: &'a [usize],
    pub count: usize,
    pub kappa: f64,
    pub kappa_last: f64,
}

/// The groups of a grouped comparison and their weights: the space `U` (every group's
/// weighted sum `sum_{i in g} W_i x_i` zero), a projector onto it and the residual's form.
pub(in crate::certify::multiple) trait CoarseSpace: Sync {
    /// The groups and their coefficients' bounds.
    fn layout(&self) -> &Layout<'_>;
    /// Each node's group, `0..count`.
    fn group_of(&self) -> &[usize] {
        self.layout().of
    }
    /// The number of groups.
    fn count(&self) -> usize {
        self.layout().count
    }
    /// `z <- fl(z - W c)`, `(W c)_i = W_i c_g` for some coefficients `c_g` per group (those of
    /// the orthogonal projection onto `U`, approximately): every such `z - W c` has the same
    /// product with every vector of `U`, so any `c` gives a valid residual.
    fn project(&self, z: &mut [f64]);
    /// A bound on `||p - (y - W c)||_2` for `p = fl(project(y))` and the `c` it used.
    fn projection_error(&self, y: &[f64], p: &[f64]) -> f64;
    /// `kappa`, with `|a|^2 <= kappa^2 |x|^2` for the weighted means `a` of every group.
    fn kappa(&self) -> f64 {
        self.layout().kappa
    }
    /// `kappa_k` of the last group alone: `|a_k| <= kappa_k |x|`.
    fn kappa_last(&self) -> f64 {
        self.layout().kappa_last
    }
    /// A bound on `||(I - P)(z - E)||_F` over the columns `z` (`P` the space's projector onto
    /// `U`, `E` the coarse directions): how far the computed `z` is from the `V'` it stands for.
    fn off_space(&self, z: &[Vec<f64>]) -> f64;
    /// Coarse directions besides the groups' constant ones (`[A16]`, "Deflation"), after them
    /// in [`coarse_terms_gauged`]'s columns: a space with any must bound their coefficients in
    /// `kappa` too and know them in `off_space`.
    fn extra_columns(&self) -> Vec<Vec<f64>> {
        Vec::new()
    }
}

/// The coarse directions' bounds: `rho >= ||Pi M V'||_2` (reported) and
/// `lambda <= lambda_min(V'^T M V' - (Pi M V')^T (Pi M V') / zeta)`.
pub(in crate::certify::multiple) struct Coarse {
    pub rho: f64,
    pub lambda: f64,
    /// `|b|^2 <= scale |a|^2` for the coefficients `b` the bound `x^T M x >= min(0, lambda)
    /// |b|^2` is in.
    pub scale: f64,
}

impl Coarse {
    /// The proven `mu_M <= lambda_min(M)`: `min(0, lambda) scale kappa^2` (`|a|^2 <= kappa^2
    /// |x|^2`).
    pub(in crate::certify::multiple) fn mu(&self, kappa: f64) -> f64 {
        self.lambda.min(0.0) * self.scale * kappa * kappa * (1.0 + 1e-10)
    }
}

/// `V' = E + Pi X` with `X` from conjugate gradients on `Pi M Pi X = -Pi M E` (block-Jacobi,
/// projected) to the relative residual `rel`, for every group but the last and for the gauge
/// directions `v0 = sum_g E_g`, the last group's `X` the gauge's less the others' sum (so the
/// gauge directions of `V'` carry their own correction, whose residual is relative to `Pi M
/// v0`, small at a critical point, and not the other columns' residuals); then `lambda`
/// bounded for the exact `V'` of the computed `X` (any `X` is valid: only the bound's size
/// depends on it). No column stops early (`solved_bound`): the gauge directions' Gram
/// eigenvalue, near zero, leaves no scale to stop against.
pub(in crate::certify::multiple) fn coarse_terms(
    m: &BlockOperator,
    groups: &impl CoarseSpace,
    (zeta, rel, stop_at): (f64, f64, Option<std::time::Instant>),
) -> Option<Coarse> {
    if !groups.extra_columns().is_empty() {
        // their coefficients are not in this bound's basis: only the gauged one takes them
        return None;
    }
    let dim = 3 * groups.group_of().len();
    let cols = 3 * groups.count();
    let coarse = coarse_columns(groups, cols);
    // the columns of every group but the last, then the gauge directions `v0_j`
    let gauge: Vec<Vec<f64>> = (0..3)
        .map(|j| (0..dim).map(|r| f64::from(u8::from(r % 3 == j))).collect())
        .collect();
    let targets: Vec<&Vec<f64>> = coarse[..cols - 3].iter().chain(&gauge).collect();
    // the last group's: the gauge directions' correction less the other groups'
    let assemble = |x: &[Vec<f64>]| {
        let mut x = x.to_vec();
        for j in 0..3 {
            let mut last = x[cols - 3 + j].clone();
            for xc in x[..cols - 3].iter().skip(j).step_by(3) {
                last.iter_mut().zip(xc).for_each(|(l, v)| *l -= v);
            }
            x[cols - 3 + j] = last;
        }
        x
    };
    let columns = (coarse.as_slice(), targets.as_slice());
    let stop = (zeta, rel, stop_at);
    let (_, (lambda, rho, _)) = solved_bound(m, groups, columns, &assemble, stop, None)?;
    Some(Coarse {
        rho,
        lambda,
        scale: 1.0,
    })
}

/// The gauge directions' own bounds, from the data in double-double (`[D15]`):
/// `rho1 >= ||M v0||_F` and `v0^T M v0 >= -rho0 I`.
#[derive(Debug, Clone, Copy)]
pub(in crate::certify::multiple) struct GaugeBounds {
    pub rho0: f64,
    pub rho1: f64,
}

impl GaugeBounds {
    /// From the estimate's `S Y` terms ([`GaugeTerms`]) and the rotations' orthogonality defect
    /// `t_max`: `rho0 = h`, and `||M v0|| = ||D^T S Y|| <= ||D|| ||S Y|| <= (1 + t_max) rho`.
    pub(in crate::certify::multiple) fn of(terms: &GaugeTerms, t_max: f64) -> Self {
        GaugeBounds {
            rho0: terms.h,
            rho1: terms.rho * (1.0 + t_max) * (1.0 + 4.0 * U),
        }
    }
}

/// The coarse bound with the gauge directions bounded apart (`[A15]`, "Regions"): in the basis
/// `b = (a_1 - a_k, ..., a_{k-1} - a_k, a_W, a_k)` of the coarse coefficients
/// (`|b|^2 <= (2k - 1) |a|^2`; `a_W` those of the space's extra columns, none but in deflated
/// regions) the
/// coarse directions are the first `k - 1` groups' `E_g` and the extra columns (corrected as in
/// [`coarse_terms`], their `G_f - 2 R_f^T R_f / zeta` bounded by `lambda_f`) and `v0`, for
/// which `R_v = M v0` (valid: `y^T M v0 = y^T R_v`), so `||R_v|| <= rho1`, `v0^T M v0 >=
/// -rho0`, and the cross block `B = V_f'^T M v0` has `||B|| <= ||V_f'||_F rho1`. With
/// `R^T R <= 2 blkdiag(R_f^T R_f, R_v^T R_v)` and `2 b_f^T B b_v >= -||B||^2 |b_f|^2 / t -
/// t |b_v|^2`: `lambda = min(lambda_f - ||B||^2 / t, -rho0 - 2 rho1^2 / zeta - t)`, `t =
/// 2 ||B||^2 / lambda_f` when `lambda_f > 0`. Where the estimate's stationarity is far below
/// rounding of `M`'s products (anisotropic information, weights of `1e5`), the gauge entries
/// of a computed `V'^T M V'` would carry errors of `|M| |v0|^2 u`; these need none. The
/// conjugate gradients stop a column early at [`COARSE_GRAM_SHARE`] (`solved_bound`).
pub(in crate::certify::multiple) fn coarse_terms_gauged(
    m: &BlockOperator,
    groups: &impl CoarseSpace,
    gauge: GaugeBounds,
    stop: (f64, f64, Option<std::time::Instant>),
) -> Option<Coarse> {
    coarse_terms_gauged_sharing(m, groups, gauge, stop, Some(COARSE_GRAM_SHARE))
}

/// [`coarse_terms_gauged`] with the conjugate gradients' early stop at `share` (`None`: none).
pub(in crate::certify::multiple) fn coarse_terms_gauged_sharing(
    m: &BlockOperator,
    groups: &impl CoarseSpace,
    gauge: GaugeBounds,
    (zeta, rel, stop_at): (f64, f64, Option<std::time::Instant>),
    share: Option<f64>,
) -> Option<Coarse> {
    let mut coarse = coarse_columns(groups, 3 * groups.count() - 3);
    coarse.extend(groups.extra_columns());
    let targets: Vec<&Vec<f64>> = coarse.iter().collect();
    let (lambda_f, rho_f, z_norm) = if coarse.is_empty() {
        (f64::INFINITY, 0.0, 0.0)
    } else {
        let columns = (coarse.as_slice(), targets.as_slice());
        // R_f^T R_f against zeta / 2: the factor 2 of the split of R^T R
        let split = (0.5 * zeta, rel, stop_at);
        let (z, (lambda_f, rho_f, delta)) =
            solved_bound(m, groups, columns, &|x| x.to_vec(), split, share)?;
        let z_norm = z.iter().flatten().map(|v| v * v).sum::<f64>().sqrt()
            * (1.0 + gamma(3 * z.len() * groups.group_of().len()));
        (lambda_f, rho_f, z_norm + delta)
    };
    let b = z_norm * gauge.rho1 * (1.0 + 4.0 * U);
    let gauge_part = -gauge.rho0 - 2.0 * gauge.rho1 * gauge.rho1 / zeta;
    let rho = rho_f.max(gauge.rho1);
    // the flux part nonnegative: only b_v = a_k is left, |a_k| <= kappa_k |x|
    let (lambda, scale) = if lambda_f > 0.0 {
        let t = 2.0 * b * b / lambda_f;
        let (kappa, last) = (groups.kappa(), groups.kappa_last());
        (gauge_part - t, (last / kappa).powi(2) * (1.0 + 1e-10))
    } else {
        let lambda = (lambda_f - b).min(gauge_part - b);
        (lambda, (2 * groups.count() - 1) as f64)
    };
    let lambda = lambda * (1.0 + 1e-10);
    (lambda.is_finite() && scale.is_finite()).then_some(Coarse { rho, lambda, scale })
}

/// The first `cols` coarse directions `E_c` (column `c`: coordinate `c % 3` on group `c / 3`).
fn coarse_columns(groups: &impl CoarseSpace, cols: usize) -> Vec<Vec<f64>> {
    let dim = 3 * groups.group_of().len();
    (0..cols)
        .map(|c| {
            let mut e = vec![0.0; dim];
            for (i, &g) in groups.group_of().iter().enumerate() {
                if 3 * g + c % 3 == c {
                    e[3 * i + c % 3] = 1.0;
                }
            }
            e
        })
        .collect()
}

/// The coarse columns' corrections `X` from their targets' (`solved_bound`).
type Assemble<'a> = &'a dyn Fn(&[Vec<f64>]) -> Vec<Vec<f64>>;

/// `(lambda, rho, delta)` of [`bound_coarse`].
type CoarseBound = (f64, f64, f64);

/// The columns `z = E + Pi X` of the coarse directions `coarse` and their bound
/// ([`bound_coarse`] against `zeta`): `X = assemble(X_T)` from the corrections `X_T` of the
/// `targets` ([`corrections`]). With a `share` ([`COARSE_GRAM_SHARE`]) the conjugate
/// gradients stop a column once its residual is small against its own Gram entry; where the
/// residual's term then takes more than half of the Gram matrix's least eigenvalue
/// ([`bound_coarse`]) they go on from there to the relative residual `rel` alone and bound
/// again (any `X` gives a valid bound: the stop decides only its size), unless `stop_at` has
/// passed. The resumed solve forms its right-hand sides again (one product per column) and
/// holds the stopped `X` beside its own vectors (one more set of columns at its peak).
fn solved_bound(
    m: &BlockOperator,
    groups: &impl CoarseSpace,
    (coarse, targets): (&[Vec<f64>], &[&Vec<f64>]),
    assemble: Assemble<'_>,
    (zeta, rel, stop_at): (f64, f64, Option<std::time::Instant>),
    share: Option<f64>,
) -> Option<(Vec<Vec<f64>>, CoarseBound)> {
    let gram_stop = share.map(|s| s * zeta);
    let (x, early) = corrections(m, groups, targets, None, (gram_stop, rel, stop_at))?;
    let z = corrected(groups, coarse, assemble(&x));
    let (bound, spoiled) = bound_coarse(m, groups, &z, zeta)?;
    // past `stop_at` the resumed iterations would run none, only their products and a bound
    let late = stop_at.is_some_and(|t| std::time::Instant::now() >= t);
    if !early || !spoiled || late {
        return Some((z, bound));
    }
    drop(z);
    let (x, _) = corrections(m, groups, targets, Some(&x), (None, rel, stop_at))?;
    let z = corrected(groups, coarse, assemble(&x));
    let (bound, _) = bound_coarse(m, groups, &z, zeta)?;
    Some((z, bound))
}

/// `X` from conjugate gradients on `Pi M Pi X = -Pi M T` for the columns `T` (block-Jacobi,
/// projected), from `from` (zero when `None`), to the relative residual `rel`, stopping at
/// `stop_at`; with `gram_stop = share zeta`, a column stops as soon as `|r|^2 <= share zeta
/// G_tt` too, `G_tt = (t + Pi x)^T M (t + Pi x) = t^T M t - b^T x - x^T r` (`b = -Pi M t`, `r = b -
/// Pi M Pi x`) its Gram entry. Also whether any column stopped so (before `rel`).
fn corrections(
    m: &BlockOperator,
    groups: &impl CoarseSpace,
    targets: &[&Vec<f64>],
    from: Option<&[Vec<f64>]>,
    (gram_stop, rel, stop_at): (Option<f64>, f64, Option<std::time::Instant>),
) -> Option<(Vec<Vec<f64>>, bool)> {
    let dim = 3 * groups.group_of().len();
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    // the right-hand sides `-Pi M t` and `t^T M t`, the columns on both threads
    let mut columns: Vec<&Vec<f64>> = targets.to_vec();
    let parallel = dim * columns.len() >= crate::linalg::threads::PARALLEL_EDGES;
    let parts = crate::linalg::threads::in_chunks(&mut columns, parallel, |_, part| {
        let each = |e: &&Vec<f64>| {
            let mut y = vec![0.0; dim];
            m.times(e, &mut y);
            let own = dot(e, &y);
            groups.project(&mut y);
            y.iter_mut().for_each(|v| *v = -*v);
            (y, own)
        };
        part.iter().map(each).collect::<Vec<_>>()
    });
    let (rhs, own): (Vec<Vec<f64>>, Vec<f64>) = parts.into_iter().flatten().unzip();
    let inverses: Vec<Matrix3<f64>> = m
        .diagonal()
        .iter()
        .map(|d| {
            d.cholesky()
                .map(|c| c.inverse())
                .unwrap_or_else(Matrix3::identity)
        })
        .collect();
    let operator = |x: &[f64], y: &mut [f64]| {
        let mut p = x.to_vec();
        groups.project(&mut p);
        m.times(&p, y);
        groups.project(y);
    };
    let precondition = |r: &[&[f64]], z: &mut [&mut [f64]]| {
        for (r, z) in r.iter().zip(z.iter_mut()) {
            for (i, inv) in inverses.iter().enumerate() {
                let v = inv * nalgebra::Vector3::new(r[3 * i], r[3 * i + 1], r[3 * i + 2]);
                z[3 * i..3 * i + 3].copy_from_slice(v.as_slice());
            }
            groups.project(z);
        }
    };
    let early = std::sync::atomic::AtomicBool::new(false);
    let enough = |c: usize, x: &[f64], r: &[f64]| {
        let Some(share_zeta) = gram_stop else {
            return false;
        };
        let gram = own[c] - dot(&rhs[c], x) - dot(x, r);
        let small = dot(r, r) <= share_zeta * gram;
        if small {
            early.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        small
    };
    let limits = (CG_MAX_ITERATIONS, stop_at);
    let (x, _) = pcg_from(
        (&operator, &precondition),
        (&rhs, from),
        (rel, &enough),
        limits,
    )?;
    Some((x, early.into_inner()))
}

/// The columns `z = E + fl(project(X))`.
fn corrected(groups: &impl CoarseSpace, coarse: &[Vec<f64>], x: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    coarse
        .iter()
        .zip(x)
        .map(|(e, mut xc)| {
            groups.project(&mut xc);
            e.iter().zip(&xc).map(|(a, b)| a + b).collect()
        })
        .collect()
}

/// `(lambda, rho, delta)` for the computed columns `z`, and whether the residual's term took
/// more than half of the Gram matrix's least eigenvalue `g` (`lambda_min(H) < g - |g| / 2`, both
/// estimated in floating point: a choice, no bound) (`z - E` not exactly in `U`: `V' = E + Pi (z - E)`
/// differs from `z` by `dz = (I - Pi)(z - E)`, of norm at most `delta`). With `R = Pi M V' =
/// fl(Pi fl(M z)) + dR`, `||dR|| <= eps` (the product's and the projection's rounding, and
/// `||M|| delta`): `R^T R <= 2 R'^T R' + 2 eps^2 I`, and `V'^T M V' = z^T M z -
/// 2 sym(z^T M dz) + dz^T M dz`; the Gram matrices by blocks summed pairwise, with their errors.
fn bound_coarse(
    m: &BlockOperator,
    groups: &impl CoarseSpace,
    z: &[Vec<f64>],
    zeta: f64,
) -> Option<(CoarseBound, bool)> {
    let dim = 3 * groups.group_of().len();
    let cols = z.len();
    let delta = groups.off_space(z);
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt() * (1.0 + gamma(dim));
    let (mut ys, mut ps) = (Vec::with_capacity(cols), Vec::with_capacity(cols));
    let (mut eps_sq, mut y_sq, mut r_sq) = (0.0f64, 0.0f64, 0.0f64);
    let mut y_errs = Vec::with_capacity(cols);
    // the columns' products on both threads, summed in column order (the same numbers)
    let product = |zc: &Vec<f64>| {
        let mut y = vec![0.0; dim];
        m.times(zc, &mut y);
        let err = m.product_error() * norm(zc);
        let mut p = y.clone();
        groups.project(&mut p);
        let e = err + groups.projection_error(&y, &p);
        (y, p, err, e)
    };
    let mut columns: Vec<&Vec<f64>> = z.iter().collect();
    let parallel = dim * cols >= crate::linalg::threads::PARALLEL_EDGES;
    let products = crate::linalg::threads::in_chunks(&mut columns, parallel, |_, part| {
        part.iter().map(|zc| product(zc)).collect::<Vec<_>>()
    });
    for (y, p, err, e) in products.into_iter().flatten() {
        let (ny, np) = (norm(&y), norm(&p));
        eps_sq += e * e;
        y_sq += ny * ny;
        r_sq += np * np;
        y_errs.push(err);
        ys.push(y);
        ps.push(p);
    }
    let m_norm = m.norm();
    let eps = (eps_sq.sqrt() + m_norm * delta) * (1.0 + 1e-10);
    let r_norm = r_sq.sqrt();
    let rho = (r_norm + eps) * (1.0 + 1e-10);
    // blocks summed pairwise: the error grows with the block and the depth of the tree, not
    // with `3n` (whose `gamma(3n)` alone failed 10^5-node graphs in 8 regions)
    let (g, r, g_err_sq, r_err_sq) = gram_matrices((z, &ys, &ps), &y_errs, norm);
    // R^T R <= 2 R'^T R' + 2 eps^2 I: the doubled R'^T R' is small against the flux's
    // eigenvalues of G, and nearly zero on the gauge directions, where G is too
    let h = (&g + g.transpose()) * 0.5 - (&r + r.transpose()) * (1.0 / zeta);
    let h_err = g_err_sq.sqrt()
        + 2.0 * r_err_sq.sqrt() / zeta
        + 2.0 * eps * eps / zeta
        + 4.0 * U * (g.norm() + 2.0 * r.norm() / zeta);
    let least = |a: DMatrix<f64>| a.symmetric_eigenvalues().min();
    let g_least = least((&g + g.transpose()) * 0.5);
    let spoiled = least(h.clone()) < g_least - 0.5 * g_least.abs();
    let lambda_h = verified_min_eigenvalue(&h)? - h_err;
    // the columns' own error: V'^T M V' against z^T M z
    let lambda = (lambda_h - 2.0 * (y_sq.sqrt() + eps_sq.sqrt()) * delta - m_norm * delta * delta)
        * (1.0 + 1e-10)
        - f64::MIN_POSITIVE;
    (rho.is_finite() && lambda.is_finite()).then_some(((lambda, rho, delta), spoiled))
}

/// Columns of `3n` values.
type Columns<'a> = &'a [Vec<f64>];

/// `G = z^T Y` and `R = P^T P` (`Y` the columns' products `M z`, `P` their projections), with
/// the sums of their entries' squared error bounds (`y_errs` the products' own errors, `norm` a
/// norm bounded above): by blocks of [`GRAM_BLOCK`] rows, each block's Gram matrices a matrix
/// product (its entries sums of `GRAM_BLOCK` terms in any order), the blocks' summed
/// pairwise within each thread's run of blocks and the runs' sums pairwise again (each a tree
/// no deeper than the blocks' count's), so each product passes through at most
/// [`gram_depth`] additions and
/// `|fl(x . y) - x . y| <= gamma(depth) sum |x_i y_i|` (Higham 2002, section 3.1 and 4.2),
/// with `sum |x_i y_i|` the same products' magnitudes, computed the same way.
fn gram_matrices(
    (z, ys, ps): (Columns<'_>, Columns<'_>, Columns<'_>),
    y_errs: &[f64],
    norm: impl Fn(&[f64]) -> f64 + Sync,
) -> (DMatrix<f64>, DMatrix<f64>, f64, f64) {
    let (dim, cols) = (z.first().map_or(0, Vec::len), z.len());
    let g_dot = gamma(gram_depth(dim) + 2);
    let mut blocks: Vec<usize> = (0..dim.div_ceil(GRAM_BLOCK)).collect();
    let parallel = dim * cols >= crate::linalg::threads::PARALLEL_EDGES;
    let parts = crate::linalg::threads::in_chunks(&mut blocks, parallel, |_, part| {
        sum_pairwise(part, &|b| {
            block_grams((z, ys, ps), b * GRAM_BLOCK..dim.min((b + 1) * GRAM_BLOCK))
        })
    });
    let parts: Vec<[DMatrix<f64>; 4]> = parts.into_iter().flatten().collect();
    let [g, g_mag, r, r_mag] = sum_pairwise(&parts, &|p| p.clone())
        .unwrap_or_else(|| std::array::from_fn(|_| DMatrix::zeros(cols, cols)));
    let norms: Vec<f64> = z.iter().map(|c| norm(c)).collect();
    let (mut g_err_sq, mut r_err_sq) = (0.0f64, 0.0f64);
    let mut r_sym = DMatrix::zeros(cols, cols);
    for a in 0..cols {
        for b in 0..cols {
            let e = norms[a] * y_errs[b] + g_dot * g_mag[(a, b)] * (1.0 + g_dot);
            g_err_sq += e * e;
            // `R`'s upper part, mirrored (a matrix product need not sum both orders alike)
            let (lo, hi) = (a.min(b), a.max(b));
            r_sym[(a, b)] = r[(lo, hi)];
            let e = g_dot * r_mag[(lo, hi)] * (1.0 + g_dot);
            r_err_sq += e * e;
        }
    }
    (g, r_sym, g_err_sq, r_err_sq)
}

/// Rows per block of [`gram_matrices`].
const GRAM_BLOCK: usize = 256;

/// One block's `(z^T Y, |z|^T |Y|, P^T P, |P|^T |P|)` over the rows `rows`.
fn block_grams(
    (z, ys, ps): (Columns<'_>, Columns<'_>, Columns<'_>),
    rows: std::ops::Range<usize>,
) -> [DMatrix<f64>; 4] {
    let take = |c: Columns<'_>| DMatrix::from_fn(rows.len(), c.len(), |i, k| c[k][rows.start + i]);
    let (zb, yb, pb) = (take(z), take(ys), take(ps));
    let (za, ya, pa) = (zb.abs(), yb.abs(), pb.abs());
    [
        zb.tr_mul(&yb),
        za.tr_mul(&ya),
        pb.tr_mul(&pb),
        pa.tr_mul(&pa),
    ]
}

/// The matrices `make(item)` of `items` summed pairwise (halves first; made as the tree is
/// walked, so at most one per level is held), `None` for none.
fn sum_pairwise<T>(
    items: &[T],
    make: &dyn Fn(&T) -> [DMatrix<f64>; 4],
) -> Option<[DMatrix<f64>; 4]> {
    match items {
        [] => None,
        [one] => Some(make(one)),
        _ => {
            let (a, b) = items.split_at(items.len() / 2);
            let (a, b) = (sum_pairwise(a, make)?, sum_pairwise(b, make)?);
            Some(std::array::from_fn(|k| &a[k] + &b[k]))
        }
    }
}

/// The most additions a product of [`gram_matrices`] over `len` rows passes through: those of
/// its block's sum, then at most `ceil(log2 B)` levels of a thread's pairwise sum over its `c
/// <= B` blocks and as many of the threads' (`B` the blocks).
fn gram_depth(len: usize) -> usize {
    let (mut levels, mut at) = (0, len.div_ceil(GRAM_BLOCK));
    while at > 1 {
        at = at.div_ceil(2);
        levels += 1;
    }
    GRAM_BLOCK + 2 * levels
}

/// A proven lower bound on `lambda_min(a)` of a small symmetric matrix: the dense eigenvalues'
/// estimate less a margin, proven by a Cholesky factorisation of `fl(a - tau I)` (Higham, Thm
/// 10.3: the computed factor is exact for `fl(a - tau I) + E`, `|E| <= gamma(d + 1) |L| |L^T|`;
/// the shift's rounding, at most `u |a_ii - tau|` per diagonal entry, charged too).
pub(in crate::certify::multiple) fn verified_min_eigenvalue(a: &DMatrix<f64>) -> Option<f64> {
    let d = a.nrows();
    let estimate = crate::linalg::dense::symmetric_eigenvalues(a)?
        .first()
        .copied()?;
    let scale = a.norm().max(f64::MIN_POSITIVE);
    for margin in [1e-12, 1e-9, 1e-6] {
        let tau = estimate - margin * scale;
        let shifted = a - DMatrix::identity(d, d) * tau;
        if let Some(c) = crate::linalg::dense::DenseCholesky::new(&shifted) {
            let diagonal = (0..d).map(|i| (a[(i, i)] - tau).abs()).fold(0.0, f64::max);
            let proven =
                tau - (gamma(d + 1) * c.factor_norm_squared() + 2.0 * U * diagonal) * (1.0 + 1e-10);
            if proven.is_finite() {
                return Some(proven);
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::{GRAM_BLOCK, gram_matrices};
    use crate::linalg::compensated::Accumulator;
    use nalgebra::DMatrix;
    use rand::{Rng, SeedableRng};

    /// The blocked Gram matrices against the exact sums (compensated, each entry rounded once):
    /// within their stated error bounds, for lengths below, at and past a block (and of 40
    /// blocks, summed on the machine's threads), magnitudes from 1e-3 to 1e3 and both signs;
    /// `R` symmetric.
    #[test]
    fn blocked_gram_matrices_are_within_their_bounds() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for dim in [
            1,
            7,
            GRAM_BLOCK,
            GRAM_BLOCK + 1,
            5 * GRAM_BLOCK + 13,
            40 * GRAM_BLOCK + 5,
        ] {
            let cols = 6;
            let mut column = || -> Vec<f64> {
                (0..dim)
                    .map(|_| (rng.random::<f64>() - 0.5) * 10f64.powf(rng.random_range(-3.0..3.0)))
                    .collect()
            };
            let z: Vec<Vec<f64>> = (0..cols).map(|_| column()).collect();
            let ys: Vec<Vec<f64>> = (0..cols).map(|_| column()).collect();
            let ps: Vec<Vec<f64>> = (0..cols).map(|_| column()).collect();
            let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
            let (g, r, g_err_sq, r_err_sq) = gram_matrices((&z, &ys, &ps), &[0.0; 6], norm);
            let exact = |x: &[f64], y: &[f64]| {
                let mut acc = Accumulator::default();
                x.iter().zip(y).for_each(|(a, b)| acc.add_product(*a, *b));
                acc.value()
            };
            let g_exact = DMatrix::from_fn(cols, cols, |a, b| exact(&z[a], &ys[b]));
            let r_exact = DMatrix::from_fn(cols, cols, |a, b| exact(&ps[a], &ps[b]));
            assert!((&g - &g_exact).norm() <= g_err_sq.sqrt(), "dim {dim}: G");
            assert!((&r - &r_exact).norm() <= r_err_sq.sqrt(), "dim {dim}: R");
            assert_eq!(r, r.transpose(), "dim {dim}");
            // the values themselves, not only within a loose bound
            assert!(
                (&g - &g_exact).norm() <= 1e-12 * g_exact.norm(),
                "dim {dim}"
            );
        }
    }
}
