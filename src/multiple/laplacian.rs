//! The connection Laplacian `Q` (3n x 3n) of a view graph (`paper-notes/multiple.md`, `[M2]`):
//! `Q_ii = (sum of w over edges at i) I_3`, and for each edge `(i, j)`:
//! `Q_ij -= w_ij R_ij^T`, `Q_ji -= w_ij R_ij`. Then `f(R) = tr(Y^T Q Y)` with
//! `Y = [R_0; ...; R_{n-1}]` (3n x 3). Anisotropic edges (`paper-notes/anisotropic.md`, `[A2]`):
//! `Q_ii += 2M`, `Q_jj += 2M`, `Q_ij -= 2 M R_ij^T`, `Q_ji -= 2 R_ij M`, `M = tr(H)/2 I - H`;
//! then `f(R) = tr(Y^T Q Y)` exactly for rotations (no constant).

use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::Matrix3;

/// Triplets of `Q` (duplicates summed by the sparse constructor). Both triangles are present.
pub fn connection_laplacian_triplets(problem: &MultipleProblem) -> Vec<Triplet<usize, usize, f64>> {
    if let Some(info) = problem.information() {
        return anisotropic_triplets(problem, info);
    }
    let mut t = Vec::with_capacity(problem.num_edges() * 24 + problem.num_rotations() * 3);
    let mut degree = vec![0.0; problem.num_rotations()];
    for e in problem.edges() {
        degree[e.i] += e.weight;
        degree[e.j] += e.weight;
        let r = e.rotation.matrix();
        for a in 0..3 {
            for b in 0..3 {
                // Q_ij = -w R_ij^T  => (Q_ij)_{ab} = -w r[b][a]
                t.push(Triplet::new(
                    3 * e.i + a,
                    3 * e.j + b,
                    -e.weight * r[(b, a)],
                ));
                t.push(Triplet::new(
                    3 * e.j + a,
                    3 * e.i + b,
                    -e.weight * r[(a, b)],
                ));
            }
        }
    }
    for (i, d) in degree.iter().enumerate() {
        for a in 0..3 {
            t.push(Triplet::new(3 * i + a, 3 * i + a, *d));
        }
    }
    t
}

/// Each edge's part of `Q` as blocks `(i, j, Q_ii part, Q_jj part, Q_ij)` (`Q_ji = Q_ij^T`):
/// `(w I, w I, -w R_ij^T)`, or `(2M, 2M, -2M R_ij^T)` with information `[A2]`. The same
/// matrix as [`connection_laplacian_triplets`], block by block.
pub fn edge_blocks(
    problem: &MultipleProblem,
) -> impl Iterator<Item = (usize, usize, Matrix3<f64>, Matrix3<f64>, Matrix3<f64>)> + '_ {
    problem.edges().iter().enumerate().map(move |(k, e)| {
        let (d, off) = edge_block(problem, k);
        (e.i, e.j, d, d, off)
    })
}

