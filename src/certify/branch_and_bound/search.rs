//! Best-first branch and bound over the axis-angle cube `[-pi, pi]^3` (`[B1]`), with balls
//! around incumbents (`[B5]`), for any cost whose balls can be bounded (`[B2]`-`[B4]`).

use super::bound::{ANGLE_ERROR, BallBound};
use crate::certify::evidence::{BranchAndBoundStats, BranchAndBoundStop};
use crate::certify::settings::BranchAndBoundSettings;
use crate::certify::tolerance::GapTolerance;
use crate::so3::{self, Rotation};
use nalgebra::Vector3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::f64::consts::PI;
use std::time::Instant;

/// `sqrt 3` rounded up.
const SQRT_3_UP: f64 = 1.732_050_807_568_877_4;

/// Cells smaller than this half side are not split (the rounding margins would dominate).
const MIN_HALF_SIDE: f64 = 1e-11;

/// What the search needs of a problem.
pub(crate) trait Terms {
    /// The solution type of the local solver.
    type Solution;
    /// The data margin `[B6]` subtracted from every ball bound (infinite: no proof possible).
    fn data_slack(&self) -> f64;
    /// A proven lower bound of the cost on the geodesic ball `B(centre, radius)` and the
    /// cost at the centre.
    fn ball(&self, centre: &Rotation, radius: f64) -> BallBound;
    /// The cost as the crate defines it (the problem's `cost`).
    fn cost(&self, x: &Rotation) -> f64;
    /// The local solver started at `start`, with the cost of its result.
    fn local_solve(&self, start: &Rotation) -> Option<(Self::Solution, f64)>;
    /// The rotation of a solution.
    fn rotation(solution: &Self::Solution) -> Rotation;
}

/// A cube of the axis-angle domain: centre `c`, half side `h`; every rotation `exp(v)`,
/// `v` in the cube, is within `sqrt 3 h` of `exp(c)` (`[B1]`).
#[derive(Debug, Clone, Copy)]
struct Cell {
    c: [f64; 3],
    h: f64,
    depth: u32,
    lb: f64,
}

impl Cell {
    fn radius(&self) -> f64 {
        SQRT_3_UP * self.h * (1.0 + 4.0 * f64::EPSILON)
    }
    /// `true` when no point of the cube has norm `<= pi` (no rotation needs it).
    fn outside_pi_ball(&self) -> bool {
        let d2: f64 = self
            .c
            .iter()
            .map(|x| (x.abs() - self.h).max(0.0).powi(2))
            .sum();
        d2.sqrt() > PI * (1.0 + 1e-12)
    }
    fn centre(&self) -> Rotation {
        so3::exp(&Vector3::new(self.c[0], self.c[1], self.c[2]))
    }
}

