//! The block comparison `[A15]` alone on subgraphs of a graph of issue 37's realistic
//! two-view class (no outliers), at its least-squares solution: factor size, time and outcome
//! per subgraph.
//!
//! ```text
//! cargo run --release --example block_sweep -- CAMERAS EDGES SHAPE...
//! ```
//!
//! A shape is `K` (edges per node) or `K:T` (topped up to the ratio `T`; default: the ladder's
//! `BLOCK_SHAPES`), e.g. `-- 10000 100000 3 4 2:14` (`paper-notes/anisotropic.md` `[A15]`); with `outliers`, 10 % of
//! the pairs are wrong and the sweep runs on the edges within 5 degrees of the truth, or, with
//! `outliers robust` too, on the inliers of the Cauchy solve (the pipeline's inlier graph);
//! `regions=K` splits each subgraph into `K` regions (`[A15]`, "Regions"; default 1).
use rotavg::certify::multiple::block::{BlockAnalysis, BlockShape, block_comparison};
use rotavg::certify::multiple::multipliers;
use rotavg::multiple::synthetic::SyntheticAnisotropic;
use rotavg::multiple::{MultipleSettings, solve_multiple};
use std::time::Instant;
fn main() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let number =
        |k: usize, default: f64| args.get(k).and_then(|a| a.parse().ok()).unwrap_or(default);
    let (n, m) = (number(0, 1000.0) as usize, number(1, 4000.0) as usize);
    // `K` (edges per node) or `K:T` (topped up to the ratio `T`)
    let mut shapes: Vec<BlockShape> = args
        .iter()
        .skip(2)
        .filter(|a| !a.contains('='))
        .filter_map(|a| {
            let (k, t) = a.split_once(':').unwrap_or((a, "0"));
            Some(BlockShape {
                edges_per_node: k.parse().ok()?,
                top_up: t.parse().ok()?,
            })
        })
        .collect();
    if shapes.is_empty() {
        shapes = rotavg::certify::multiple::block::rungs::BLOCK_SHAPES.to_vec();
    }
    let outliers = args.iter().any(|a| a == "outliers");
    let regions: usize = args
        .iter()
        .find_map(|a| a.strip_prefix("regions=")?.parse().ok())
        .unwrap_or(1);
    let (p, truth) =
        SyntheticAnisotropic::two_view_like(n, m, if outliers { 0.1 } else { 0.0 }).generate();
    // with outliers: the graph of the edges within 5 degrees of the truth (the inlier graph a
    // robust solve finds, up to a few edges)
    let robust = args.iter().any(|a| a == "robust");
    let p = if robust {
        // the inlier flags of the Cauchy solve, as the pipeline's inlier graph takes them
        let cauchy = rotavg::objective::Objective::new(
            rotavg::Metric::Geodesic,
            rotavg::objective::Loss::Cauchy { scale_deg: 5.0 },
        );
        let r = solve_multiple(
            &p.clone().with_objective(cauchy)?,
            &MultipleSettings::default(),
        )?;
        let keep = r.residuals.map(|x| x.inlier).unwrap_or_default();
        println!(
            "{} of {} edges inliers",
            keep.iter().filter(|k| **k).count(),
            keep.len()
        );
        p.edge_subset(&keep)?
    } else if outliers {
        let keep: Vec<bool> = p
            .edges()
            .iter()
            .map(|e| {
                let r = e.rotation.matrix() * truth[e.i].matrix() * truth[e.j].matrix().transpose();
                rotavg::so3::log(&rotavg::Rotation::from_matrix_unchecked(r)).norm()
                    <= 5f64.to_radians()
            })
            .collect();
        p.edge_subset(&keep)?
    } else {
        p
    };
    let s = solve_multiple(&p, &MultipleSettings::default())?;
    let lambdas = multipliers(&p, &s.rotations)?;
    let target = 0.5 * 1e-6 * s.cost / (3 * n) as f64;
    for shape in shapes {
        let t = Instant::now();
        let Ok(a) = BlockAnalysis::grouped(&p, &s.rotations, Some(shape), regions, usize::MAX)?
        else {
            continue;
        };
        let analysed = t.elapsed().as_secs_f64();
        let r = block_comparison(&p, &a, &s.rotations, &lambdas, target)?;
        println!(
            "{shape}, {} regions: factor {:.2e}, analysis {analysed:.2} s, total {:.2} s -> {:?}",
            a.groups(),
            a.factor_len() as f64,
            t.elapsed().as_secs_f64(),
            r.map(|b| b.verified_min_eigenvalue)
        );
    }
    Ok(())
}
