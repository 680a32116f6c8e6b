//! Speed of the multiple-rotation-averaging local path (`paper-notes/multiple.md`, "Speed"):
//! spectral initialisation + chordal L2 Riemannian Newton to relative gradient 1e-8.
//!
//! `cargo bench --features bench --bench multiple` prints a table (real g2o graphs when
//! /work/shared/data is present, and a scaling curve 10^3..10^5 nodes with 3 edges per node),
//! then runs criterion on the small cases. A throwaway g2o loader (EDGE_SE3:QUAT only, weight =
//! SE-Sync's kappa) is included so this bench does not depend on the crate's readers.

use criterion::{Criterion, criterion_group};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion};
use rotavg::Metric;
use rotavg::multiple::synthetic::{SyntheticAnisotropic, SyntheticGraph};
use rotavg::multiple::{
    Edge, Initialisation, MultipleProblem, MultipleSettings, initialise, solve_multiple,
};
use rotavg::objective::{Loss, Objective};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn data_dir() -> Option<PathBuf> {
    [
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
        PathBuf::from("/work/shared/data"),
    ]
    .into_iter()
    .find(|p| p.exists())
}

/// EDGE_SE3:QUAT i j x y z qx qy qz qw I11 I12 .. I66 (upper triangle). Z_ij = R(q),
/// R_ij = Z_ij^T; weight kappa = 3 / (2 tr(Omega_rot^-1)) from the rotation block.
#[allow(clippy::needless_range_loop)]
fn load_g2o(path: &Path) -> Option<MultipleProblem> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut edges = Vec::new();
    let mut n = 0;
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.first() != Some(&"EDGE_SE3:QUAT") || f.len() < 31 {
            continue;
        }
        let i: usize = f[1].parse().ok()?;
        let j: usize = f[2].parse().ok()?;
        let v: Vec<f64> = f[3..31]
            .iter()
            .map(|s| s.parse().unwrap_or(f64::NAN))
            .collect();
        let q = UnitQuaternion::from_quaternion(Quaternion::new(v[6], v[3], v[4], v[5]));
        let info = &v[7..];
        // upper-triangular row-major 6x6 -> full
        let mut full = [[0.0; 6]; 6];
        let mut k = 0;
        for r in 0..6 {
            for c in r..6 {
                full[r][c] = info[k];
                full[c][r] = info[k];
                k += 1;
            }
        }
        let rot = Matrix3::from_fn(|a, b| full[3 + a][3 + b]);
        let weight = rot
            .try_inverse()
            .map(|m| 1.5 / m.trace())
            .filter(|w| w.is_finite() && *w > 0.0)
            .unwrap_or(1.0);
        n = n.max(i + 1).max(j + 1);
        edges.push(Edge {
            i,
            j,
            rotation: q.to_rotation_matrix().inverse(),
            weight,
        });
    }
    MultipleProblem::new(n, edges).ok()
}

fn run(name: &str, p: &MultipleProblem) {
    // initialisation alone (includes its own direct/PCG decision)
    let t0 = Instant::now();
    let init = initialise(p, &Initialisation::Spectral).unwrap();
    let t_init = t0.elapsed().as_secs_f64();
    let init_cost = p.chordal_cost(&init);
    // the whole local path: spectral initialisation + Riemannian Newton to rel. gradient 1e-8
    let t1 = Instant::now();
    let sol = solve_multiple(p, &MultipleSettings::default()).unwrap();
    let t_total = t1.elapsed().as_secs_f64();
    println!(
        "| {name} | {} | {} | {:.4} | {:.4} | {} | {:.3e} | {:.6e} | {:.6e} | {} |",
        p.num_rotations(),
        p.num_edges(),
        t_init,
        t_total,
        sol.report.iterations,
        sol.gradient_norm / p.edges().iter().map(|e| e.weight).sum::<f64>(),
        init_cost,
        sol.cost,
        sol.report.termination.name(),
    );
}

fn table() {
    println!(
        "| graph | n | m | spectral init alone (s) | solve_multiple total (s) | Newton iterations | rel. gradient | init cost | final cost | termination |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    if let Some(d) = data_dir() {
        for f in [
            "g2o/3d/sesync/sphere2500.g2o",
            "g2o/3d/sesync/parking-garage.g2o",
            "g2o/3d/sesync/smallGrid3D.g2o",
            "g2o/3d/sesync/tinyGrid3D.g2o",
            "g2o/3d/mrob/sphere.g2o",
            "g2o/3d/gtsam/Klaus3.g2o",
        ] {
            match load_g2o(&d.join(f)) {
                Some(p) if p.require_connected().is_ok() => run(f, &p),
                _ => println!("| {f} | (not loaded or disconnected) |"),
            }
        }
    } else {
        println!("skipping: shared data not found");
    }
    for n in [1_000usize, 3_000, 10_000, 30_000, 100_000] {
        let (p, _) = SyntheticGraph {
            num_rotations: n,
            num_edges: 3 * n,
            noise_sigma: 0.05,
            outlier_fraction: 0.0,
            seed: 1,
        }
        .generate();
        run("synthetic sigma=0.05 3n edges", &p);
    }
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("multiple_chordal_from_spectral");
    g.sample_size(10);
    let mut cases: Vec<(String, MultipleProblem)> = Vec::new();
    if let Some(d) = data_dir() {
        for f in ["sphere2500", "parking-garage"] {
            if let Some(p) = load_g2o(&d.join(format!("g2o/3d/sesync/{f}.g2o"))) {
                cases.push((f.to_string(), p));
            }
        }
    }
    let (p, _) = SyntheticGraph {
        num_rotations: 10_000,
        num_edges: 30_000,
        noise_sigma: 0.05,
        outlier_fraction: 0.0,
        seed: 1,
    }
    .generate();
    cases.push(("synthetic_1e4_3e4".into(), p));
    // anisotropic noise (standard deviations 0.5 / 0.5 / 5 degrees) with its information
    let (p, _) = SyntheticAnisotropic {
        num_rotations: 1000,
        num_edges: 4000,
        seed: 1,
        ..Default::default()
    }
    .generate();
    cases.push(("anisotropic_1e3_4e3".into(), p));
    // issue 37's two-view anisotropy (ratio log-normal around 9) with 10 % outliers under
    // Cauchy: the information against its scalar weights tr(H) / 3
    let (p, _) = SyntheticAnisotropic::two_view_like(1000, 4000, 0.1).generate();
    let cauchy = Objective::new(Metric::Geodesic, Loss::Cauchy { scale_deg: 5.0 });
    let scalar: Vec<Edge> = p
        .edges()
        .iter()
        .zip(p.information().unwrap_or_default())
        .map(|(e, h)| Edge {
            weight: h.matrix().trace() / 3.0,
            ..e.clone()
        })
        .collect();
    let scalar =
        MultipleProblem::new(p.num_rotations(), scalar).and_then(|s| s.with_objective(cauchy));
    cases.push(("cauchy_scalar_1e3_4e3".into(), scalar.unwrap()));
    cases.push((
        "cauchy_anisotropic_1e3_4e3".into(),
        p.with_objective(cauchy).unwrap(),
    ));
    for (name, p) in &cases {
        g.bench_function(name.as_str(), |b| {
            b.iter(|| solve_multiple(p, &MultipleSettings::default()).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);

fn main() {
    table();
    if std::env::var_os("ROTAVG_TABLE_ONLY").is_none() {
        benches();
        criterion::Criterion::default()
            .configure_from_args()
            .final_summary();
    }
}
