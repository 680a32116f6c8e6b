//! The coupled bound of a rig (`paper-notes/conjugate.md` `[H21]`): the images' view graph with
//! pseudo-edges inside each frame ([`super::couplings`]), whose cost on rig points is the
//! rig's cost plus a constant. Its components' certified minima, less that constant, bound `J*`;
//! tight on the noisy rigs where the images' bound `[H19]` leaves a gap.

use super::couplings::{self, Coupled, couple};
use super::images::{Start, components_minimum};
use super::search::{Limits, SEARCH_MAX_IMAGES, search};
use super::state::RigState;
use crate::certify::log::{Prediction, Refusal};
use crate::certify::multiple::block::regional_dual_bound;
use crate::certify::multiple::scalar::grouped_dual_bound;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, GraphCertifier, Handed, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::deadline::Deadline;
use crate::error::Result;
use crate::rig::{RigProblem, polish_passes};
use crate::so3::Rotation;

/// The coupled bound as a rung; with the reason when planned for the bounds by sensor alone
/// (the augmented graph's checks over their cap, [`fill_refusal`]).
pub(crate) struct CoupledRung(pub(crate) Handed<GraphCertifier>, pub(crate) Option<String>);

impl<'a> Rung<RigState<'a>> for CoupledRung {
    fn proof(&self) -> Proof {
        Proof::RigCoupled
    }

    fn plan(&mut self, cx: &RigState<'a>) -> Result<Plan> {
        if self.0.done {
            return Ok(Plan::Done);
        }
        if cx.problem.all_held() {
            // the frames' view graph is then the rig's problem itself ([H19]); the couplings'
            // bound, a relaxation over free images, can only be weaker (a 6000-image rig with
            // information: 360 s for a bound of 1.74e5 against the frames' 4.98e5, 2026-12-08)
            return Ok(Plan::Refuse(
                Refusal::NotApplicable {
                    reason: "every sensor held: the frames' view graph is the rig's problem itself [H19]"
                        .into(),
                },
                None,
            ));
        }
        if !joins_sensors(cx.problem) {
            return Ok(Plan::Refuse(
                Refusal::NotApplicable {
                    reason: "no edge joins two sensors' images: the least-norm couplings do \
                             not certify such rigs (generated rigs of 100-300 frames: none \
                             certified without such edges, all with 10 % of frames having one) \
                             [H21]"
                        .into(),
                },
                None,
            ));
        }
        // the images' view graph with up to three pseudo-edges per pair of images of a frame
        let images = cx.problem.images().len() as f64;
        let size = 4.0 * images + cx.problem.edges().len() as f64;
        let cap = fill_cap(cx);
        if let Some(reason) = fill_refusal(cx.problem, cap)? {
            // the sensors' own graphs factorised apart: one pencil each ([D13], groups), or
            // with information matrices the regional bound [A16] with its deflation (10^4
            // frames and 2 sensors: about 2e-4 s per unit of size, 2026-12-03)
            self.1 = Some(reason);
            let seconds = if cx.problem.is_anisotropic() {
                2e-4
            } else {
                3e-5
            };
            return Ok(Plan::Run(Prediction::new(seconds * size, 3000.0 * size)));
        }
        Ok(Plan::Run(Prediction::new(6e-6 * size, 6000.0 * size)))
    }

