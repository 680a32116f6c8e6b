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
    let info = problem.information();
    problem.edges().iter().enumerate().map(move |(k, e)| {
        let r_t = e.rotation.matrix().transpose();
        match info {
            Some(info) => {
                let m2 = info[k].twice_chordal_matrix();
                (e.i, e.j, m2, m2, -(m2 * r_t))
            }
            None => {
                let d = Matrix3::identity() * e.weight;
                (e.i, e.j, d, d, -(r_t * e.weight))
            }
        }
    })
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
}
