//! `rotavg::certify::spectrum`: the k smallest eigenvalues of a certificate matrix (estimates)
//! checked against independent dense eigensolvers (faer's self-adjoint eigenvalues, not the
//! nalgebra solver the dense path uses) on random instances, and against the closed form of a
//! noise-free planted instance: there `S = D (L (x) I_3) D^T` with `D = blkdiag(R_i)` orthogonal
//! (paper-notes/certificates.md [D14]), so the spectrum of `S` is the scalar weighted graph
//! Laplacian's, each eigenvalue with multiplicity 3.

use faer::Side;
use faer::sparse::SparseColMat;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::certify::CertifySettings;
use rotavg::certify::SpectrumSettings;
use rotavg::certify::multiple::{certificate_matrix, lower_bound_from_multipliers, multipliers};
use rotavg::certify::spectrum::{SpectrumMethod, certificate_spectrum, smallest_eigenvalues};
use rotavg::multiple::MultipleProblem;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::so3::random_rotation;

/// All eigenvalues of a sparse symmetric matrix, ascending, by faer's dense solver.
fn faer_eigenvalues(s: &SparseColMat<usize, f64>) -> Vec<f64> {
    let d = s.to_dense();
    let mut v = d.self_adjoint_eigenvalues(Side::Lower).unwrap();
    v.sort_by(f64::total_cmp);
    v
}

/// Scalar weighted Laplacian `L` of the graph (n x n), eigenvalues ascending (faer dense).
fn scalar_laplacian_eigenvalues(p: &MultipleProblem) -> Vec<f64> {
    let n = p.num_rotations();
    let mut l = faer::Mat::<f64>::zeros(n, n);
    for e in p.edges() {
        l[(e.i, e.i)] += e.weight;
        l[(e.j, e.j)] += e.weight;
        l[(e.i, e.j)] -= e.weight;
        l[(e.j, e.i)] -= e.weight;
    }
    let mut v = l.self_adjoint_eigenvalues(Side::Lower).unwrap();
    v.sort_by(f64::total_cmp);
    v
}

fn assert_close(got: &[f64], want: &[f64], tol: f64, what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (g - w).abs() <= tol,
            "{what}: value {k}: {g} vs {w} (tol {tol})\n got {got:?}\nwant {want:?}"
        );
    }
}

/// Random instances away from the optimum (random estimate: S indefinite, no multiplicities):
/// dense, plain block Lanczos and shift-invert block Lanczos all match faer's dense spectrum.
#[test]
fn matches_independent_dense_solver_on_random_instances() {
    for seed in 0..4u64 {
        let (p, _) = SyntheticGraph {
            num_rotations: 40,
            num_edges: 120,
            noise_sigma: 0.2,
            seed,
            ..Default::default()
        }
        .generate();
        let mut rng = StdRng::seed_from_u64(100 + seed);
        let est: Vec<_> = (0..40).map(|_| random_rotation(&mut rng)).collect();
        let l = multipliers(&p, &est).unwrap();
        let s = certificate_matrix(&p, &l).unwrap();
        let exact = faer_eigenvalues(&s);
        let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let want = &exact[..10];
        // dense path (nalgebra)
        let d = smallest_eigenvalues(&s, &SpectrumSettings::default(), None).unwrap();
        assert_eq!(d.method, SpectrumMethod::Dense);
        assert_close(&d.values, want, 1e-10 * scale, "dense");
        // plain block Lanczos: Krylov space up to the full dimension (exact at m = 120)
        let lz = SpectrumSettings {
            dense_max_dim: 0,
            max_subspace: 120,
            ..Default::default()
        };
        let r = smallest_eigenvalues(&s, &lz, None).unwrap();
        assert_eq!(r.method, SpectrumMethod::Lanczos);
        assert!(r.converged(), "{r:?}");
        assert_close(&r.values, want, 1e-7 * scale, "lanczos");
        // shift-invert with a shift making S + sigma I positive definite
        let sigma = -exact[0] + 0.05 * scale;
        let si = SpectrumSettings {
            dense_max_dim: 0,
            max_subspace: 90,
            ..Default::default()
        };
        let r = smallest_eigenvalues(&s, &si, Some(sigma)).unwrap();
        assert_eq!(r.method, SpectrumMethod::ShiftInvertLanczos);
        assert!(r.converged(), "{r:?}");
        assert!(r.subspace_dim <= 90);
        assert_close(&r.values, want, 1e-7 * scale, "shift-invert");
        for (v, res) in r.values.iter().zip(&r.residuals) {
            assert!(res.is_finite() && *res <= 1e-6 * scale, "{v} {res}");
        }
    }
}