/// `Q + blkdiag(D_1, ..., D_n)` assembled directly in compressed columns, both triangles
/// stored, every diagonal block and every edge's two off-diagonal blocks stored in full (the
/// pattern of [`connection_laplacian_triplets`] plus the diagonal blocks, explicit zeros kept:
/// the `3 x 3` block orderings recognise whole blocks). Each entry is the sum of its edges'
/// parts in edge order, then `D_i` on the diagonal blocks: for isotropic edges exactly the
/// values of the triplet assembly, without its sort (a 10^5-node, 10^6-edge graph: 1.3 s of
/// triplets, issue 35).
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem, laplacian::{connection_laplacian, laplacian_plus_diagonal}};
/// use rotavg::Rotation;
/// use nalgebra::Matrix3;
/// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 2.0 };
/// let p = MultipleProblem::new(3, vec![e(0, 1), e(1, 2), e(1, 0)]).unwrap();
/// let s = laplacian_plus_diagonal(&p, &[Matrix3::identity(); 3]);
/// let q = connection_laplacian(&p).to_dense();
/// let s = s.to_dense();
/// for r in 0..9 {
///     for c in 0..9 {
///         assert_eq!(s[(r, c)], q[(r, c)] + if r == c { 1.0 } else { 0.0 });
///     }
/// }
/// ```
pub fn laplacian_plus_diagonal(
    problem: &MultipleProblem,
    diagonal: &[Matrix3<f64>],
) -> SparseColMat<usize, f64> {
    let n = problem.num_rotations();
    let (offsets, incident) = incident_edges(problem);
    let own = diagonal_blocks(problem, diagonal);
    let mut col_ptr = Vec::with_capacity(3 * n + 1);
    let (mut row_idx, mut values) = (Vec::new(), Vec::new());
    col_ptr.push(0usize);
    let mut column: Vec<(usize, Matrix3<f64>)> = Vec::new();
    for i in 0..n {
        let d = own[i];
        block_column(
            problem,
            i,
            &incident[offsets[i]..offsets[i + 1]],
            d,
            &mut column,
        );
        for b in 0..3 {
            for (j, m) in &column {
                row_idx.extend((0..3).map(|a| 3 * j + a));
                values.extend((0..3).map(|a| m[(a, b)]));
            }
            col_ptr.push(row_idx.len());
        }
    }
    let dim = 3 * n;
    let symbolic =
        faer::sparse::SymbolicSparseColMat::new_checked(dim, dim, col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

/// The diagonal blocks of [`laplacian_plus_diagonal`]`(problem, diagonal)`, as it stores them.
pub(crate) fn diagonal_blocks(
    problem: &MultipleProblem,
    diagonal: &[Matrix3<f64>],
) -> Vec<Matrix3<f64>> {
    let mut own = vec![Matrix3::zeros(); problem.num_rotations()];
    for (k, e) in problem.edges().iter().enumerate() {
        let qii = edge_diagonal_block(problem, k);
        own[e.i] += qii;
        own[e.j] += qii;
    }
    for (o, d) in own.iter_mut().zip(diagonal) {
        *o += d;
    }
    own
}

/// Each node's incident edges as `(other end, edge)`, sorted, in compressed rows.
fn incident_edges(problem: &MultipleProblem) -> (Vec<usize>, Vec<(usize, usize)>) {
    let n = problem.num_rotations();
    let mut offsets = vec![0usize; n + 1];
    for e in problem.edges() {
        offsets[e.i + 1] += 1;
        offsets[e.j + 1] += 1;
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    let mut next = offsets.clone();
    let mut incident = vec![(0usize, 0usize); offsets[n]];
    for (k, e) in problem.edges().iter().enumerate() {
        for (a, b) in [(e.i, e.j), (e.j, e.i)] {
            incident[next[a]] = (b, k);
            next[a] += 1;
        }
    }
    for i in 0..n {
        incident[offsets[i]..offsets[i + 1]].sort_unstable();
    }
    (offsets, incident)
}

/// The blocks of block column `i`, by block row: `d` at `i`, and at each neighbour `j` the sum
/// over the edges between them (in edge order) of `Q_ji`.
fn block_column(
    problem: &MultipleProblem,
    i: usize,
    incident: &[(usize, usize)],
    d: Matrix3<f64>,
    column: &mut Vec<(usize, Matrix3<f64>)>,
) {
    column.clear();
    let mut own = Some(d);
    for &(j, k) in incident {
        if j > i
            && let Some(d) = own.take()
        {
            column.push((i, d));
        }
        let (_, qij) = edge_block(problem, k);
        let qji = if problem.edges()[k].i == i {
            qij.transpose()
        } else {
            qij
        };
        match column.last_mut() {
            Some((last, m)) if *last == j => *m += qji,
            _ => column.push((j, qji)),
        }
    }
    if let Some(d) = own {
        column.push((i, d));
    }
}

/// Edge `k`'s part of `Q` as `(Q_ii part = Q_jj part, Q_ij)` ([`edge_blocks`]).
fn edge_block(problem: &MultipleProblem, k: usize) -> (Matrix3<f64>, Matrix3<f64>) {
    let e = &problem.edges()[k];
    let r_t = e.rotation.matrix().transpose();
    let d = edge_diagonal_block(problem, k);
    let off = match problem.information() {
        Some(_) => -(d * r_t),
        None => -(r_t * e.weight),
    };
    (d, off)
}

/// Edge `k`'s part of `Q_ii` (and of `Q_jj`): `w I`, or `2M` with information `[A2]`.
fn edge_diagonal_block(problem: &MultipleProblem, k: usize) -> Matrix3<f64> {
    match problem.information() {
        Some(info) => info[k].twice_chordal_matrix(),
        None => Matrix3::identity() * problem.edges()[k].weight,
    }
}

/// `[A2]`: per edge the 6x6 block `[[2M, -2M R_ij^T], [-2 R_ij M, 2M]]` at `(i, j)`.
fn anisotropic_triplets(
    problem: &MultipleProblem,
    info: &[Information],
) -> Vec<Triplet<usize, usize, f64>> {
    let mut t = Vec::with_capacity(problem.num_edges() * 36);
    for (e, h) in problem.edges().iter().zip(info) {
        let m2 = h.twice_chordal_matrix();
        let off = -(m2 * e.rotation.matrix().transpose()); // Q_ij; Q_ji is its transpose
        for a in 0..3 {
            for b in 0..3 {
                t.push(Triplet::new(3 * e.i + a, 3 * e.i + b, m2[(a, b)]));
                t.push(Triplet::new(3 * e.j + a, 3 * e.j + b, m2[(a, b)]));
                t.push(Triplet::new(3 * e.i + a, 3 * e.j + b, off[(a, b)]));
                t.push(Triplet::new(3 * e.j + a, 3 * e.i + b, off[(b, a)]));
            }
        }
    }
    t
}

/// The connection Laplacian as a faer sparse matrix (both triangles stored).
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem, laplacian::connection_laplacian};
/// use rotavg::Rotation;
/// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 2.0 };
/// let p = MultipleProblem::new(2, vec![e(0, 1)]).unwrap();
/// let q = connection_laplacian(&p);
/// assert_eq!(q.nrows(), 6);
/// ```
pub fn connection_laplacian(problem: &MultipleProblem) -> SparseColMat<usize, f64> {
    let n3 = 3 * problem.num_rotations();
    SparseColMat::try_new_from_triplets(n3, n3, &connection_laplacian_triplets(problem))
        .expect("indices are validated by MultipleProblem")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multiple::Edge;
    use crate::so3::{perturb, random_rotation};
    use nalgebra::DMatrix;
    use rand::SeedableRng;

    #[test]
    fn trace_form_equals_cost() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let n = 6;
        let mut edges = vec![];
        for i in 0..n {
            for j in (i + 1)..n {
                edges.push(Edge {
                    i,
                    j,
                    rotation: random_rotation(&mut rng),
                    weight: 0.5 + i as f64,
                });
            }
        }
        edges.push(edges[3].reversed()); // a multi-edge in the opposite direction
        let p = MultipleProblem::new(n, edges).unwrap();
        let rs: Vec<_> = (0..n)
            .map(|_| perturb(&random_rotation(&mut rng), 0.3, &mut rng))
            .collect();
        let q = connection_laplacian(&p);
        let mut qd = DMatrix::<f64>::zeros(3 * n, 3 * n);
        let dense = q.to_dense();
        for c in 0..3 * n {
            for r in 0..3 * n {
                qd[(r, c)] = dense[(r, c)];
            }
        }
        assert!((qd.clone() - qd.transpose()).norm() < 1e-12);
        let y = DMatrix::<f64>::from_fn(3 * n, 3, |r, c| rs[r / 3].matrix()[(r % 3, c)]);
        let tr = (y.transpose() * qd * y).trace();
        let f = p.chordal_cost(&rs);
        assert!(
            (tr - f).abs() < 1e-10 * f.max(1.0),
            "tr(Y^T Q Y) = {tr}, f = {f}"
        );
    }

    /// `[A2]`: `tr(Y^T Q Y)` equals the anisotropic cost, written here as the closed form
    /// `4 (1 - cos theta) u^T H u` of each edge's residual `[A1]` (independent of the code's
    /// `chordal_term`), with a multi-edge and indefinite `M`.
    #[test]
    fn anisotropic_trace_form_equals_closed_form_cost() {
        use crate::multiple::anisotropic::Information;
        use crate::so3::log;
        use nalgebra::Matrix3;
        let mut rng = rand::rngs::StdRng::seed_from_u64(12);
        let n = 5;
        let mut edges = vec![];
        let mut info = vec![];
        for i in 0..n {
            for j in (i + 1)..n {
                edges.push(Edge {
                    i,
                    j,
                    rotation: random_rotation(&mut rng),
                    weight: 1.0,
                });
                let a = Matrix3::from_fn(|p, q| ((p * 5 + q * 7 + i * 3 + j) % 7) as f64 - 3.0);
                info.push(Information::new(a * a.transpose() + Matrix3::identity() * 0.1).unwrap());
            }
        }
        edges.push(edges[2].reversed());
        info.push(info[2]);
        let indefinite = info
            .iter()
            .filter(|h| h.chordal_matrix_indefinite())
            .count();
        assert!(indefinite > 0, "the test wants some indefinite M");
        let p = MultipleProblem::new(n, edges)
            .unwrap()
            .with_information(info.clone())
            .unwrap();
        let rs: Vec<_> = (0..n).map(|_| random_rotation(&mut rng)).collect();
        let dense = connection_laplacian(&p).to_dense();
        let qd = DMatrix::<f64>::from_fn(3 * n, 3 * n, |r, c| dense[(r, c)]);
        assert!((qd.clone() - qd.transpose()).norm() < 1e-12);
        let y = DMatrix::<f64>::from_fn(3 * n, 3, |r, c| rs[r / 3].matrix()[(r % 3, c)]);
        let tr = (y.transpose() * qd * y).trace();
        let closed: f64 = p
            .edges()
            .iter()
            .zip(&info)
            .map(|(e, h)| {
                let v = log(&(e.rotation.inverse() * rs[e.j] * rs[e.i].inverse()));
                let (t, u) = (v.norm(), v.normalize());
                4.0 * (1.0 - t.cos()) * u.dot(&(h.matrix() * u))
            })
            .sum();
        assert!((tr - closed).abs() < 1e-10 * closed, "{tr} vs {closed}");
        assert!((p.chordal_cost(&rs) - closed).abs() < 1e-10 * closed);
    }

    /// The direct assembly has the triplet assembly's pattern (every diagonal block and both
    /// off-diagonal blocks of each edge, explicit zeros kept) and its values, isotropic to the
    /// last bit, anisotropic to rounding; a multi-edge and a node without edges included.
    #[test]
    fn the_direct_assembly_is_the_triplet_assembly() {
        use crate::multiple::anisotropic::Information;
        use nalgebra::Matrix3;
        let mut rng = rand::rngs::StdRng::seed_from_u64(13);
        let n = 7;
        let mut edges = vec![];
        for (i, j) in [(0, 1), (1, 2), (2, 0), (3, 1), (4, 5), (5, 3), (0, 4)] {
            edges.push(Edge {
                i,
                j,
                rotation: random_rotation(&mut rng),
                weight: 0.25 + i as f64,
            });
        }
        edges.push(edges[1].reversed());
        edges.push(Edge {
            i: 5,
            j: 4,
            rotation: crate::Rotation::identity(), // entries exactly 0 in its blocks
            weight: 1.0,
        });
        let diagonal: Vec<Matrix3<f64>> = (0..n)
            .map(|i| Matrix3::from_fn(|a, b| ((a + b + i) % 3) as f64 - 1.3))
            .collect();
        let triplets = |p: &MultipleProblem| {
            let mut t = connection_laplacian_triplets(p);
            for (i, d) in diagonal.iter().enumerate() {
                for a in 0..3 {
                    for b in 0..3 {
                        t.push(Triplet::new(3 * i + a, 3 * i + b, d[(a, b)]));
                    }
                }
            }
            SparseColMat::try_new_from_triplets(3 * n, 3 * n, &t).unwrap()
        };
        let info: Vec<Information> = (0..edges.len())
            .map(|k| {
                let a = Matrix3::from_fn(|p, q| ((p * 5 + q * 7 + k) % 7) as f64 - 3.0);
                Information::new(a * a.transpose() + Matrix3::identity() * 0.1).unwrap()
            })
            .collect();
        let isotropic = MultipleProblem::new(n, edges).unwrap();
        let anisotropic = isotropic.clone().with_information(info).unwrap();
        for (p, exact) in [(&isotropic, true), (&anisotropic, false)] {
            let (direct, reference) = (laplacian_plus_diagonal(p, &diagonal), triplets(p));
            assert_eq!(direct.symbolic().col_ptr(), reference.symbolic().col_ptr());
            assert_eq!(direct.symbolic().row_idx(), reference.symbolic().row_idx());
            for (x, y) in direct.val().iter().zip(reference.val()) {
                if exact {
                    assert_eq!(x, y);
                } else {
                    assert!((x - y).abs() <= 1e-14 * y.abs().max(1.0), "{x} vs {y}");
                }
            }
        }
    }
}