    fn attempt(&mut self, cx: &mut RigState<'a>) -> Result<Found> {
        self.0.done = true;
        let clock = std::time::Instant::now();
        let (frames, sensors, coupled, passes) = match polished(cx)? {
            Ok(found) => found,
            Err(why) => return Ok(Found::failed(why)),
        };
        if passes > 0 {
            let report = polish_report(passes, coupled.charge, cx.tally.allowed_gap, clock);
            cx.improve(frames.clone(), sensors.clone(), report);
        }
        // the augmented cost is about `cost + offset`: its tolerance made a quarter of the rig's
        let mut settings = cx.tally.settings.clone();
        // the couplings are chosen for the estimate's own multipliers: the dual certificate at
        // it is the proof that can use them (no SDP or staircase of the augmented graph); its
        // pseudo-edges are far from consistent (rotations by pi/2 and pi), so the scalar
        // comparison's sparsified subgraphs and splits fail: the whole graph's alone
        if settings.mode == CertifyMode::Auto {
            settings.mode = CertifyMode::Dual;
        }
        settings.dual.scalar_fallbacks = false;
        // the block comparison's subgraphs `[A15]` fail alike (a 3000-frame, 6-sensor rig:
        // 1744 negative pivots at both couplings, its planning 8 s of 47)
        settings
            .dual
            .proofs
            .retain(|&p| p != Proof::BlockComparison);
        settings.dual.max_factor_nonzeros = coupled_cap(cx);
        // a labelled estimate is no bound of the rig's: not run
        settings.dual.randomized.enabled = false;
        let augmented = cx.tally.cost + coupled.offset.max(0.0);
        if augmented > 0.0 {
            let relative = 0.25 * cx.tally.allowed_gap / augmented;
            settings.tolerance.relative = settings.tolerance.relative.min(relative);
        }
        let x = cx.problem.image_rotations(&frames, &sensors);
        let (coupled, found, searched) = self.searched(cx, coupled, (&x, &sensors), &settings)?;
        let (parts, sum, grouped) = match found {
            Ok(found) => found,
            Err(why) => return Ok(Found::failed(why)),
        };
        let bound = rig_bound(cx, sum, coupled.offset);
        let note = format!(
            "the images' view graph with {} within-frame coupling edges{}{searched}: {parts} \
             component(s), certified minima summing to {sum:.9e}{}, less the couplings' \
             constant {:.9e} [H21]",
            coupled.pseudo_edges,
            match passes {
                0 => String::new(),
                n => format!(" (at the estimate polished by {n} steps of the rig's solver)"),
            },
            match (grouped, cx.problem.is_anisotropic()) {
                (false, _) => "",
                (true, false) => {
                    " (by the grouped scalar comparison [D13]: each sensor's images factorised apart)"
                }
                (true, true) => {
                    " (by the regional bound [A16]: each sensor's images' exact block factorised \
                     apart)"
                }
            },
            coupled.offset
        );
        let bound = cx.offer(bound, Proof::RigCoupled, &note);
        Ok(Found::proved(bound, cx.tally.certifies(bound), note))
    }
}

/// A bound of the augmented graph's minimum: `(components, bound, by the sensors apart)`, or
/// why there is none.
type Minimum = std::result::Result<(usize, f64, bool), String>;

impl CoupledRung {
    /// The least-norm couplings' bound, or, where it does not certify, the couplings of the
    /// search (`[H21]`, "The search"; within a third of the time left) with theirs when it is
    /// larger: the couplings, their bound and a note of the search. On a rig of more than
    /// [`SEARCH_MAX_IMAGES`] images the least-norm couplings are checked first by the grounded
    /// bound alone (one factorisation, `[D15]`); their whole ladder runs only when the
    /// search's couplings do not certify (a 3000-frame, 6-sensor rig: the shifted Cholesky's
    /// bound of an indefinite `S`, 6 s of 30, below zero less the couplings' constant).
    fn searched(
        &self,
        cx: &RigState<'_>,
        coupled: Coupled,
        (x, sensors): (&[Rotation], &[Rotation]),
        settings: &crate::certify::settings::CertifySettings,
    ) -> Result<(Coupled, Minimum, String)> {
        let bound = |m: &Minimum, offset: f64| {
            m.as_ref()
                .map_or(f64::NEG_INFINITY, |&(_, sum, _)| rig_bound(cx, sum, offset))
        };
        let wide = x.len() > SEARCH_MAX_IMAGES;
        let mut first = self.least_norm(cx, &coupled, x, settings, wide)?;
        if cx.tally.certifies(bound(&first, coupled.offset)) {
            return Ok((coupled, first, String::new()));
        }
        let limits = Limits {
            deadline: Deadline::after(cx.tally.left().map(|l| l / 3.0)),
            max_bytes: cx.tally.settings.budget.max_memory_bytes,
            gap: cx.tally.allowed_gap,
        };
        let images = cx.problem.image_graph()?;
        let Some(found) = search(&coupled, &images, (x, sensors), limits)? else {
            if wide {
                first = self.least_norm(cx, &coupled, x, settings, false)?;
            }
            return Ok((coupled, first, String::new()));
        };
        let layout = coupled.layout.clone();
        let again = couplings::coupled(&images, layout, (found.sums, found.traces), sensors)?;
        let second = self.augmented_minimum(cx, &again, x, settings)?;
        if wide && !cx.tally.certifies(bound(&second, again.offset)) {
            first = self.least_norm(cx, &coupled, x, settings, false)?;
        }
        if bound(&second, again.offset) < bound(&first, coupled.offset) {
            return Ok((coupled, first, String::new()));
        }
        let what = if found.grounded {
            "lambda_min(S without image 0), Lanczos estimates"
        } else {
            "lambda_min(S)"
        };
        let note = format!(
            " (their sums searched in {} rounds: {what} {:.3e} -> {:.3e})",
            found.rounds, found.start, found.reached
        );
        Ok((again, second, note))
    }

