//! Shared by the fuzz targets: how an input is split into a selector byte and text, the reader
//! options a selector chooses, and cheap checks run on whatever a reader accepts.
#![allow(dead_code)]

use rotavg::Rotation;
use rotavg::io::detect::{LoadedGraph, ReadOptions, WeightSource};
use rotavg::multiple::{init::spanning_tree, laplacian::connection_laplacian};

/// Largest problem (nodes or edges) on which the downstream checks run, to keep every
/// execution fast; parsing itself is always exercised in full.
pub const DOWNSTREAM_LIMIT: usize = 2_000;

/// The first byte selects a variant (reader, options); the rest is the file text, decoded as
/// lossy UTF-8 so that every byte string reaches the parser.
pub fn split(data: &[u8]) -> Option<(u8, String)> {
    let (&selector, rest) = data.split_first()?;
    Some((selector, String::from_utf8_lossy(rest).into_owned()))
}

/// Reader options from the selector's bits: bit 0 unit weights; bits 1-2 the tolerances
/// (default, loose, zero, very loose).
pub fn options(selector: u8) -> ReadOptions {
    let mut o = ReadOptions::default();
    if selector & 1 == 1 {
        o.weights = WeightSource::Unit;
    }
    match (selector >> 1) & 3 {
        0 => {}
        1 => {
            o.rotation_tolerance = 1e-2;
            o.quaternion_tolerance = 1e-1;
        }
        2 => {
            o.rotation_tolerance = 0.0;
            o.quaternion_tolerance = 0.0;
        }
        _ => {
            o.rotation_tolerance = 10.0;
            o.quaternion_tolerance = 0.9;
        }
    }
    o
}

/// Rotation-validation tolerance (hand-eye readers take it directly) from the selector.
pub fn tolerance(selector: u8) -> f64 {
    options(selector).rotation_tolerance
}

/// A valid rotation? (orthonormal with determinant 1, to 1e-9.)
pub fn assert_rotation(r: &Rotation) {
    let m = r.matrix();
    assert!(m.iter().all(|x| x.is_finite()), "non-finite rotation {m}");
    let defect = (m.transpose() * m - nalgebra::Matrix3::identity()).norm();
    assert!(defect < 1e-9, "not orthonormal ({defect:e}): {m}");
    assert!((m.determinant() - 1.0).abs() < 1e-9, "det != 1: {m}");
}

/// Invariants of an accepted graph, and cheap downstream steps (components, largest
/// component, costs at the identity and at the spanning-tree estimate, the connection
/// Laplacian): they must not panic on anything a reader accepts.
pub fn check_graph(g: &LoadedGraph) {
    let p = &g.problem;
    let n = p.num_rotations();
    assert!(n > 0 && p.num_edges() > 0);
    assert_eq!(g.node_ids.len(), n, "one file id per node");
    assert!(g.node_ids.windows(2).all(|w| w[0] < w[1]), "ids sorted");
    for e in p.edges() {
        assert!(e.i < n && e.j < n && e.i != e.j);
        assert!(e.weight.is_finite() && e.weight > 0.0);
        assert_rotation(&e.rotation);
    }
    if let Some(init) = &g.initial {
        assert_eq!(init.len(), n);
        init.iter().for_each(assert_rotation);
    }
    assert!(g.reversed <= p.num_edges() && g.duplicates < p.num_edges());
    if n > DOWNSTREAM_LIMIT || p.num_edges() > DOWNSTREAM_LIMIT {
        return;
    }
    let comps = p.components();
    assert_eq!(comps.iter().map(Vec::len).sum::<usize>(), n);
    let _ = p.require_connected();
    let (sub, keep) = p.largest_component();
    assert_eq!(sub.num_rotations(), keep.len());
    let identity = vec![Rotation::identity(); n];
    let cost = p.chordal_cost(&identity);
    assert!(cost >= 0.0, "cost {cost}"); // also rejects NaN
    assert_eq!(p.residual_angles(&identity).len(), p.num_edges());
    let tree = spanning_tree(p);
    assert_eq!(tree.len(), n);
    assert!(p.chordal_cost(&tree) >= 0.0);
    if let Some(init) = &g.initial {
        assert!(p.chordal_cost(init) >= 0.0);
    }
    let l = connection_laplacian(p);
    assert_eq!((l.nrows(), l.ncols()), (3 * n, 3 * n));
}
