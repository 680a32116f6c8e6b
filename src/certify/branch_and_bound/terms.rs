//! The terms of single and conjugate averaging for the search: the samples (pairs) projected
//! onto SO(3) once, their weights, and the slack that covers the projection (`[B6]`).

use super::bound::{Accumulator, BallBound, Geometry};
use super::profile::Profile;
use super::search::Terms;
use crate::conjugate::{ConjugateProblem, ConjugateSettings, ConjugateSolution, solve_conjugate};
use crate::single::{SingleProblem, SingleSettings, SingleSolution, solve_single};
use crate::so3::{self, Rotation};
use nalgebra::{Matrix3, Vector3};

/// The nearest rotation to `r` and the Frobenius distance to it (`0` when the projection
/// fails, which it does not for finite input).
fn projected(r: &Rotation) -> (Matrix3<f64>, f64) {
    match so3::project_to_so3(r.matrix()) {
        Some(p) => (*p.matrix(), (p.matrix() - r.matrix()).norm()),
        None => (*r.matrix(), 0.0),
    }
}

/// The data margin `[B6]` of one term of weight `w` whose matrices are `e` from SO(3): every
/// distance of the crate is a function of the angle `atan2(|vee X|, (tr X - 1) / 2)` (the
/// quaternion distance `2 sin(theta / 4)` included), which moves by at most `2 e`.
fn term_slack(profile: &Profile, w: f64, e: f64) -> f64 {
    w * profile.perturbation(e, 2.0 * e)
}

/// `(theta, sin theta, u)` of a matrix `x` that is a rotation to rounding: `theta =
/// atan2(|vee x|, (tr x - 1) / 2)` (as [`so3::angle`]) and `vee x = sin(theta) u`.
#[inline]
fn angle_axis(x: &Matrix3<f64>) -> (f64, f64, Vector3<f64>) {
    let v = so3::vee(x);
    let s = v.norm();
    let c = 0.5 * (x.trace() - 1.0);
    (s.atan2(c), s, v)
}

/// Single averaging: `theta_k(X) = theta(X, A_k)`, 1-Lipschitz, convex along geodesics where
/// below pi (`[B2]`, `[B3]`); gradient `-u_k` (the axis of `X^T A_k`).
pub(crate) struct SingleTerms<'a> {
    problem: &'a SingleProblem,
    profile: Profile,
    samples: Vec<Matrix3<f64>>,
    data_slack: f64,
}

impl<'a> SingleTerms<'a> {
    /// The terms of `problem`.
    pub(crate) fn new(problem: &'a SingleProblem) -> Self {
        let (samples, data_slack) = projected_samples(problem, |_| true);
        SingleTerms {
            problem,
            profile: Profile::new(problem.objective()),
            samples,
            data_slack,
        }
    }
}

/// The samples of `problem` (those `project` selects replaced by their nearest rotations) and
/// the data margin `[B6]` of the replacement: for every rotation `X`, the cost of the samples
/// as given is at least that of the returned matrices minus the margin.
pub(crate) fn projected_samples(
    problem: &SingleProblem,
    project: impl Fn(&Rotation) -> bool,
) -> (Vec<Matrix3<f64>>, f64) {
    let profile = Profile::new(problem.objective());
    let mut data_slack = 0.0;
    let samples = problem
        .samples()
        .map(|(_, r, w)| {
            if !project(r) {
                return *r.matrix();
            }
            let (p, e) = projected(r);
            data_slack += term_slack(&profile, w, e);
            p
        })
        .collect();
    (samples, data_slack * (1.0 + 1e-9))
}

const SINGLE: Geometry = Geometry {
    lambda: 1.0,
    kappa: 0.0,
    grad_norm_sup: 1.0,
    credit: true,
};

/// Conjugate averaging: `theta_i(S) = theta(R_i, S^T L_i S)`, 2-Lipschitz, `theta'' >=
/// -2 |v|^2` (`[B2]`, `[B3]`); gradient `(I - M_i) u_i`, `M_i = C^T L_i C`.
const CONJUGATE: Geometry = Geometry {
    lambda: 2.0,
    kappa: 2.0,
    grad_norm_sup: 2.0,
    credit: false,
};

impl Terms for SingleTerms<'_> {
    type Solution = SingleSolution;

    fn data_slack(&self) -> f64 {
        self.data_slack
    }

    fn ball(&self, centre: &Rotation, radius: f64) -> BallBound {
        let ct = centre.matrix().transpose();
        let mut acc = Accumulator::new(&self.profile, SINGLE, radius);
        for (a, &w) in self.samples.iter().zip(self.problem.weights()) {
            let x = ct * a;
            let (theta, s, v) = angle_axis(&x);
            acc.add(w, theta, s, || -v / s);
        }
        acc.finish(self.data_slack)
    }

    fn cost(&self, x: &Rotation) -> f64 {
        self.problem.cost(x)
    }

    fn local_solve(&self, start: &Rotation) -> Option<(SingleSolution, f64)> {
        let settings = SingleSettings {
            init: Some(*start),
            ..Default::default()
        };
        solve_single(self.problem, &settings)
            .ok()
            .filter(|s| s.cost.is_finite())
            .map(|s| {
                let c = s.cost;
                (s, c)
            })
    }

    fn rotation(solution: &SingleSolution) -> Rotation {
        solution.estimate
    }
}