    /// The least-norm couplings' bound: by the grounded bound alone when `quick`.
    fn least_norm(
        &self,
        cx: &RigState<'_>,
        coupled: &Coupled,
        x: &[Rotation],
        settings: &crate::certify::settings::CertifySettings,
        quick: bool,
    ) -> Result<Minimum> {
        if !quick {
            return self.augmented_minimum(cx, coupled, x, settings);
        }
        self.augmented_minimum(cx, coupled, x, &grounded_only(settings))
    }

    /// A bound on the augmented graph's minimum: `(components, bound, by the sensors apart)`.
    /// With information matrices the regional bound `[A16]` first (each sensor's images'
    /// exact block factorised apart: 3000 frames and 4 sensors certified in 4.5 s of certify
    /// where the whole graph's ladder took 49 s); on isotropic rigs the grouped comparison
    /// first with more than [`SCALAR_PROVES_UP_TO_ESTIMATED`] estimated sensors (where the
    /// whole graph's scalar comparison fails with one negative pivot per estimated sensor),
    /// alone when the whole graph's checks are over their cap; otherwise, or when it does not
    /// certify, the view graph's ladder on each component (the larger bound kept).
    fn augmented_minimum(
        &self,
        cx: &RigState<'_>,
        coupled: &Coupled,
        x: &[Rotation],
        settings: &crate::certify::settings::CertifySettings,
    ) -> Result<std::result::Result<(usize, f64, bool), String>> {
        let augmented = cx.tally.cost + coupled.offset.max(0.0);
        let anisotropic = cx.problem.is_anisotropic();
        let grouped_first = anisotropic
            || self.1.is_some()
            || cx.problem.estimated_sensors().len() > SCALAR_PROVES_UP_TO_ESTIMATED;
        let mut first = Err(String::new());
        if grouped_first {
            first = if anisotropic {
                regional_minimum(cx, &coupled.graph, x)?
            } else {
                grouped_minimum(cx, &coupled.graph, x, augmented)?
            };
            let certifies =
                |&(_, sum): &(usize, f64)| cx.tally.certifies(rig_bound(cx, sum, coupled.offset));
            if let Some(over) = &self.1 {
                return Ok(first
                    .map(|(parts, sum)| (parts, sum, true))
                    .map_err(|why| format!("{why}; the whole graph is not checked: {over}")));
            }
            if first.as_ref().is_ok_and(certifies) {
                return Ok(first.map(|(parts, sum)| (parts, sum, true)));
            }
        }
        let seconds = cx.tally.left().map(|l| 0.6 * l);
        let graph = (&coupled.graph, x, Start::Given);
        let whole = components_minimum(self.0.certify, graph, cx, settings, seconds)?;
        Ok(match (first, whole) {
            (Ok((p, g)), Ok((_, w))) if g > w => Ok((p, g, true)),
            (_, Ok((q, w))) => Ok((q, w, false)),
            (Ok((p, g)), Err(_)) => Ok((p, g, true)),
            (Err(a), Err(b)) if a.is_empty() => Err(b),
            (Err(a), Err(b)) => Err(format!("{a}; {b}")),
        })
    }
}

/// `settings` for the grounded bound alone (`[D15]`, one factorisation): no other check of
/// the dual certificate, and not the `conv(SO(3))` dual's search, a rung of its own that the
/// whole ladder runs after the couplings' search at the same point (a 2000-image rig of 3
/// sensors with information: 42 s each time, `[H24]` "Three sensors").
fn grounded_only(
    settings: &crate::certify::settings::CertifySettings,
) -> crate::certify::settings::CertifySettings {
    let mut quick = settings.clone();
    quick.dual.proofs.retain(|&p| p == Proof::Grounded);
    quick.dual.conv.enabled = false;
    quick
}

/// The rig's bound from the augmented graph's `sum` less the couplings' constant `offset`: with
/// information the augmented graph holds the rig's own data and the pseudo-edges as `c I`,
/// whose trace form's constant is exact (`[H24]`): nothing to charge; otherwise `[H19]`'s
/// rounding floor.
fn rig_bound(cx: &RigState<'_>, sum: f64, offset: f64) -> f64 {
    if cx.problem.is_anisotropic() {
        sum - offset
    } else {
        cx.floor(sum - offset)
    }
}

