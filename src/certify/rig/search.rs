//! The couplings' search (`paper-notes/conjugate.md` `[H21]`, "The search", "Large rigs"):
//! where the least-norm couplings leave the augmented graph's `S` indefinite, the proximal
//! spectral bundle of [`super::bundle`] moves each frame's pairs' sums and the trace couplings
//! towards the largest `lambda_min(S)`, on the dense `S` of a rig of at most
//! [`SEARCH_MAX_IMAGES`] images and on the sparse one of a larger rig ([`super::wide`]). Only a
//! choice: whatever it returns is handed to the augmented graph's ladder, which proves its bound
//! or does not ([`super::couplings`]: any pseudo-edges give a sound bound).

use super::bundle::{Dense, Space, Spectrum, added_sums, stopped};
use super::couplings::{Coupled, PairSum};
use super::traces::Traces;
use super::wide::Wide;
use crate::certify::multiple::multipliers::{FirstOrder, certificate_matrix};
use crate::deadline::Deadline;
use crate::error::Result;
use crate::linalg::cholesky::to_dense;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::DMatrix;

/// Most images a rig's search takes: a dense `3N x 3N` eigen-decomposition and a Clarabel model
/// per round (30 frames and 6 sensors, `3N = 540`: 17.9 s for four rigs' solves and
/// certificates, `docs/benchmarks.md` "Small rigs along a path").
pub(crate) const SEARCH_MAX_IMAGES: usize = 300;

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
    /// `start` and `reached` are estimates of `S` grounded at image 0 ([`Wide`]), not the
    /// dense `S`'s gauged `lambda_min`.
    pub grounded: bool,
}

/// Dense `3N x 3N` matrices the search holds at once (`S` at the start, at the point and at the
/// candidate, the two eigenvector matrices and the one being formed), charged against the
/// memory budget.
const DENSE_COPIES: u64 = 6;

/// The bytes of the search's dense matrices for `images` images.
fn dense_bytes(images: usize) -> u64 {
    DENSE_COPIES * 8 * (3 * images as u64).pow(2)
}

/// The search from `coupled` (the least-norm couplings at the image rotations `x` of the
/// rig's view graph `images`), or `None` when it does not apply (the dense or the sparse
/// search's matrices over their share of `max_bytes`, frames photographed by different
/// sensors, `S` already positive semidefinite, an estimate too far from critical for any
/// couplings: [`hopeless`]) or finds no positive `lambda_min`.
pub(crate) fn search(
    coupled: &Coupled,
    images: &MultipleProblem,
    (x, sensors): (&[Rotation], &[Rotation]),
    limits: Limits,
) -> Result<Option<Searched>> {
    let per_frame = &coupled.layout.per_frame;
    let Some(k) = uniform(per_frame) else {
        return Ok(None);
    };
    let first = FirstOrder::at(&coupled.graph, x)?;
    let s = certificate_matrix(&coupled.graph, &first.lambdas)?;
    if let Some(why) = hopeless(first.stationarity, trace(s.as_ref()), x.len(), limits.gap) {
        stopped(&why);
        return Ok(None);
    }
    let edges = coupled.graph.edges().iter().map(|e| (e.i, e.j));
    let space = Space::new(per_frame, edges, (x, sensors), k);
    let run = if x.len() <= SEARCH_MAX_IMAGES {
        if dense_bytes(x.len()) > limits.max_bytes / 2 {
            return Ok(None);
        }
        let s = to_dense(s.as_ref());
        let dense = Dense(gauged(0.5 * (&s + s.transpose()), x));
        let Some(start) = dense.at(&space, &space.zero()) else {
            return Ok(None);
        };
        space
            .bundle(&dense, start, limits.deadline)
            .map(|run| (run, false))
    } else {
        let wide = Wide::new(coupled, images, (x, sensors), &space, limits.max_bytes);
        // the least-norm couplings' `S`, built above, is the search's start
        let Some((wide, start)) = wide.and_then(|w| w.spectrum(s).map(|start| (w, start))) else {
            return Ok(None);
        };
        space
            .bundle(&wide, start, limits.deadline)
            .map(|run| (run, true))
    };
    Ok(run.map(|(found, grounded)| Searched {
        sums: added_sums(&coupled.sums, &space.with_flows(&found.moves).sums),
        traces: found.moves.traces,
        start: found.start,
        reached: found.reached,
        rounds: found.rounds,
        grounded,
    }))
}