/// Noise-free planted instance: spectrum = scalar Laplacian spectrum, each value 3 times; the
/// first three (gauge directions) are 0.
#[test]
fn planted_instance_has_the_scalar_laplacian_spectrum_tripled() {
    for (n, m) in [(30, 70), (250, 600)] {
        let (p, gt) = SyntheticGraph {
            num_rotations: n,
            num_edges: m,
            noise_sigma: 0.0,
            seed: 7,
            ..Default::default()
        }
        .generate();
        let l = multipliers(&p, &gt).unwrap();
        let scalar = scalar_laplacian_eigenvalues(&p);
        let want: Vec<f64> = scalar.iter().flat_map(|&v| [v; 3]).take(10).collect();
        assert!(want[3] > 1e-3, "connected graph: Fiedler value {}", want[3]);
        let tol = 1e-9 * scalar[n - 1];
        // dense (3n <= 600) or shift-invert with the verified Cholesky shift (3n = 750)
        let b = lower_bound_from_multipliers(&p, &l, &CertifySettings::default()).unwrap();
        let e = certificate_spectrum(&p, &l, &SpectrumSettings::default(), b.shift).unwrap();
        if 3 * n <= 600 {
            assert_eq!(e.method, SpectrumMethod::Dense);
        } else {
            assert_eq!(e.method, SpectrumMethod::ShiftInvertLanczos, "{e:?}");
        }
        assert!(e.converged(), "{e:?}");
        assert_close(&e.values, &want, tol, "planted");
        // plain block Lanczos on S (no factor), generous subspace
        let lz = SpectrumSettings {
            dense_max_dim: 0,
            max_subspace: 3 * n.min(60),
            ..Default::default()
        };
        let r = certificate_spectrum(&p, &l, &lz, None).unwrap();
        assert_eq!(r.method, SpectrumMethod::Lanczos);
        if r.converged() {
            assert_close(&r.values, &want, 1e-7 * scalar[n - 1], "planted lanczos");
        } else {
            // unconverged: every value is still within its residual of some eigenvalue
            // (Rayleigh quotients are >= lambda_min by Courant-Fischer)
            assert!(r.values[0] >= -1e-9);
        }
    }
}

#[test]
fn invalid_settings_and_tiny_matrices() {
    let (p, gt) = SyntheticGraph {
        num_rotations: 2,
        num_edges: 1,
        noise_sigma: 0.0,
        ..Default::default()
    }
    .generate();
    let l = multipliers(&p, &gt).unwrap();
    // k larger than the dimension: all 6 eigenvalues (closed form: 0 x3, 2w x3)
    let e = certificate_spectrum(&p, &l, &SpectrumSettings::default(), None).unwrap();
    assert_eq!(e.values.len(), 6);
    let w = p.edges()[0].weight;
    assert_close(
        &e.values,
        &[0.0, 0.0, 0.0, 2.0 * w, 2.0 * w, 2.0 * w],
        1e-12,
        "n=2",
    );
    for bad in [
        SpectrumSettings {
            count: 0,
            ..Default::default()
        },
        SpectrumSettings {
            block_size: 0,
            ..Default::default()
        },
        SpectrumSettings {
            tolerance: f64::NAN,
            ..Default::default()
        },
    ] {
        assert!(certificate_spectrum(&p, &l, &bad, None).is_err());
    }
}

/// The pipeline attaches the estimates only when asked, always attaches the verified bound, and
/// the verified bound is below every estimate (minus its residual): the proof and the estimate
/// agree. n = 250 (3n = 750 > 600): shift-invert with the verification's shift.
#[test]
fn pipeline_attaches_spectrum_only_on_request() {
    use rotavg::pipeline::{AverageMultipleSettings, average_multiple};
    let (p, _) = SyntheticGraph {
        num_rotations: 250,
        num_edges: 700,
        noise_sigma: 0.05,
        seed: 11,
        ..Default::default()
    }
    .generate();
    let plain = average_multiple(&p, &AverageMultipleSettings::default()).unwrap();
    let c = plain.certificate.unwrap();
    assert!(c.is_certified());
    assert!(c.smallest_eigenvalues.is_none());
    let mu = c.verified_min_eigenvalue.expect("verified bound exposed");
    let with = average_multiple(
        &p,
        &AverageMultipleSettings {
            certify: CertifySettings {
                spectrum: Some(SpectrumSettings::default()),
                ..Default::default()
            },
            ..Default::default()
        },
    )
    .unwrap();
    let c2 = with.certificate.unwrap();
    assert_eq!(c2.verdict, c.verdict);
    let e = c2.smallest_eigenvalues.expect("requested");
    assert_eq!(e.method, SpectrumMethod::ShiftInvertLanczos);
    assert_eq!(e.values.len(), 10);
    for (v, r) in e.values.iter().zip(&e.residuals) {
        assert!(
            mu <= v + r + 1e-12,
            "verified {mu} above estimate {v} (residual {r})"
        );
    }
    // critical point: the 3 gauge directions are (numerically) null, the 4th is not
    assert!(
        e.values[..3].iter().all(|v| v.abs() < 1e-6),
        "{:?}",
        e.values
    );
    assert!(e.values[3] > 1e-3);
    // the estimates agree with an independent dense solve of the same matrix
    let l = multipliers(&p, &with.solution.rotations).unwrap();
    let s = certificate_matrix(&p, &l).unwrap();
    let exact = faer_eigenvalues(&s);
    let scale = exact.last().unwrap().abs();
    assert_close(&e.values, &exact[..10], 1e-8 * scale, "pipeline");
}