/// The pairs of a conjugate problem, projected.
pub(crate) struct ConjugateTerms<'a> {
    problem: &'a ConjugateProblem,
    profile: Profile,
    pairs: Vec<(Matrix3<f64>, Matrix3<f64>, f64)>,
    data_slack: f64,
}

impl<'a> ConjugateTerms<'a> {
    /// The terms of `problem`.
    pub(crate) fn new(problem: &'a ConjugateProblem) -> Self {
        let profile = Profile::new(problem.objective());
        let mut data_slack = 0.0;
        let pairs = problem
            .pairs()
            .iter()
            .map(|p| {
                let (l, el) = projected(&p.left);
                let (r, er) = projected(&p.right);
                data_slack += term_slack(&profile, p.weight, el + er);
                (l, r.transpose(), p.weight)
            })
            .collect();
        ConjugateTerms {
            problem,
            profile,
            pairs,
            data_slack: data_slack * (1.0 + 1e-9),
        }
    }
}

impl Terms for ConjugateTerms<'_> {
    type Solution = ConjugateSolution;

    fn data_slack(&self) -> f64 {
        self.data_slack
    }

    fn ball(&self, centre: &Rotation, radius: f64) -> BallBound {
        let c = centre.matrix();
        let ct = c.transpose();
        let mut acc = Accumulator::new(&self.profile, CONJUGATE, radius);
        for (l, rt, w) in &self.pairs {
            let m = ct * l * c;
            let p = rt * m;
            let (theta, s, v) = angle_axis(&p);
            acc.add(*w, theta, s, || {
                let u = v / s;
                u - m * u
            });
        }
        acc.finish(self.data_slack)
    }

    fn cost(&self, x: &Rotation) -> f64 {
        self.problem.cost(x)
    }

    fn local_solve(&self, start: &Rotation) -> Option<(ConjugateSolution, f64)> {
        let settings = ConjugateSettings {
            init: Some(*start),
            ..Default::default()
        };
        solve_conjugate(self.problem, &settings)
            .ok()
            .filter(|s| s.cost.is_finite())
            .map(|s| {
                let c = s.cost;
                (s, c)
            })
    }

    fn rotation(solution: &ConjugateSolution) -> Rotation {
        solution.estimate
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objective::{Loss, Objective};
    use crate::so3::{Metric, exp, random_rotation};
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    use crate::certify::branch_and_bound::test_objectives as objectives;

    /// Random points of random balls never beat the ball's bound (single and conjugate, every
    /// metric and loss, spread data).
    #[test]
    fn ball_bounds_hold_at_random_points() {
        let mut rng = StdRng::seed_from_u64(5);
        for o in objectives() {
            for trial in 0..6 {
                let rs: Vec<_> = (0..7).map(|_| random_rotation(&mut rng)).collect();
                let single = SingleProblem::new(rs.clone(), Some((1..=7).map(f64::from).collect()))
                    .unwrap()
                    .with_objective(o);
                let Ok(single) = single else { continue };
                let ls: Vec<_> = (0..7).map(|_| random_rotation(&mut rng)).collect();
                let conj = ConjugateProblem::from_rotations(&ls, &rs)
                    .unwrap()
                    .with_objective(o);
                let st = SingleTerms::new(&single);
                let ct = conj.as_ref().ok().map(ConjugateTerms::new);
                for _ in 0..20 {
                    let c = random_rotation(&mut rng);
                    let r = [1e-3, 0.05, 0.3, 1.0][trial % 4] * rng.random::<f64>();
                    let bs = st.ball(&c, r).lower_bound;
                    let bc = ct.as_ref().map(|t| t.ball(&c, r).lower_bound);
                    for _ in 0..30 {
                        let v = so3::random_unit_vector(&mut rng) * r * rng.random::<f64>();
                        let x = c * exp(&v);
                        let f = single.cost(&x);
                        assert!(bs <= f + 1e-12 * (1.0 + f), "{o}: single {bs} > {f}");
                        if let (Some(b), Ok(p)) = (bc, &conj) {
                            let f = p.cost(&x);
                            assert!(b <= f + 1e-12 * (1.0 + f), "{o}: conjugate {b} > {f}");
                        }
                    }
                }
            }
        }
    }

    /// Near the minimiser the first-order bound `[B3]` is tight to second order.
    #[test]
    fn first_order_bound_is_tight_near_a_smooth_point() {
        let mut rng = StdRng::seed_from_u64(2);
        let truth = random_rotation(&mut rng);
        let rs: Vec<_> = (0..50)
            .map(|_| so3::perturb_gaussian(&truth, 0.1, &mut rng))
            .collect();
        let p = SingleProblem::new(rs, None)
            .unwrap()
            .with_objective(Objective::new(Metric::Geodesic, Loss::L2))
            .unwrap();
        let sol = solve_single(&p, &SingleSettings::default()).unwrap();
        let t = SingleTerms::new(&p);
        let b = t.ball(&sol.estimate, 1e-3);
        assert!(
            sol.cost - b.lower_bound < 1e-9 * sol.cost,
            "{} {}",
            sol.cost,
            b.lower_bound
        );
    }
}
