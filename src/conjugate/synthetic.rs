//! Seeded synthetic conjugate instances with a planted `S` (tests, benches, the demo):
//! [`random_instance`].

use super::problem::{ConjugatePair, ConjugateProblem};
use crate::so3::{Rotation, exp, perturb_gaussian, random_rotation, random_unit_vector};
use rand::Rng;

/// `n` pairs: `R_i = exp(a_i u_i)` with random unit axis `u_i` and angle `a_i` uniform in
/// `[0.2, 2.0]` rad, `L_i = S R_i S^T` perturbed by isotropic Gaussian noise of `sigma` radians
/// per axis; a fraction `outliers` of the `L_i` replaced by uniformly random rotations.
/// Returns the problem and the planted `S`.
///
/// ```
/// use rand::SeedableRng;
/// use rotavg::conjugate::synthetic::random_instance;
/// let mut rng = rand::rngs::StdRng::seed_from_u64(1);
/// let (problem, s) = random_instance(5, 0.0, 0.0, &mut rng);
/// assert_eq!(problem.num_pairs(), 5);
/// assert!(problem.chordal_cost(&s) < 1e-24); // noise-free: the planted S is exact
/// ```
pub fn random_instance<R: Rng + ?Sized>(
    n: usize,
    sigma: f64,
    outliers: f64,
    rng: &mut R,
) -> (ConjugateProblem, Rotation) {
    let s = random_rotation(rng);
    let pairs: Vec<ConjugatePair> = (0..n.max(2))
        .map(|_| {
            let a = 0.2 + 1.8 * rng.random::<f64>();
            let r = exp(&(random_unit_vector(rng) * a));
            let l = if rng.random::<f64>() < outliers {
                random_rotation(rng)
            } else {
                perturb_gaussian(&(s * r * s.inverse()), sigma, rng)
            };
            ConjugatePair::new(l, r)
        })
        .collect();
    // n.max(2) >= 1 pair and weights are 1: `new` cannot fail.
    let problem = match ConjugateProblem::new(pairs) {
        Ok(p) => p,
        Err(_) => unreachable!("non-empty pairs with unit weights are valid"),
    };
    (problem, s)
}