/// The augmented graph's minimum bounded by the grouped scalar comparison (`[D13]`, groups:
/// one group per sensor, [`sensor_groups`], each factorised apart) at the estimate's own
/// multipliers: `(1, bound)`, or why it did not prove. Its target is the share of the gap
/// that the whole graph's comparison would get (a quarter of the rig's allowed gap over
/// `6n`).
fn grouped_minimum(
    cx: &RigState<'_>,
    graph: &crate::multiple::MultipleProblem,
    x: &[Rotation],
    augmented: f64,
) -> Result<std::result::Result<(usize, f64), String>> {
    let group = sensor_groups(cx.problem);
    let n = x.len().max(1) as f64;
    let target = 0.25 * cx.tally.allowed_gap.min(augmented.abs()) / (6.0 * n);
    let memory =
        usize::try_from(cx.tally.settings.budget.max_memory_bytes / 16).unwrap_or(usize::MAX);
    let max_values = cx
        .tally
        .settings
        .dual
        .max_factor_nonzeros
        .min(COUPLED_MAX_FACTOR_VALUES)
        .min(memory);
    let found = grouped_dual_bound(graph, x, &group, target, (max_values, cx.tally.left()))?;
    Ok(found.map(|(bound, _)| (1, bound)).map_err(|why| {
        format!("the grouped scalar comparison [D13] of the augmented graph: {why}")
    }))
}

/// The grouped comparison's groups: each image in its sensor's group, except an image that no
/// edge of its own sensor measures, which joins the group of its first edge's other image
/// (`[H21]` "Groups"). Any grouping is sound; alone in its group, such an image is a
/// component of one node whose only ties, its pseudo-edges and edges to other sensors, are all
/// charged (a 10^4-frame rig of 6 sensors with 3 of them: a 0.27 % gap instead of certified).
fn sensor_groups(problem: &RigProblem) -> Vec<usize> {
    let images = problem.images();
    let mut group: Vec<usize> = images.iter().map(|im| im.sensor).collect();
    let mut own = vec![false; images.len()];
    for e in problem.edges() {
        if images[e.i].sensor == images[e.j].sensor {
            own[e.i] = true;
            own[e.j] = true;
        }
    }
    for e in problem.edges() {
        for (a, b) in [(e.i, e.j), (e.j, e.i)] {
            if !own[a] && group[a] == images[a].sensor {
                group[a] = images[b].sensor;
            }
        }
    }
    group
}

/// The augmented graph's minimum bounded by the regional bound (`[A16]`: one region per sensor,
/// each sensor's images' exact block of `M` factorised apart, the couplings and the edges
/// between sensors charged) at the estimate's own multipliers: `(1, bound)`, or why it did not
/// prove. Each region's factor within the ladder's cap and the memory budget.
fn regional_minimum(
    cx: &RigState<'_>,
    graph: &crate::multiple::MultipleProblem,
    x: &[Rotation],
) -> Result<std::result::Result<(usize, f64), String>> {
    let region: Vec<usize> = cx.problem.images().iter().map(|im| im.sensor).collect();
    let largest = (0..cx.problem.sensors().len())
        .map(|s| region.iter().filter(|&&r| r == s).count())
        .max()
        .unwrap_or(0);
    let memory = crate::certify::budget::Budget {
        max_seconds: None,
        ..cx.tally.settings.budget
    };
    let max_values = coupled_cap(cx).min(memory.max_factor_values(3 * largest + 3));
    let found = regional_dual_bound(graph, x, &region, (max_values, cx.tally.left()))?;
    Ok(found
        .map(|(bound, _)| (1, bound))
        .map_err(|why| format!("the regional bound [A16] of the augmented graph: {why}")))
}

/// The largest factor the augmented graph's checks may form: [`COUPLED_MAX_FACTOR_VALUES`]
/// for scalar weights; with information matrices the ladder's own budget checks decide (its
/// `3n x 3n` factors: the grounded bound `[D15]` proves these rigs where the block comparison
/// fails; measured on a rig of 10^4 frames and 2 sensors, 1 estimated, `rig_many`: certified in
/// 95 s and 5.9 GB with a 12 GiB budget, a factor of 7.4e8 values, where the 1.5e8 cap left a
/// 25 % gap).
fn coupled_cap(cx: &RigState<'_>) -> usize {
    let cap = cx.tally.settings.dual.max_factor_nonzeros;
    if cx.problem.is_anisotropic() {
        cap
    } else {
        cap.min(COUPLED_MAX_FACTOR_VALUES)
    }
}

