//! The connection Laplacian `Q` (3n x 3n) of a view graph (`paper-notes/multiple.md`, `[M2]`):
//! `Q_ii = (sum of w over edges at i) I_3`, and for each edge `(i, j)`:
//! `Q_ij -= w_ij R_ij^T`, `Q_ji -= w_ij R_ij`. Then `f(R) = tr(Y^T Q Y)` with
//! `Y = [R_0; ...; R_{n-1}]` (3n x 3).

use crate::multiple::MultipleProblem;
use faer::sparse::{SparseColMat, Triplet};

/// Triplets of `Q` (duplicates summed by the sparse constructor). Both triangles are present.
pub fn connection_laplacian_triplets(problem: &MultipleProblem) -> Vec<Triplet<usize, usize, f64>> {
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
}
