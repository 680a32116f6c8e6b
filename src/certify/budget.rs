//! The memory and time a certification may use ([`Budget`]), the models that predict a rung's
//! cost before it runs, and the one clock of a certification ([`Deadline`]).

use crate::error::{Error, Result};
use crate::linalg::cholesky::RESIDUAL_FACTOR_LIMIT;
use serde::{Deserialize, Serialize};

/// Predicted times below this many seconds are not told apart: such rungs run strongest first
/// (the timer and the time model resolve no finer; `paper-notes/certificates.md` `[D12]`).
pub const FREE_SECONDS: f64 = 0.05;

/// The cost of a rung predicted from the problem before it runs (the models of
/// [`crate::certify::budget::Budget`]), and its chance of proving what the verdict needs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Prediction {
    /// Predicted wall time, seconds.
    pub seconds: f64,
    /// Predicted peak memory of its largest allocation (a factor and its scratch), bytes.
    pub bytes: f64,
    /// The predicted chance, in `(0, 1]`, that it proves what the verdict needs (from cheap
    /// observables of the problem; 1 when nothing predicts a failure). Omitted from JSON at 1.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub success: f64,
}

fn one() -> f64 {
    1.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

impl Prediction {
    /// A prediction of `seconds` and `bytes` with nothing predicting a failure.
    pub fn new(seconds: f64, bytes: f64) -> Self {
        Prediction {
            seconds,
            bytes,
            success: 1.0,
        }
    }

    /// The same prediction with a chance of success `p` (clamped to `[1e-3, 1]`).
    pub fn with_success(self, p: f64) -> Self {
        Prediction {
            success: if p.is_nan() { 1.0 } else { p.clamp(1e-3, 1.0) },
            ..self
        }
    }

    /// The order of the climb: the expected time to a proof, `seconds / success` (the order
    /// that minimises the expected time of a sequence of independent tries), with times below
    /// [`FREE_SECONDS`] tied.
    pub(crate) fn order_key(&self) -> f64 {
        self.seconds.max(FREE_SECONDS) / self.success
    }
}

/// Bytes a factorisation needs per stored factor value (an `f64`). The matrix factorised is
/// not counted (it exists before the factorisation is tried: the shift is added to its diagonal
/// in place); see [`Budget::factorisation_bytes`] for the whole model.
pub const BYTES_PER_FACTOR_VALUE: u64 = 8;

/// Bytes per factor value, for factors of up to [`RESIDUAL_FACTOR_LIMIT`] values, of the
/// residual-based margin `[D6]` (2) (the factor's columns and rows as `(index, value)` pairs).
pub const RESIDUAL_MARGIN_BYTES_PER_VALUE: u64 = 32;

/// Floating-point operations per second assumed when predicting the time of sparse
/// matrix-vector products (the randomized test `[D16]`; memory-bound, one core).
pub const PREDICTED_FLOP_RATE: f64 = 2e9;

/// Multiply-subtracts per second assumed for a sparse factorisation's dense work, which is
/// about `values^2 / dim` for a factor of `values` stored values of a `dim x dim` matrix
/// (Cauchy-Schwarz over the column counts: a lower estimate). Calibrated on the reference
/// 2-core machine (faer 0.24 supernodal, both cores), where the measured rate on that count
/// was 4.3e10 to 7.8e10 for the scalar `LDL^T` of random graphs (10^4 to 10^5 nodes, factors of
/// 1.3e7 to 1.2e9 values) and 2e9 to 2.4e9 for the 3n Cholesky of grids and chains, whose
/// time is mostly per value ([`PREDICTED_SECONDS_PER_FACTOR_VALUE`]).
pub const PREDICTED_FACTOR_RATE: f64 = 1e10;

/// Multiply-adds per second assumed for a sparse `LDL^T` whose symbolic structure is known, so
/// that its exact count is ([`crate::linalg::cholesky::factor_multiply_adds`]): the scalar
/// comparison `[D13]`, whose candidates (whole graph, subgraphs, splits) are analysed before one
/// is chosen ([`Budget::predicted_factor_seconds`]). Calibrated on the reference 2-core machine
/// (faer 0.24 supernodal, both cores, 2026-11-26, `examples/pipeline_scale`, random graphs at
/// 0.1 rad): measured 2.3e10 (1.3e7 values, 0.32 s), 3.4e10 (1.1e8 values, 5.7 s), 4.1e10
/// (4.2e8 values, 35.3 s), 4.4e10 (5.9e8 values, 54.7 s). With
/// [`PREDICTED_SECONDS_PER_COUNTED_VALUE`] the model is 1.2x to 1.6x those times.
pub const PREDICTED_MULTIPLY_ADD_RATE: f64 = 3e10;

/// Seconds per stored factor value besides the multiply-adds (assembly, memory traffic), in
/// the model of [`PREDICTED_MULTIPLY_ADD_RATE`].
pub const PREDICTED_SECONDS_PER_COUNTED_VALUE: f64 = 1e-8;

/// Seconds per stored factor value assumed on top of the dense work (symbolic bookkeeping,
/// assembly, small fronts): the 3n Cholesky of a 10^6-node grid sweep (1.88e8 values) took
/// 4.9 s, predicted 6.8 s; the scalar `LDL^T` of the 10^5-node random graph (1.21e9 values)
/// took about 340 s, predicted 1500 s. Measured predictions run 0.9x to 8x the times.
pub const PREDICTED_SECONDS_PER_FACTOR_VALUE: f64 = 3e-8;

/// The memory and time a certification may use, checked *before* each expensive step from a
/// predicted cost (the factor size from the symbolic analysis, and its time from
/// [`Budget::predicted_seconds`]), so that a run never swaps or hangs: a step that does not fit is not started, and the
/// certificate says why (`inconclusive` when no proof fits).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Budget {
    /// Largest memory one factorisation may need, bytes (default 4 GiB).
    pub max_memory_bytes: u64,
    /// Wall-clock limit of the certification, seconds (default 600; `None`: none). Checked
    /// before each step (dual certificate, refinement, SDP, staircase) and against each
    /// factorisation's predicted time.
    pub max_seconds: Option<f64>,
}