/// The cap of [`fill_refusal`]: [`coupled_cap`], and with information matrices the factor the
/// memory budget holds (`3n x 3n`; its time is left to the ladder's predictions, which count
/// the factorisation's multiply-adds).
fn fill_cap(cx: &RigState<'_>) -> usize {
    let cap = coupled_cap(cx);
    if !cx.problem.is_anisotropic() {
        return cap;
    }
    let memory = crate::certify::budget::Budget {
        max_seconds: None,
        ..cx.tally.settings.budget
    };
    cap.min(memory.max_factor_values(3 * cx.problem.images().len()))
}

/// Why the whole augmented graph (the images' view graph and every pair of images of a frame)
/// cannot be checked, when it is connected and the ordering predicts the scalar comparison's
/// factor above `cap` ([`fill_cap`]): no check of it fits (the `3n` ones are at least 9 times
/// it), so the rung runs its bounds by sensor alone (the grouped scalar comparison, or with
/// information matrices the regional bound `[A16]`). With information matrices the checks
/// factorise `S` (`3n x 3n`), predicted as 9 times the scalar factor of the pattern with every
/// pair (the refusal names the memory budget: a larger one proves such rigs). For rigs of at most
/// [`SCALAR_PROVES_UP_TO_ESTIMATED`] estimated sensors that factor is the images' own graph's:
/// the pairs that hold only pseudo-edges keep no weight and leave its pattern (`[D13]`,
/// weightless parallel groups; 10^4 frames and 2 sensors: 6.8e7 values against 8.2e7 with
/// them). A graph of several components is left to its components' own checks.
fn fill_refusal(problem: &RigProblem, cap: usize) -> Result<Option<String>> {
    let images = problem.images();
    let n = images.len();
    let mut per_frame: Vec<Vec<usize>> = vec![Vec::new(); problem.num_frames()];
    for (a, image) in images.iter().enumerate() {
        if let Some(f) = per_frame.get_mut(image.frame) {
            f.push(a);
        }
    }
    let mut pairs: Vec<(usize, usize)> = problem.edges().iter().map(|e| (e.i, e.j)).collect();
    for frame in &per_frame {
        for (k, &a) in frame.iter().enumerate() {
            pairs.extend(frame[k + 1..].iter().map(|&b| (a, b)));
        }
    }
    let mut components = crate::multiple::union_find::UnionFind::new(n);
    let joined = pairs
        .iter()
        .filter(|&&(a, b)| {
            components.find(a) != components.find(b) && {
                components.union(a, b);
                true
            }
        })
        .count();
    if n == 0 || joined + 1 < n {
        return Ok(None);
    }
    // the pairs that hold only pseudo-edges keep no weight: the scalar comparison leaves them
    // out of its pattern (`[D13]`, weightless parallel groups), which is the images' own graph;
    // with more estimated sensors it fails there, and the `3n` factors need every pair
    // with information matrices the checks factorise `S` itself (`3n x 3n`: nine values per
    // scalar one), every pair of a frame's images included
    let (own, per_value) = match problem.estimated_sensors().len() {
        _ if problem.is_anisotropic() => (&pairs[..], 9),
        0..=SCALAR_PROVES_UP_TO_ESTIMATED => (&pairs[..problem.edges().len()], 1),
        _ => (&pairs[..], 1),
    };
    let mut triplets = Vec::with_capacity(2 * own.len() + n);
    triplets.extend((0..n).map(|a| faer::sparse::Triplet::new(a, a, 1.0)));
    for &(a, b) in own {
        triplets.push(faer::sparse::Triplet::new(a, b, 1.0));
        triplets.push(faer::sparse::Triplet::new(b, a, 1.0));
    }
    let pattern = faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| crate::error::Error::Solver {
            message: format!("could not assemble the augmented graph's pattern: {e:?}"),
        })?;
    let within =
        crate::linalg::cholesky::symbolic_cholesky_within(pattern.symbolic(), cap / per_value)?;
    Ok(within.err().map(|predicted| match per_value {
        1 => format!(
            "the augmented graph's scalar factor is predicted at {predicted:.1e} values, \
                 above the {cap:.1e} its checks may form [H21]"
        ),
        _ => format!(
            "the augmented graph's 3n factor is predicted at about {:.1e} values, above the \
                 {cap:.1e} its checks may form within the memory budget (--max-memory) [H21]",
            per_value as f64 * predicted as f64
        ),
    }))
}

/// Some edge joins images of two different sensors (of any frames).
fn joins_sensors(problem: &RigProblem) -> bool {
    let images = problem.images();
    problem
        .edges()
        .iter()
        .any(|e| images[e.i].sensor != images[e.j].sensor)
}

