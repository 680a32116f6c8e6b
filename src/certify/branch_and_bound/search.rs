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
    /// The eight cells of half the side.
    fn children(&self) -> impl Iterator<Item = Cell> + '_ {
        let h = 0.5 * self.h;
        [-h, h].into_iter().flat_map(move |dx| {
            [-h, h].into_iter().flat_map(move |dy| {
                [-h, h].into_iter().map(move |dz| Cell {
                    c: [self.c[0] + dx, self.c[1] + dy, self.c[2] + dz],
                    h,
                    depth: self.depth + 1,
                    lb: 0.0,
                })
            })
        })
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
    let mut s = Search::new(terms, estimate, cost, tolerance, settings);
    let mut pending = initial_cells(settings.initial_divisions.max(1));
    let mut stop = BranchAndBoundStop::Converged;
    loop {
        for cell in pending.drain(..) {
            s.bound_cell(cell);
        }
        // The next cell to split.
        let threshold = s.prune_threshold();
        let Some(cell) = s.heap.pop() else { break };
        if cell.lb >= threshold {
            s.pruned_min = s.pruned_min.min(cell.lb);
            s.stats.cells_pruned += 1;
            continue;
        }
        if inside_a_ball(&s.balls, &cell.centre(), cell.radius()) {
            s.stats.cells_in_balls += 1;
            continue;
        }
        let over_time = max_seconds.is_some_and(|t| start.elapsed().as_secs_f64() > t);
        if let Some(reason) = s.budget_stop(&cell, over_time) {
            stop = reason;
            s.heap.push(cell);
            break;
        }
        pending.extend(cell.children());
    }
    s.finish(stop, start)
}

/// The `k^3` cells of half side `pi / k` covering the cube `[-pi, pi]^3`.
fn initial_cells(k: usize) -> Vec<Cell> {
    let h0 = PI / k as f64;
    let mut cells: Vec<Cell> = Vec::with_capacity(k * k * k);
    for i in 0..k {
        for j in 0..k {
            for l in 0..k {
                let at = |m: usize| -PI + (2 * m + 1) as f64 * h0;
                cells.push(Cell {
                    c: [at(i), at(j), at(l)],
                    h: h0,
                    depth: 0,
                    lb: 0.0,
                });
            }
        }
    }
    cells
}

/// The state of a search: the incumbent, the balls around incumbents, the live cells, the
/// smallest bound of a pruned cell and the statistics.
struct Search<'a, T: Terms> {
    terms: &'a T,
    tolerance: GapTolerance,
    settings: &'a BranchAndBoundSettings,
    best_cost: f64,
    best: Option<(T::Solution, f64)>,
    stats: BranchAndBoundStats,
    balls: Vec<Ball>,
    heap: BinaryHeap<Cell>,
    pruned_min: f64,
}

impl<'a, T: Terms> Search<'a, T> {
    /// The search before any cell: the estimate the incumbent, with its ball.
    fn new(
        terms: &'a T,
        estimate: &Rotation,
        cost: f64,
        tolerance: GapTolerance,
        settings: &'a BranchAndBoundSettings,
    ) -> Self {
        let mut stats = BranchAndBoundStats::default();
        let mut balls: Vec<Ball> = Vec::new();
        if let Some(b) = incumbent_ball(terms, estimate, cost, tolerance.allowed_gap(cost)) {
            stats.ball_radius = b.radius;
            balls.push(b);
        }
        Search {
            terms,
            tolerance,
            settings,
            best_cost: cost,
            best: None,
            stats,
            balls,
            heap: BinaryHeap::new(),
            pruned_min: f64::INFINITY,
        }
    }

    /// Cells bounded at or above this are pruned: half the allowed gap below the incumbent.
    fn prune_threshold(&self) -> f64 {
        self.best_cost - 0.5 * self.tolerance.allowed_gap(self.best_cost)
    }

