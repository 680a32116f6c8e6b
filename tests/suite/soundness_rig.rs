//! Rig certificates on the data where rounding decides (`paper-notes/conjugate.md`, issue 36):
//! noise-free rigs, whose minimum is the truth's cost (about `1e-30`), with weights from `0.01`
//! to `100`, scalar or anisotropic, sensors known or estimated, with and without soft gravity
//! priors: no bound above the truth's cost written out from the definitions. And the rig's
//! cost counts its soft priors whatever its edges' weights are.

use rotavg::Rotation;
use rotavg::certify::{CertifySettings, certify_rig};
use rotavg::multiple::MultipleProblem;
use rotavg::multiple::anisotropic::Information;
use rotavg::multiple::gravity::GravityPriors;
use rotavg::rig::{RigProblem, RigScene, RigTruth};
use rotavg::so3::perturb;

/// The rig's cost term by term: `sum w ||X_j - R X_i||^2` (or `[A1]`'s anisotropic term) and
/// every soft prior's `2 w ||X_a d - g_a||^2`.
fn written_out_cost(p: &RigProblem, frames: &[Rotation], sensors: &[Rotation]) -> f64 {
    let x = p.image_rotations(frames, sensors);
    let edges: f64 = match p.information() {
        // [A1]'s trace form, defined so; evaluated in double-double (plain floating point
        // knows it only to `u tr(H)` per edge: a noise-free cost of `-1e-11` is exact here)
        Some(info) => MultipleProblem::new(x.len(), p.edges().to_vec())
            .and_then(|g| g.with_information(info.to_vec()))
            .unwrap()
            .chordal_cost(&x),
        None => (p.edges().iter())
            .map(|e| {
                let r = x[e.j].matrix() - e.rotation.matrix() * x[e.i].matrix();
                e.weight * r.norm_squared()
            })
            .sum(),
    };
    let priors: f64 = p.gravity().map_or(0.0, |g| {
        (0..x.len())
            .filter_map(|a| {
                let d = g.world_down();
                Some(2.0 * g.prior_weight(a)? * (x[a] * d - g.direction(a)?).norm_squared())
            })
            .sum()
    });
    edges + priors
}

/// Noise-free rig `k`: 4-8 frames, 2-3 sensors, known or estimated, edges scaled by `scale`,
/// anisotropic (ratio 10) or not, with exact soft priors of weight `prior` or none.
fn rig(k: u64, scale: f64, anisotropic: bool, prior: Option<f64>) -> (RigProblem, RigTruth) {
    let (p, truth) = RigScene {
        frames: 4 + (k % 5) as usize,
        sensors: 2 + (k % 2) as usize,
        extra_edges_per_frame: 1 + (k % 2) as usize,
        cross_fraction: 0.5,
        noise_sigma: 0.0,
        known: k.is_multiple_of(3),
        anisotropy: if anisotropic { 10.0 } else { 1.0 },
        seed: k,
        ..Default::default()
    }
    .generate();
    let edges = (p.edges().iter())
        .map(|e| rotavg::multiple::Edge {
            weight: e.weight * scale,
            ..e.clone()
        })
        .collect();
    let mut q = p.scalar().with_edges(edges).unwrap();
    if let Some(info) = p.information() {
        let scaled = (info.iter())
            .map(|h| Information::new(h.matrix() * scale).unwrap())
            .collect();
        q = q.with_information(scaled).unwrap();
    }
    if let Some(w) = prior {
        let g = GravityPriors::new(truth.gravity(&q, 0.0, 0, k)).unwrap();
        q = q.with_gravity(g.with_weight(w).unwrap()).unwrap();
    }
    (q, truth)
}