impl Default for Budget {
    fn default() -> Self {
        Budget {
            max_memory_bytes: 4 << 30,
            max_seconds: Some(600.0),
        }
    }
}

impl Budget {
    /// The same budget with the time limit reduced by the time since `start`, to at least
    /// 1 microsecond (a valid budget: a certification with nothing left ends inconclusive).
    /// The pipelines hand their certificate what their solves left of one clock.
    pub fn after(&self, start: std::time::Instant) -> Budget {
        let spent = start.elapsed().as_secs_f64();
        Budget {
            max_seconds: self.max_seconds.map(|t| (t - spent).max(1e-6)),
            ..*self
        }
    }

    /// Check the values; [`Error::InvalidSettings`] names `budget.max_memory_bytes` or
    /// `budget.max_seconds`.
    pub fn validate(&self) -> Result<()> {
        if self.max_memory_bytes == 0 {
            return Err(Error::InvalidSettings {
                name: "budget.max_memory_bytes".into(),
                reason: "must be at least 1".into(),
            });
        }
        if let Some(t) = self.max_seconds {
            crate::validate::positive("budget.max_seconds", t)?;
        }
        Ok(())
    }

    /// The most factor values a factorisation of a `dim x dim` matrix may store within this
    /// budget: the inverse of [`Budget::factorisation_fits`], used to refuse a factorisation
    /// before its symbolic analysis (which itself costs time proportional to the factor).
    ///
    /// ```
    /// use rotavg::certify::Budget;
    /// let b = Budget { max_memory_bytes: 8 << 30, max_seconds: None };
    /// let v = b.max_factor_values(30_000);
    /// assert!(b.factorisation_fits(v, 30_000).is_ok());
    /// assert!(b.factorisation_fits(v + 1, 30_000).is_err());
    /// // below 40 bytes x 2e7 values every value carries the residual margin's 32 bytes
    /// let small = Budget { max_memory_bytes: 100 << 20, max_seconds: None };
    /// assert_eq!(small.max_factor_values(30_000), (100 << 20) / 40);
    /// assert_eq!(Budget::factorisation_bytes(v), (8u64 << 30) as f64);
    /// ```
    pub fn max_factor_values(&self, dim: usize) -> usize {
        // the inverse of `factorisation_bytes` (piecewise linear)
        let full = BYTES_PER_FACTOR_VALUE + RESIDUAL_MARGIN_BYTES_PER_VALUE;
        let limit = RESIDUAL_FACTOR_LIMIT as u64;
        let by_memory = if self.max_memory_bytes <= full * limit {
            self.max_memory_bytes / full
        } else {
            (self.max_memory_bytes - RESIDUAL_MARGIN_BYTES_PER_VALUE * limit)
                / BYTES_PER_FACTOR_VALUE
        };
        let by_time = match self.max_seconds {
            // the positive root of values^2 a + values c = limit
            Some(limit) => {
                let a = 1.0 / (dim.max(1) as f64 * PREDICTED_FACTOR_RATE);
                let c = PREDICTED_SECONDS_PER_FACTOR_VALUE;
                (2.0 * limit / (c + (c * c + 4.0 * a * limit).sqrt())).floor()
            }
            None => f64::INFINITY,
        };
        let mut v = (by_memory as f64).min(by_time).min(usize::MAX as f64) as usize;
        // the float round trip may land one off the exact boundary of `factorisation_fits`
        while v > 0 && self.factorisation_fits(v, dim).is_err() {
            v -= 1;
        }
        while self.factorisation_fits(v.saturating_add(1), dim).is_ok() && v < usize::MAX {
            v += 1;
        }
        v
    }