    /// Bound a pending cell (unless it is outside the ball of radius `pi` or inside an
    /// incumbent's ball), improve the incumbent from its centre, then prune or keep it.
    fn bound_cell(&mut self, mut cell: Cell) {
        if cell.outside_pi_ball() {
            return;
        }
        let centre = cell.centre();
        let r = cell.radius();
        if inside_a_ball(&self.balls, &centre, r) {
            self.stats.cells_in_balls += 1;
            return;
        }
        let bound = self.terms.ball(&centre, r);
        self.stats.cells_explored += 1;
        self.stats.max_depth = self.stats.max_depth.max(cell.depth);
        cell.lb = bound.lower_bound;
        let allowed = self.tolerance.allowed_gap(self.best_cost);
        if bound.centre_cost < self.best_cost - allowed {
            self.improve_from(&centre, allowed);
        }
        if cell.lb >= self.prune_threshold() {
            self.pruned_min = self.pruned_min.min(cell.lb);
            self.stats.cells_pruned += 1;
        } else {
            self.heap.push(cell);
        }
    }

    /// A centre whose cost estimate beats the incumbent by more than `allowed`: its exact
    /// cost, and a local solve from it while the budget of local solves lasts; a solution
    /// that improves becomes the incumbent, with its ball.
    fn improve_from(&mut self, centre: &Rotation, allowed: f64) {
        let exact = self.terms.cost(centre);
        if exact < self.best_cost - allowed
            && self.stats.local_solves < self.settings.max_local_solves
        {
            self.stats.local_solves += 1;
            let (point, c) = match self.terms.local_solve(centre) {
                Some((s, c)) if c < exact => (Some(s), c),
                _ => (None, exact),
            };
            if c < self.best_cost {
                self.best_cost = c;
                if let Some(s) = point {
                    let at = T::rotation(&s);
                    let allowed = self.tolerance.allowed_gap(c);
                    if let Some(b) = incumbent_ball(self.terms, &at, c, allowed) {
                        self.balls.push(b);
                    }
                    self.best = Some((s, c));
                }
            }
        } else if exact < self.best_cost {
            self.best_cost = exact;
        }
    }

    /// Why the search stops before splitting `cell`, if it does: the cell budget, the time
    /// budget (`over_time`) or the resolution.
    fn budget_stop(&self, cell: &Cell, over_time: bool) -> Option<BranchAndBoundStop> {
        if self.stats.cells_explored + 8 > self.settings.max_cells {
            Some(BranchAndBoundStop::CellBudget)
        } else if over_time {
            Some(BranchAndBoundStop::TimeBudget)
        } else if cell.h < MIN_HALF_SIDE {
            Some(BranchAndBoundStop::Resolution)
        } else {
            None
        }
    }

    /// The proven lower bound: the smallest bound of a live cell, a pruned cell or a ball.
    fn finish(mut self, stop: BranchAndBoundStop, start: Instant) -> Outcome<T::Solution> {
        // a NaN cell bound counts as the trivial 0 (f64::min would skip it)
        let valid = |lb: f64| if lb.is_nan() { 0.0 } else { lb };
        let live_min = self
            .heap
            .iter()
            .map(|c| valid(c.lb))
            .fold(f64::INFINITY, f64::min);
        let ball_min = self
            .balls
            .iter()
            .map(|b| valid(b.lb))
            .fold(f64::INFINITY, f64::min);
        let mut lower_bound = live_min.min(self.pruned_min).min(ball_min);
        if !lower_bound.is_finite() {
            // Nothing was bounded (cannot happen: the cells cover SO(3)); 0 is always a bound.
            lower_bound = 0.0;
        }
        self.stats.live_cells = self.heap.len();
        self.stats.stop = stop;
        self.stats.lower_bound = lower_bound;
        self.stats.best_cost = self.best_cost;
        self.stats.seconds = start.elapsed().as_secs_f64();
        Outcome {
            lower_bound,
            best: self.best,
            stats: self.stats,
        }
    }
}