/// The largest factor the augmented graph's checks may form (1.2 GB). Measured on generated
/// rigs (`rig_many`): the factors that certified held 6.8e7 (10^4 frames, 2 sensors, `[D13]`
/// without the weightless pairs) and 9.1e7 values (1000 frames, 6 sensors, `[D15]`); at 10^4
/// frames and 4 sensors `[D13]`'s whole graph took 25 s to fail with 4e8 values (4 negative
/// pivots, 2026-11-30), and 21 s with 1.2e8 without the weightless pairs (3 negative pivots,
/// 2026-12-02; predicted at 2.0e8 by the ordering, so refused here): larger factors are not
/// tried.
const COUPLED_MAX_FACTOR_VALUES: usize = 150_000_000;

/// The most estimated sensors with which the scalar comparison of the augmented graph was seen
/// to prove at scale (10^4 frames, 1 estimated sensor, `rge10000_2`); with 3 (10^4 frames, 4
/// sensors) and 5 (1000 frames, 6 sensors) it fails with 3 and 5 negative pivots
/// (2026-12-02), and only the `3n` factors, of the pattern with every pair of a frame's
/// images, prove: [`fill_refusal`] predicts that pattern's factor for such rigs.
const SCALAR_PROVES_UP_TO_ESTIMATED: usize = 2;

/// Steps of the rig's solver (joint Gauss-Newton steps, or alternation passes where those do not
/// apply) per round of [`polished`] at most, and the most in all.
const POLISH_ROUND: usize = 5;
const POLISH_MAX: usize = 200;

/// The couplings at the estimate, or, while their charge for the sensors' gradient (linear in it,
/// `[H21]`) is above a quarter of the allowed gap, at the estimate polished by the rig's solver
/// ([`polish_passes`]: at most [`POLISH_MAX`] steps, within a third of the time left, until a
/// round takes none): the bound holds for the global minimum from any point. The point, its
/// couplings and the steps taken.
#[allow(clippy::type_complexity)]
fn polished(
    cx: &RigState<'_>,
) -> Result<std::result::Result<(Vec<Rotation>, Vec<Rotation>, Coupled, usize), String>> {
    let (mut frames, mut sensors) = (cx.frames.to_vec(), cx.sensors.to_vec());
    let deadline = Deadline::after(cx.tally.left().map(|l| l / 3.0));
    let mut passes = 0;
    let max_bytes = cx.tally.settings.budget.max_memory_bytes;
    loop {
        // an estimate the couplings or the passes cannot take fails the rung, not the certificate
        let coupled = match couple(cx.problem, &frames, &sensors, max_bytes) {
            Ok(Ok(c)) => c,
            Ok(Err(why)) => return Ok(Err(why)),
            Err(e) => return Ok(Err(e.to_string())),
        };
        let done = coupled.charge <= 0.25 * cx.tally.allowed_gap
            || passes >= POLISH_MAX
            || deadline.is_some_and(|d| d.passed());
        if done {
            return Ok(Ok((frames, sensors, coupled, passes)));
        }
        let seconds = deadline.map(|d| d.left().unwrap_or(0.0));
        let start = (frames.clone(), sensors.clone());
        let (f, s, taken) =
            match polish_passes(cx.problem, start, POLISH_ROUND, (seconds, max_bytes)) {
                Ok(polished) => polished,
                Err(e) => return Ok(Err(format!("the polish failed: {e}"))),
            };
        // stationary to the cost's rounding already: these couplings are the polish's best
        if taken == 0 {
            return Ok(Ok((frames, sensors, coupled, passes)));
        }
        (frames, sensors) = (f, s);
        passes += taken;
    }
}

/// The polish as a solve's report: converged when the couplings' charge came below a quarter
/// of the allowed gap, else stopped at its pass limit or time.
fn polish_report(
    passes: usize,
    charge: f64,
    allowed_gap: f64,
    clock: std::time::Instant,
) -> crate::termination::SolverReport {
    use crate::termination::Termination;
    let (value, threshold) = (charge, 0.25 * allowed_gap);
    let termination = if value <= threshold {
        Termination::Converged {
            measure: "the couplings' charge for the sensors' gradient [H21]".into(),
            value,
            threshold,
        }
    } else {
        Termination::IterationLimit {
            iterations: passes,
            value,
            threshold,
        }
    };
    crate::termination::SolverReport {
        name: "rig polish of the coupled bound [H21] (joint Gauss-Newton steps; alternation \
               passes where they do not apply)"
            .into(),
        iterations: passes,
        termination,
        seconds: clock.elapsed().as_secs_f64(),
    }
}

