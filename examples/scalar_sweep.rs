//! The scalar comparison `[D13]` alone on the subgraphs of `SPARSIFIED_EDGES_PER_NODE` of a
//! view graph file, at its least-squares solution: per subgraph, the factor's size, the time
//! and the outcome (proved, or the number of negative pivots).
//!
//! ```text
//! python3 benches/gen_graph.py expander 10000 20 0.1 10000 /tmp/g.json
//! cargo run --release --example scalar_sweep -- /tmp/g.json
//! ```
use rotavg::certify::multiple::multipliers;
use rotavg::certify::multiple::scalar::{
    SPARSIFIED_EDGES_PER_NODE, ScalarAnalysis, scalar_comparison,
};
use rotavg::io::detect::{GraphFormat, ReadOptions};
use rotavg::io::input::load_view_graph;
use rotavg::multiple::{MultipleSettings, solve_multiple};
use std::time::Instant;
fn main() -> rotavg::Result<()> {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: scalar_sweep VIEW_GRAPH_FILE (any format `rotavg multiple` reads)");
        std::process::exit(2);
    };
    let p = load_view_graph(&path, GraphFormat::Auto, &ReadOptions::default())?.problem;
    let t = Instant::now();
    let s = solve_multiple(&p, &MultipleSettings::default())?;
    let n = p.num_rotations();
    println!(
        "n {n} m {} solve {:.3} s cost {:.6e}",
        p.num_edges(),
        t.elapsed().as_secs_f64(),
        s.cost
    );
    let lambdas = multipliers(&p, &s.rotations)?;
    let target = 0.5 * 1e-6 * s.cost / (3 * n) as f64;
    for k in SPARSIFIED_EDGES_PER_NODE {
        let t = Instant::now();
        let Ok(a) = ScalarAnalysis::sparsified(&p, &s.rotations, k, usize::MAX)? else {
            continue;
        };
        let ta = t.elapsed().as_secs_f64();
        let r = scalar_comparison(&p, &a, &s.rotations, &lambdas, target)?;
        println!(
            "k {k}: factor {:.2e} analysis {ta:.3} s all {:.3} s -> {:?}",
            a.factor_len() as f64,
            t.elapsed().as_secs_f64(),
            r.map(|b| b.verified_min_eigenvalue)
        );
    }
    Ok(())
}
