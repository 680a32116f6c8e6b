//! The verdict of a certification of multiple averaging: the certificate of the *given*
//! estimate from the best verified bound of its climb, in words (its diagnosis, the better
//! estimate found if any, how the bound was proven), and the improvement.

use super::diagnosis::{DualDiagnosis, diagnosis_text};
use super::dual::attach_randomized;
use super::state::{Best, State};
use crate::certify::certificate::Certificate;
use crate::certify::certification::{Improvement, ImprovementSource};
use crate::certify::log::Point;
use crate::certify::proof::BoundMethod;
use crate::certify::spectrum::certificate_spectrum;
use crate::certify::tolerance::GapTolerance;
use crate::multiple::MultipleSolution;

/// The certificate of the given estimate from the best bound (the improvement's is
/// [`Certificate::with_upper_bound`]); with `settings.spectrum` set, also the
/// smallest-eigenvalue estimates of that bound's certificate matrix `[D14]`.
pub(crate) fn certificate(cx: &mut State<'_>) -> Certificate {
    let seconds = cx.deadline.elapsed();
    let tolerance = cx.settings.tolerance.resolve(cx.problem.min_weight());
    let first = first_diagnosis(cx);
    let mut c = match cx.best.take() {
        None => Certificate::from_bounds(
            cx.cost,
            None,
            BoundMethod::Dual,
            None,
            tolerance,
            format!(
                "no lower bound could be computed; {}",
                diagnosis_text(&first, cx.problem)
            ),
            seconds,
        ),
        Some(b) => certificate_of(cx, b, &first, seconds),
    };
    // a Monte Carlo bound [D16] is a bound on the global minimum whatever point gave it
    let randomized = attach_randomized(&mut c, cx.last.as_ref().and_then(|l| l.randomized));
    c.explanation.push_str(&randomized);
    c
}

/// The given estimate's diagnosis: its dual certificate's, "not a critical point" when its
/// own multipliers were found hopeless, "certified" when another rung certified it first.
fn first_diagnosis(cx: &State<'_>) -> DualDiagnosis {
    match &cx.first {
        Some(d) => d.clone(),
        None if cx.best_certifies() => DualDiagnosis::Certified,
        None => DualDiagnosis::NotCritical {
            residual: cx.given_stationarity_residual.unwrap_or(f64::NAN),
        },
    }
}

fn certificate_of(cx: &State<'_>, b: Best, first: &DualDiagnosis, seconds: f64) -> Certificate {
    let tolerance = cx.settings.tolerance.resolve(cx.problem.min_weight());
    let mut c = Certificate::from_bounds(
        cx.cost,
        Some(b.lower_bound),
        b.method,
        b.min_eigenvalue,
        tolerance,
        String::new(),
        seconds,
    );
    let mut verdict = if c.is_certified() && matches!(b.point, Point::ConvSdp | Point::ConvDual) {
        format!(
            "certified globally optimal for the anisotropic chordal L2 cost of its {} edges \
             (a bound over conv(SO(3)) Gram blocks, hence over SO(3)^n: on these data the \
             O(3) relaxation can prefer reflections)",
            cx.problem.num_edges()
        )
    } else if c.is_certified() {
        diagnosis_text(&DualDiagnosis::Certified, cx.problem)
    } else {
        match first {
            // the estimate's own dual certificate would certify, but a bound from another
            // point is what was kept: say it plainly
            DualDiagnosis::Certified => "not certified within the tolerance".to_string(),
            d => diagnosis_text(d, cx.problem),
        }
    };
    verdict.push_str(&improvement_text(cx, &b, &tolerance));
    c.explanation = format!(
        "{verdict}; bound ({}, at {}): {}",
        b.method, b.point, b.explanation
    );
    c.verified_min_eigenvalue = Some(b.verified_min_eigenvalue);
    c.bound_from = Some(b.point);
    if let (Some(sp), Some(l)) = (cx.settings.spectrum.as_ref(), &b.lambdas) {
        // an estimate for a figure: its failure never fails the certification
        c.smallest_eigenvalues = certificate_spectrum(cx.problem, l, sp, b.shift).ok();
    }
    c
}

/// The better estimate found, in words, and whether the bound certifies it.
fn improvement_text(cx: &State<'_>, b: &Best, tolerance: &GapTolerance) -> String {
    let Some((s, source)) = &cx.current.solution else {
        return String::new();
    };
    let better = s.chordal_cost;
    if better >= cx.cost {
        return String::new();
    }
    let certified =
        b.lower_bound.is_finite() && better - b.lower_bound <= tolerance.allowed_gap(better);
    format!(
        "; a better estimate was found ({}: cost {better:.9e}){}",
        match source {
            ImprovementSource::Refinement => "the estimate refined by the local solver",
            ImprovementSource::SdpRounding => "the SDP rounding polished by the local solver",
            ImprovementSource::BranchAndBound => "a local solve from a branch-and-bound cell",
            ImprovementSource::StaircaseRounding => {
                "the staircase rounding polished by the local solver"
            }
            ImprovementSource::ConvSdpRounding => {
                "the conv(SO(3)) SDP rounding polished by the local solver"
            }
            ImprovementSource::RigPolish => "the rig solver's polish",
        },
        if certified {
            ", which the bound below certifies globally optimal"
        } else {
            ""
        }
    )
}

/// The improvement, when strictly cheaper than the given estimate, and its record.
pub(crate) fn improvement(cx: &mut State<'_>) -> Option<(MultipleSolution, Improvement)> {
    match cx.current.solution.take() {
        Some((s, source)) if cx.cost - s.chordal_cost > 1e-15 * cx.cost.abs() => {
            let record = Improvement {
                source,
                cost: s.chordal_cost,
            };
            Some((s, record))
        }
        _ => None,
    }
}