#[cfg(test)]
mod tests {
    use super::fill_refusal;
    use crate::certify::multiple::block::regional_bound;
    use crate::certify::multiple::multipliers::{certificate_matrix, multipliers};
    use crate::rig::RigScene;
    use crate::so3::{Rotation, perturb_gaussian, random_rotation};
    use nalgebra::Matrix3;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// `lambda_min` of the dense `S` formed by `certificate_matrix` (not by the bound's code).
    fn dense_min(p: &crate::multiple::MultipleProblem, lambdas: &[Matrix3<f64>]) -> f64 {
        let s =
            crate::linalg::cholesky::to_dense(certificate_matrix(p, lambdas).expect("S").as_ref());
        (0.5 * (&s + s.transpose())).symmetric_eigenvalues().min()
    }

    /// The quick check of the least-norm couplings on large rigs is the grounded bound alone: on
    /// data whose `O(3)` relaxation prefers reflections (2 nodes, `H = diag(1, 1, 4)`, `[A5]`)
    /// the whole ladder runs the `conv(SO(3))` dual and proves the minimum 0, the quick check
    /// neither runs it nor proves anything near 0.
    #[test]
    fn the_quick_check_runs_no_conv_search() {
        use crate::certify::multiple::certify_multiple;
        use crate::certify::settings::{CertifyMode, CertifySettings};
        use crate::multiple::anisotropic::Information;
        use crate::multiple::{Edge, MultipleProblem};
        let edge = Edge {
            i: 0,
            j: 1,
            rotation: Rotation::identity(),
            weight: 1.0,
        };
        let h = Information::new(Matrix3::from_diagonal(&nalgebra::Vector3::new(
            1.0, 1.0, 4.0,
        )))
        .unwrap();
        let p = MultipleProblem::new(2, vec![edge])
            .unwrap()
            .with_information(vec![h])
            .unwrap();
        let r = [Rotation::identity(); 2];
        let settings = CertifySettings {
            mode: CertifyMode::Dual,
            ..Default::default()
        };
        let runs_conv = |s: &CertifySettings| {
            let c = certify_multiple(&p, &r, s).unwrap();
            let conv =
                (c.details.ladder.iter()).any(|a| a.rung == crate::certify::proof::Proof::ConvDual);
            (conv, c.certificate.lower_bound.unwrap_or(f64::NEG_INFINITY))
        };
        let (conv, whole) = runs_conv(&settings);
        assert!(conv && whole > -1e-9, "the whole ladder: {whole:e}");
        let (conv, quick) = runs_conv(&super::grounded_only(&settings));
        assert!(!conv && quick < -1.0, "the quick check: {quick:e}");
    }

    /// The estimate perturbed by 1e-5 and 1e-2 rad, and random rotations.
    fn moved_points(y: &[Rotation], rng: &mut StdRng) -> Vec<Vec<Rotation>> {
        let mut out: Vec<Vec<Rotation>> = [1e-5, 1e-2]
            .iter()
            .map(|&eps| y.iter().map(|r| perturb_gaussian(r, eps, rng)).collect())
            .collect();
        out.push(y.iter().map(|_| random_rotation(rng)).collect());
        out
    }