/// The rig's cost with soft priors is the written-out sum at points away from the truth, for
/// scalar and anisotropic edges (it dropped the priors with information matrices).
#[test]
fn the_rigs_cost_counts_its_soft_priors_with_information_too() {
    let mut rng = <rand::rngs::StdRng as rand::SeedableRng>::seed_from_u64(3);
    for anisotropic in [false, true] {
        let (p, truth) = rig(4, 1.0, anisotropic, Some(5.0));
        let frames: Vec<Rotation> = (truth.frames.iter())
            .map(|f| perturb(f, 0.3, &mut rng))
            .collect();
        let (cost, expected) = (
            p.cost(&frames, &truth.sensors),
            written_out_cost(&p, &frames, &truth.sensors),
        );
        assert!(
            (cost - expected).abs() <= 1e-12 * expected,
            "anisotropic {anisotropic}: {cost} against {expected}"
        );
        assert!(p.prior_cost(&frames, &truth.sensors) > 1e-6 * expected);
    }
}

/// A planted wrong point: a rig with exact soft priors, certified at its truth turned by 30
/// degrees about a horizontal axis (every edge's residual unchanged, every prior's
/// `2 w ||X d - g||^2` grown by more than `0.5`). Not certified, and the certificate's upper
/// bound is the point's cost with its priors: with information matrices the rig's cost left
/// the priors out (upper bound `-2.8e-9` against `8.57` here; a bound near the truth's `0`
/// would have certified it).
#[test]
fn a_tilted_anisotropic_rig_with_soft_priors_is_not_certified() {
    for anisotropic in [false, true] {
        let (p, truth) = rig(4, 1.0, anisotropic, Some(1.0));
        let tilt = rotavg::so3::exp(&nalgebra::Vector3::new(std::f64::consts::FRAC_PI_6, 0.0, 0.0));
        let frames: Vec<Rotation> = truth.frames.iter().map(|f| f * tilt).collect();
        let (turned, at_truth) = (
            written_out_cost(&p, &frames, &truth.sensors),
            written_out_cost(&p, &truth.frames, &truth.sensors),
        );
        assert!(turned > at_truth + 0.5, "{turned} against {at_truth}");
        let c = certify_rig(&p, &frames, &truth.sensors, &CertifySettings::default())
            .unwrap()
            .certificate;
        assert!(
            !c.is_certified(),
            "anisotropic {anisotropic}: {}",
            c.explanation
        );
        assert!(
            (c.upper_bound - turned).abs() <= 1e-9 * turned,
            "anisotropic {anisotropic}: upper bound {} against {turned}",
            c.upper_bound
        );
    }
}

/// No rig certificate bounds a noise-free rig above the cost of its truth (its minimum, up to
/// the data's rounding, which the trace form's double-double evaluation keeps), for every
/// weight scale, scalar or anisotropic, sensors known or estimated, with soft priors or
/// without. Scalar rigs of one weight are certified; anisotropic ones (eigenvalue spreads to
/// `1e4`) and mixed weights (spread `1e2`-`1e4`) may be `gap_reported`, the rounding of the
/// largest weights against a tolerance of the smallest (SPEC section 3), never certified wrongly.
#[test]
fn rig_bounds_of_noise_free_rigs_stay_below_the_truth() {
    let mut failures = Vec::new();
    let (mut uniform, mut uniform_certified) = (0, 0);
    for k in 0..24u64 {
        let scale = [0.01, 0.016, 0.1, 100.0][(k % 4) as usize];
        let prior = [None, Some(0.01), Some(1.0)][(k / 4 % 3) as usize];
        for anisotropic in [false, true] {
            let (p, truth) = rig(k, scale, anisotropic, prior);
            let at_truth = written_out_cost(&p, &truth.frames, &truth.sensors);
            let c = certify_rig(
                &p,
                &truth.frames,
                &truth.sensors,
                &CertifySettings::default(),
            )
            .unwrap()
            .certificate;
            let lb = c.lower_bound.unwrap_or(f64::NEG_INFINITY);
            if lb > at_truth {
                failures.push(format!(
                    "rig {k} (scale {scale}, priors {prior:?}, anisotropic {anisotropic}): \
                     bound {lb:e} above the truth's cost {at_truth:e} ({})",
                    c.method
                ));
            }
            if !anisotropic && prior.is_none_or(|w| w == scale) {
                uniform += 1;
                uniform_certified += usize::from(c.is_certified());
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert_eq!(
        uniform_certified, uniform,
        "scalar rigs of one weight are certified"
    );
}