    /// The memory a factorisation with `values` stored factor values allocates, bytes:
    /// [`BYTES_PER_FACTOR_VALUE`] per value, plus [`RESIDUAL_MARGIN_BYTES_PER_VALUE`] per value
    /// for the first [`RESIDUAL_FACTOR_LIMIT`] (the residual margin `[D6]` (2), computed only
    /// for factors up to that size). Callers that know the numeric scratch add it to `values`
    /// in units of 8 bytes. Measured (faer 0.24, supernodal, 10^6-node grid sweep,
    /// `examples/pipeline_scale`): a factor of 1.88e8 values, 2.1 GiB by this model; the whole
    /// process peaked at 3.8 GB RSS, against 1.7 GB for the solve alone.
    ///
    /// ```
    /// use rotavg::certify::Budget;
    /// assert_eq!(Budget::factorisation_bytes(1_000), 40_000.0);
    /// assert_eq!(Budget::factorisation_bytes(100_000_000), 8e8 + 6.4e8);
    /// ```
    pub fn factorisation_bytes(values: usize) -> f64 {
        values as f64 * BYTES_PER_FACTOR_VALUE as f64
            + values.min(RESIDUAL_FACTOR_LIMIT) as f64 * RESIDUAL_MARGIN_BYTES_PER_VALUE as f64
    }

    /// The predicted time of a factorisation with `values` stored factor values of a
    /// `dim x dim` matrix: `values^2 / dim / PREDICTED_FACTOR_RATE + values *
    /// PREDICTED_SECONDS_PER_FACTOR_VALUE` (calibration in [`PREDICTED_FACTOR_RATE`]).
    ///
    /// ```
    /// use rotavg::certify::Budget;
    /// // the 10^5-node random graph's scalar LDL^T: 1.21e9 values, about 340 s measured
    /// let t = Budget::predicted_seconds(1_210_000_000, 100_000);
    /// assert!(t > 340.0 && t < 2000.0, "{t}");
    /// ```
    pub fn predicted_seconds(values: usize, dim: usize) -> f64 {
        let v = values as f64;
        v * v / dim.max(1) as f64 / PREDICTED_FACTOR_RATE + v * PREDICTED_SECONDS_PER_FACTOR_VALUE
    }

    /// `Err(reason)` when a factorisation with `values` stored factor values of a
    /// `dim x dim` matrix does not fit: memory [`Budget::factorisation_bytes`], time
    /// [`Budget::predicted_seconds`].
    ///
    /// ```
    /// use rotavg::certify::Budget;
    /// let b = Budget { max_memory_bytes: 8 << 30, max_seconds: None };
    /// assert!(b.factorisation_fits(10_000_000, 30_000).is_ok());
    /// let why = b.factorisation_fits(41_000_000_000, 300_000).unwrap_err();
    /// assert!(why.contains("4.1e10"), "{why}");
    /// ```
    pub fn factorisation_fits(&self, values: usize, dim: usize) -> std::result::Result<(), String> {
        self.fits_with(
            values,
            Self::predicted_seconds(values, dim),
            "values^2 / dim multiply-subtracts at 1e10 per second plus 3e-8 s per value; 0.9x \
             to 8x the measured times",
        )
    }

    /// `Err(reason)` when a rung's predicted memory does not fit, or its predicted time does not
    /// fit what is left of the time budget after `elapsed` seconds (the SDP rungs of multiple
    /// and simultaneous averaging).
    ///
    /// ```
    /// use rotavg::certify::{Budget, Prediction};
    /// let b = Budget { max_memory_bytes: 1 << 30, max_seconds: Some(10.0) };
    /// assert!(b.prediction_fits(&Prediction::new(1.0, 1e8), 0.0).is_ok());
    /// assert!(b.prediction_fits(&Prediction::new(1.0, 7.6e10), 0.0).is_err());
    /// assert!(b.prediction_fits(&Prediction::new(5.0, 1e8), 6.0).is_err());
    /// ```
    pub fn prediction_fits(
        &self,
        predicted: &Prediction,
        elapsed: f64,
    ) -> std::result::Result<(), String> {
        if predicted.bytes > self.max_memory_bytes as f64 {
            return Err(format!(
                "predicted {:.1} GB, memory budget {:.1} GB",
                predicted.bytes / 1e9,
                self.max_memory_bytes as f64 / 1e9
            ));
        }
        match self.max_seconds {
            Some(limit) if predicted.seconds > limit - elapsed => Err(format!(
                "predicted {:.0} s, {:.0} s of the time budget left",
                predicted.seconds,
                (limit - elapsed).max(0.0)
            )),
            _ => Ok(()),
        }
    }