    /// The regional bound on a rig's augmented graph (`[H21]`'s couplings), one region per sensor:
    /// it proves at a local solution, every proven `mu` is at most the dense `lambda_min(S)`, and
    /// with the multipliers lowered by `c` (`S - c I`) it follows it down within `c / 10` (with
    /// the multipliers raised at the nodes with edges to other sensors, and at perturbed and random
    /// points, every proof is at most the dense `lambda_min(S)` too). The cross charges' own
    /// inequality is `block::tests::the_cross_charges_dominate_the_blocks_between_regions`.
    #[test]
    fn the_regional_bound_of_a_rig_is_below_the_smallest_eigenvalue_of_s() {
        for seed in [1, 2] {
            let scene = RigScene {
                frames: 150,
                sensors: 2,
                anisotropy: 9.0,
                seed,
                ..Default::default()
            };
            let (p, y, region) = crate::certify::rig::coupled_graph_for_tests(&scene);
            let own = multipliers(&p, &y).expect("multipliers");
            let scale = own.iter().map(|l| l.norm()).fold(1.0, f64::max);
            let lowered: Vec<Matrix3<f64>> = own
                .iter()
                .map(|l| l + Matrix3::identity() * (1e-10 * scale))
                .collect();
            for (lambdas, c) in [(&own, 0.0), (&lowered, 1e-10 * scale)] {
                let exact = dense_min(&p, lambdas);
                let found = regional_bound(&p, (&y, lambdas), &region, (usize::MAX, None)).unwrap();
                let mu = found.expect("proves").verified_min_eigenvalue;
                assert!(
                    mu <= exact + 1e-12 * scale,
                    "seed {seed}: {mu:e} > {exact:e}"
                );
                assert!(
                    mu >= exact - 0.1 * c - 1e-9 * scale,
                    "seed {seed}: {mu:e} far below {exact:e}"
                );
            }
            // the multipliers raised by half the strength of each node's edges to other sensors:
            // S loses that much of their support, negative through the couplings
            let info = p.information().expect("anisotropic");
            let mut raised = own.clone();
            for (e, h) in p.edges().iter().zip(info) {
                if region[e.i] != region[e.j] {
                    let c = 0.01 * h.matrix().norm();
                    raised[e.i] += Matrix3::identity() * c;
                    raised[e.j] += Matrix3::identity() * c;
                }
            }
            let exact = dense_min(&p, &raised);
            let found = regional_bound(&p, (&y, &raised), &region, (usize::MAX, None)).unwrap();
            if let Ok(proof) = found {
                let mu = proof.verified_min_eigenvalue;
                assert!(
                    mu <= exact + 1e-12 * scale,
                    "seed {seed}, raised: {mu:e} > {exact:e}"
                );
            }
            // perturbed and random points, where S is indefinite through the couplings too
            let mut rng = StdRng::seed_from_u64(seed);
            for (t, z) in moved_points(&y, &mut rng).into_iter().enumerate() {
                let lambdas = multipliers(&p, &z).expect("multipliers");
                let exact = dense_min(&p, &lambdas);
                let found =
                    regional_bound(&p, (&z, &lambdas), &region, (usize::MAX, None)).unwrap();
                if let Ok(proof) = found {
                    let mu = proof.verified_min_eigenvalue;
                    assert!(
                        mu <= exact + 1e-12 * scale,
                        "seed {seed}, point {t}: {mu:e} > {exact:e}"
                    );
                }
            }
        }
    }

    /// The refusal names a prediction over the cap on the 10^4-frame, 4-sensor rig whose
    /// factor took 25 s to fail, and none on the 1000-frame rigs its checks certify.
    #[test]
    fn the_fill_refusal_comes_before_the_polish_where_no_check_fits() {
        let big = RigScene {
            frames: 10_000,
            sensors: 4,
            ..Default::default()
        };
        let (p, _) = big.generate();
        let cap = super::COUPLED_MAX_FACTOR_VALUES;
        let refusal = fill_refusal(&p, cap)
            .expect("pattern")
            .expect("over the cap");
        assert!(
            format!("{refusal:?}").contains("predicted at"),
            "{refusal:?}"
        );
        for sensors in [2, 6] {
            let small = RigScene {
                frames: 1000,
                sensors,
                ..Default::default()
            };
            let (p, _) = small.generate();
            assert!(fill_refusal(&p, cap).expect("pattern").is_none());
        }
    }

    /// With information matrices the refusal predicts the `3n` factor (nine values per scalar
    /// one, every pair of a frame's images in the pattern) against the memory budget's cap:
    /// refused between the scalar count and nine times it, where the same rig with scalar
    /// weights is not, and never without a cap.
    #[test]
    fn an_anisotropic_rig_is_refused_by_its_3n_factor_and_names_the_memory_budget() {
        let scene = |anisotropy| RigScene {
            frames: 300,
            sensors: 2,
            anisotropy,
            ..Default::default()
        };
        let (iso, _) = scene(1.0).generate();
        let (aniso, _) = scene(9.0).generate();
        assert!(aniso.is_anisotropic() && !iso.is_anisotropic());
        assert!(fill_refusal(&aniso, usize::MAX).expect("pattern").is_none());
        // the smallest cap the scalar-weights rig's pattern fits (by bisection on the refusal)
        let (mut low, mut high) = (1usize, 1usize << 40);
        while high - low > 1 {
            let mid = low + (high - low) / 2;
            match fill_refusal(&iso, mid).expect("pattern") {
                Some(_) => low = mid,
                None => high = mid,
            }
        }
        // the anisotropic pattern holds every pair: at least the images' own graph's
        let refusal = fill_refusal(&aniso, 4 * high)
            .expect("pattern")
            .expect("a 3n factor over four times the scalar one");
        assert!(
            format!("{refusal:?}").contains("--max-memory"),
            "{refusal:?}"
        );
        assert!(fill_refusal(&iso, 4 * high).expect("pattern").is_none());
    }
}
