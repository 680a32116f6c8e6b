//! The tolerance of a verdict (contract section 3): certified when `gap <= max(relative |f|,
//! absolute_per_min_weight w_min)`, `w_min` the smallest positive weight of the measurements.

use serde::{Deserialize, Serialize};

/// Default relative part of the verdict's tolerance: certified when `gap <= 1e-6 |f|` (or the
/// absolute part).
pub const DEFAULT_RELATIVE_GAP_TOLERANCE: f64 = 1e-6;
/// Default absolute gap tolerance per unit of the smallest weight (for costs near zero, e.g.
/// noise-free data): the absolute part is `1e-9 x` the smallest positive edge / pair / sample
/// weight (for information matrices, their smallest positive eigenvalue).
pub const DEFAULT_ABSOLUTE_GAP_PER_MIN_WEIGHT: f64 = 1e-9;

/// The rule of the verdict's tolerance (contract section 3): certified when
/// `gap <= max(relative * |f|, absolute_per_min_weight * w_min)`, `w_min` the smallest positive
/// weight of the problem's measurements. Both parts scale with the weights, so multiplying every
/// weight by `c` never changes a verdict; and adding measurements can only lower `w_min`, so no
/// set of measurements (heavy, or uninformative ones of zero cost) can loosen it. In words, the
/// absolute part says: no single measurement's squared chordal residual could shrink by more
/// than `absolute_per_min_weight` (`1e-9`).
///
/// (An earlier rule used the *median* weight: a majority of heavy or uninformative
/// measurements then set the tolerance while the cost was carried by the light ones, and
/// estimates 1.3x to 334x the optimum were certified.)
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ToleranceRule {
    /// Relative part (default `1e-6`).
    pub relative: f64,
    /// Absolute part per unit of the smallest weight (default `1e-9`). Settings written with
    /// the earlier name `absolute_per_median_weight` read into this field.
    #[serde(alias = "absolute_per_median_weight")]
    pub absolute_per_min_weight: f64,
}

impl Default for ToleranceRule {
    fn default() -> Self {
        ToleranceRule {
            relative: DEFAULT_RELATIVE_GAP_TOLERANCE,
            absolute_per_min_weight: DEFAULT_ABSOLUTE_GAP_PER_MIN_WEIGHT,
        }
    }
}

impl ToleranceRule {
    /// Checks both parts are finite and `>= 0`; [`crate::Error::InvalidSettings`] names
    /// `tolerance.relative` or `tolerance.absolute_per_min_weight`.
    pub fn validate(&self) -> crate::Result<()> {
        crate::validate::non_negative("tolerance.relative", self.relative)?;
        crate::validate::non_negative(
            "tolerance.absolute_per_min_weight",
            self.absolute_per_min_weight,
        )
    }

    /// The tolerance for a problem whose smallest positive weight is `min_weight`.
    ///
    /// ```
    /// use rotavg::certify::ToleranceRule;
    /// let t = ToleranceRule::default().resolve(250.0);
    /// assert_eq!((t.relative, t.min_weight), (1e-6, 250.0));
    /// assert!((t.absolute - 2.5e-7).abs() < 1e-20); // 1e-9 x 250
    /// ```
    pub fn resolve(&self, min_weight: f64) -> GapTolerance {
        GapTolerance {
            relative: self.relative,
            absolute: self.absolute_per_min_weight * min_weight,
            min_weight,
        }
    }
}

/// Which part of the tolerance decided (was the larger) at the certificate's cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TolerancePart {
    /// `relative * |f|`.
    Relative,
    /// `absolute_per_min_weight * w_min`.
    Absolute,
}

/// The tolerance that applied to a verdict: certified when
/// `gap <= max(absolute, relative * |f|)`. (Unlike the reported `relative_gap`, the rule has no
/// floor on `|f|`: a floor in the cost's units would not scale with the weights.)
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GapTolerance {
    /// Relative gap tolerance.
    pub relative: f64,
    /// Absolute gap tolerance (in the cost's units).
    pub absolute: f64,
    /// The smallest positive weight the absolute part was scaled by (1 for a fixed absolute
    /// tolerance). Certificates written before the rule changed carry `median_weight`, read
    /// into this field.
    #[serde(default = "one", alias = "median_weight")]
    pub min_weight: f64,
}

fn one() -> f64 {
    1.0
}

impl Default for GapTolerance {
    fn default() -> Self {
        ToleranceRule::default().resolve(1.0)
    }
}

impl GapTolerance {
    /// Checks both parts are finite and `>= 0`; [`crate::Error::InvalidSettings`] names
    /// `tolerance.relative` or `tolerance.absolute`.
    pub fn validate(&self) -> crate::Result<()> {
        crate::validate::non_negative("tolerance.relative", self.relative)?;
        crate::validate::non_negative("tolerance.absolute", self.absolute)
    }

    /// The largest gap that is certified at upper bound `f`:
    /// `max(absolute, relative * |f|)`.
    pub fn allowed_gap(&self, f: f64) -> f64 {
        self.absolute.max(self.relative * f.abs())
    }

    /// Which part is the larger at `f`.
    pub fn decisive_part(&self, f: f64) -> TolerancePart {
        if self.relative * f.abs() >= self.absolute {
            TolerancePart::Relative
        } else {
            TolerancePart::Absolute
        }
    }

    /// The tolerance at `f` in words: its value, which part decided and what that part means.
    ///
    /// ```
    /// use rotavg::certify::ToleranceRule;
    /// let t = ToleranceRule::default().resolve(2.0);
    /// let words = t.describe(1e-4); // 1e-6 x 1e-4 is below 1e-9 x 2
    /// assert!(words.starts_with("gap <= 2.0e-9"), "{words}");
    /// assert!(words.contains("smallest weight 2.0e0"), "{words}");
    /// assert!(t.describe(1e3).contains("1e-6 of the cost"), "{}", t.describe(1e3));
    /// ```
    pub fn describe(&self, f: f64) -> String {
        let allowed = self.allowed_gap(f);
        let per_weight = if self.min_weight > 0.0 {
            self.absolute / self.min_weight
        } else {
            self.absolute
        };
        match self.decisive_part(f) {
            TolerancePart::Relative => format!(
                "gap <= {allowed:.1e} = {:.0e} of the cost (relative part; the absolute part \
                 {:.1e} = {per_weight:.0e} x smallest weight {:.1e} is smaller)",
                self.relative, self.absolute, self.min_weight
            ),
            TolerancePart::Absolute => format!(
                "gap <= {allowed:.1e} = {per_weight:.0e} x smallest weight {:.1e} (absolute \
                 part: no single measurement's squared chordal residual could shrink by more \
                 than {per_weight:.0e}; the relative part {:.0e} of the cost is smaller)",
                self.min_weight, self.relative
            ),
        }
    }
}