impl PartialEq for Cell {
    fn eq(&self, other: &Self) -> bool {
        self.lb.total_cmp(&other.lb) == Ordering::Equal
    }
}
impl Eq for Cell {}
impl PartialOrd for Cell {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Cell {
    /// Reversed: the heap pops the smallest lower bound first.
    fn cmp(&self, other: &Self) -> Ordering {
        other.lb.total_cmp(&self.lb)
    }
}

/// A ball around an incumbent whose whole region is bounded at once (`[B5]`).
#[derive(Debug, Clone, Copy)]
struct Ball {
    centre: Rotation,
    radius: f64,
    lb: f64,
}

/// `true` when the ball `B(centre, radius)` (a cell's) lies inside one of the incumbent balls,
/// whose bounds then cover it (`[B5]`), with twice the error of a computed angle to spare
/// (`[B6]`).
fn inside_a_ball(balls: &[Ball], centre: &Rotation, radius: f64) -> bool {
    balls
        .iter()
        .any(|b| so3::angle_between(centre, &b.centre) + radius + 2.0 * ANGLE_ERROR <= b.radius)
}

/// The largest radius `2^-j pi` (`j = 0..50`) whose ball bound is within `allowed / 4` of
/// `cost`, with that bound.
fn incumbent_ball<T: Terms>(terms: &T, centre: &Rotation, cost: f64, allowed: f64) -> Option<Ball> {
    let mut radius = PI;
    for _ in 0..50 {
        let b = terms.ball(centre, radius);
        if b.lower_bound >= cost - 0.25 * allowed {
            return Some(Ball {
                centre: *centre,
                radius,
                lb: b.lower_bound,
            });
        }
        radius *= 0.5;
    }
    None
}

/// The outcome of a search.
pub(crate) struct Outcome<S> {
    /// Proven lower bound of the global minimum.
    pub lower_bound: f64,
    /// The best local solution found (its cost), if any local solve improved on the estimate.
    pub best: Option<(S, f64)>,
    /// Statistics.
    pub stats: BranchAndBoundStats,
}

/// Branch and bound from `estimate` (cost `cost`): stops when the lower bound is within the
/// tolerance of the best cost found, or at the cell / time budget (`max_seconds`).
pub(crate) fn search<T: Terms>(
    terms: &T,
    estimate: &Rotation,
    cost: f64,
    tolerance: GapTolerance,
    settings: &BranchAndBoundSettings,
    max_seconds: Option<f64>,
) -> Outcome<T::Solution> {
    let start = Instant::now();
    let mut best_cost = cost;
    let mut best: Option<(T::Solution, f64)> = None;
    let mut stats = BranchAndBoundStats::default();
    let mut balls: Vec<Ball> = Vec::new();
    if let Some(b) = incumbent_ball(terms, estimate, cost, tolerance.allowed_gap(cost)) {
        stats.ball_radius = b.radius;
        balls.push(b);
    }
    let mut heap: BinaryHeap<Cell> = BinaryHeap::new();
    let mut pruned_min = f64::INFINITY;
    let k = settings.initial_divisions.max(1);
    let h0 = PI / k as f64;
    let mut pending: Vec<Cell> = Vec::with_capacity(k * k * k);
    for i in 0..k {
        for j in 0..k {
            for l in 0..k {
                let at = |m: usize| -PI + (2 * m + 1) as f64 * h0;
                pending.push(Cell {
                    c: [at(i), at(j), at(l)],
                    h: h0,
                    depth: 0,
                    lb: 0.0,
                });
            }
        }
    }
    let mut stop = BranchAndBoundStop::Converged;
    loop {
        // Bound the pending cells.
        for mut cell in pending.drain(..) {
            if cell.outside_pi_ball() {
                continue;
            }
            let centre = cell.centre();
            let r = cell.radius();
            if inside_a_ball(&balls, &centre, r) {
                stats.cells_in_balls += 1;
                continue;
            }
            let bound = terms.ball(&centre, r);
            stats.cells_explored += 1;
            stats.max_depth = stats.max_depth.max(cell.depth);
            cell.lb = bound.lower_bound;
            let allowed = tolerance.allowed_gap(best_cost);
            if bound.centre_cost < best_cost - allowed {
                let exact = terms.cost(&centre);
                if exact < best_cost - allowed && stats.local_solves < settings.max_local_solves {
                    stats.local_solves += 1;
                    let (point, c) = match terms.local_solve(&centre) {
                        Some((s, c)) if c < exact => (Some(s), c),
                        _ => (None, exact),
                    };
                    if c < best_cost {
                        best_cost = c;
                        if let Some(s) = point {
                            let at = T::rotation(&s);
                            if let Some(b) = incumbent_ball(terms, &at, c, tolerance.allowed_gap(c))
                            {
                                balls.push(b);
                            }
                            best = Some((s, c));
                        }
                    }
                } else if exact < best_cost {
                    best_cost = exact;
                }
            }
            if cell.lb >= best_cost - 0.5 * tolerance.allowed_gap(best_cost) {
                pruned_min = pruned_min.min(cell.lb);
                stats.cells_pruned += 1;
            } else {
                heap.push(cell);
            }
        }
        // The next cell to split.
        let threshold = best_cost - 0.5 * tolerance.allowed_gap(best_cost);
        let Some(cell) = heap.pop() else { break };
        if cell.lb >= threshold {
            pruned_min = pruned_min.min(cell.lb);
            stats.cells_pruned += 1;
            continue;
        }
        if inside_a_ball(&balls, &cell.centre(), cell.radius()) {
            stats.cells_in_balls += 1;
            continue;
        }
        let over_time = max_seconds.is_some_and(|t| start.elapsed().as_secs_f64() > t);
        let reason = if stats.cells_explored + 8 > settings.max_cells {
            Some(BranchAndBoundStop::CellBudget)
        } else if over_time {
            Some(BranchAndBoundStop::TimeBudget)
        } else if cell.h < MIN_HALF_SIDE {
            Some(BranchAndBoundStop::Resolution)
        } else {
            None
        };
        if let Some(reason) = reason {
            stop = reason;
            heap.push(cell);
            break;
        }
        let h = 0.5 * cell.h;
        for dx in [-h, h] {
            for dy in [-h, h] {
                for dz in [-h, h] {
                    pending.push(Cell {
                        c: [cell.c[0] + dx, cell.c[1] + dy, cell.c[2] + dz],
                        h,
                        depth: cell.depth + 1,
                        lb: 0.0,
                    });
                }
            }
        }
    }
    // a NaN cell bound counts as the trivial 0 (f64::min would skip it)
    let valid = |lb: f64| if lb.is_nan() { 0.0 } else { lb };
    let live_min = heap
        .iter()
        .map(|c| valid(c.lb))
        .fold(f64::INFINITY, f64::min);
    let ball_min = balls
        .iter()
        .map(|b| valid(b.lb))
        .fold(f64::INFINITY, f64::min);
    let mut lower_bound = live_min.min(pruned_min).min(ball_min);
    if !lower_bound.is_finite() {
        // Nothing was bounded (cannot happen: the cells cover SO(3)); 0 is always a bound.
        lower_bound = 0.0;
    }
    stats.live_cells = heap.len();
    stats.stop = stop;
    stats.lower_bound = lower_bound;
    stats.best_cost = best_cost;
    stats.seconds = start.elapsed().as_secs_f64();
    Outcome {
        lower_bound,
        best,
        stats,
    }
}