    /// The predicted time of factorisations whose multiply-adds are counted from their symbolic
    /// structure: `multiply_adds / PREDICTED_MULTIPLY_ADD_RATE + values *
    /// PREDICTED_SECONDS_PER_COUNTED_VALUE` (calibration in [`PREDICTED_MULTIPLY_ADD_RATE`]).
    ///
    /// ```
    /// use rotavg::certify::Budget;
    /// // one part of the split comparison of a 10^5-node graph with 10^6 edges: 4.5e8 values,
    /// // 1.6e12 multiply-adds, 37.5 s measured
    /// let t = Budget::predicted_factor_seconds(1.596e12, 450_389_772);
    /// assert!(t > 37.5 && t < 80.0, "{t}");
    /// ```
    pub fn predicted_factor_seconds(multiply_adds: f64, values: usize) -> f64 {
        multiply_adds / PREDICTED_MULTIPLY_ADD_RATE
            + values as f64 * PREDICTED_SECONDS_PER_COUNTED_VALUE
    }

    /// `Err(reason)` when factorisations, the largest with `values` stored values (held one at
    /// a time), together of `multiply_adds` counted multiply-adds, do not fit: memory
    /// [`Budget::factorisation_bytes`] of the largest, time
    /// [`Budget::predicted_factor_seconds`] of all.
    ///
    /// ```
    /// use rotavg::certify::Budget;
    /// let b = Budget { max_memory_bytes: 4 << 30, max_seconds: Some(600.0) };
    /// assert!(b.counted_factorisations_fit(450_000_000, 6.0 * 1.6e12, 2_700_000_000).is_ok());
    /// let why = b.counted_factorisations_fit(450_000_000, 6.0 * 4e12, 2_700_000_000).unwrap_err();
    /// assert!(why.contains("time budget 600 s"), "{why}");
    /// ```
    pub fn counted_factorisations_fit(
        &self,
        values: usize,
        multiply_adds: f64,
        total_values: usize,
    ) -> std::result::Result<(), String> {
        self.fits_with(
            values,
            Self::predicted_factor_seconds(multiply_adds, total_values),
            "counted multiply-adds at 3e10 per second plus 1e-8 s per value; 1.2x to 1.6x the \
             measured times",
        )
    }

    fn fits_with(
        &self,
        values: usize,
        seconds: f64,
        model: &str,
    ) -> std::result::Result<(), String> {
        let bytes = Self::factorisation_bytes(values);
        if bytes > self.max_memory_bytes as f64 {
            return Err(format!(
                "the proof would need a factor of {values:.1e} values ({}); memory budget {}",
                human_bytes(bytes),
                human_bytes(self.max_memory_bytes as f64)
            ));
        }
        match self.max_seconds {
            Some(limit) if seconds.is_nan() || seconds > limit => Err(format!(
                "the proof would need a factorisation of {values:.1e} values, predicted at \
                 {seconds:.0} s by the time model ({model}); time budget {limit} s"
            )),
            _ => Ok(()),
        }
    }
}

/// `bytes` in the largest binary unit that keeps the number at least 1 (`1.5 KiB`, `4.0 GiB`).
pub(crate) fn human_bytes(bytes: f64) -> String {
    let units = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut value = bytes;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < units.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{value:.0} bytes")
    } else {
        format!("{value:.1} {}", units[unit])
    }
}

// The one clock of a certification is the crate's one clock ([`crate::deadline`]): started
// once, when the certification starts, and read by every rung and every check inside one (so a
// verification after an SDP solve gets what is left, never a fresh budget).
pub use crate::deadline::Deadline;

impl Deadline {
    /// A clock started now, ending `budget.max_seconds` from now (never, without a limit).
    pub fn start(budget: &Budget) -> Self {
        Deadline::started_at(std::time::Instant::now(), budget.max_seconds)
    }

    /// `Err(reason)` when `predicted` does not fit the memory budget or the time left.
    pub fn fits(&self, budget: &Budget, predicted: &Prediction) -> std::result::Result<(), String> {
        budget.prediction_fits(predicted, self.elapsed())
    }
}