/// `tr(s)` of a sparse matrix.
fn trace(s: faer::sparse::SparseColMatRef<'_, usize, f64>) -> f64 {
    let (cp, ri, v) = (s.col_ptr(), s.row_idx(), s.val());
    (0..s.ncols())
        .flat_map(|c| (cp[c]..cp[c + 1]).filter(move |&k| ri[k] == c))
        .map(|k| v[k])
        .sum()
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
            "not a critical point: the stationarity residual {rho:.1e} needs lambda_min(S without a node) >= {needed:.1e}, above tr(S) / (3N - 3) = {mean:.1e}"
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
            searched_rig((30, 4, 1), scalar);
        }
    }

    /// The same on a rig over [`super::SEARCH_MAX_IMAGES`] (60 frames, 6 sensors: 360 images),
    /// searched with sparse `S` and Lanczos estimates ([`super::Wide`]); checked against the
    /// dense `S` rebuilt from its couplings.
    #[test]
    fn the_wide_search_makes_s_positive_definite_where_the_least_norm_couplings_do_not() {
        const { assert!(60 * 6 > super::SEARCH_MAX_IMAGES) };
        searched_rig((60, 6, 2), false);
    }

    /// A rig of `frames` frames along a path and `sensors` estimated sensors (generator seed
    /// `seed`), solved, its least-norm couplings' `S` indefinite, searched: `S` of the searched
    /// couplings positive definite (dense, with its own multipliers) at about the reported
    /// `lambda_min` (the dense search's; the wide one's is `S` grounded, only its sign), the
    /// estimate still critical, no charge added.
    fn searched_rig((frames, sensors, seed): (usize, usize, u64), scalar: bool) {
        {
            let scene = RigScene {
                frames,
                sensors,
                noise_sigma: 0.01,
                anisotropy: 9.0,
                extra_edge_span: 10,
                seed,
                ..Default::default()
            };
            let (p, _) = scene.generate();
            // with scalar weights `tr(H) / 3`: the isotropic rung's graph
            let p = if scalar { p.scalar() } else { p };
            let s = solve_rig(&p, &RigSettings::default()).unwrap();
            let (frames, sensors, _) =
                polish_passes(&p, (s.frames, s.sensors), 10, (None, u64::MAX)).unwrap();
            let c = couple(&p, &frames, &sensors, u64::MAX).unwrap().unwrap();
            let x = p.image_rotations(&frames, &sensors);
            let before = dense_min(&c.graph, &x);
            assert!(before < 0.0, "{before}");
            let limits = super::Limits {
                deadline: None,
                max_bytes: u64::MAX,
                gap: 1e-6 * p.cost(&frames, &sensors),
            };
            let images = p.image_graph().unwrap();
            let found = search(&c, &images, (&x, &sensors), limits)
                .unwrap()
                .expect("a positive lambda_min");
            assert!(
                found.start < 0.0
                    && (found.grounded || (found.start - before).abs() <= 1e-6 * before.abs()),
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
            // the sizes the large search charges (`Wide::new`) bound the point's graph: its
            // pseudo-edges and the image pairs they join beyond the view graph's
            let edges = c.graph.edges().iter().map(|e| (e.i, e.j));
            let space =
                super::Space::new(&c.layout.per_frame, edges, (&x, &sensors), sensors.len());
            assert!(again.pseudo_edges <= space.pseudo_edges_at_most());
            let pairs = |g: &MultipleProblem| {
                let all = g.edges().iter().map(|e| (e.i.min(e.j), e.i.max(e.j)));
                all.collect::<std::collections::BTreeSet<_>>().len()
            };
            assert!(pairs(&again.graph) <= images.edges().len() + space.pseudo_pairs_at_most());
            assert_eq!(found.grounded, x.len() > super::SEARCH_MAX_IMAGES);
            assert!(
                found.grounded || (after - found.reached).abs() <= 1e-6 * before.abs(),
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
