//! The JSON file of a single-averaging problem (contract section 5):
//!
//! ```text
//! {"rotations": [R, ...], "weights": [w, ...]}
//! ```
//!
//! Each `R` is a rotation as a row-major nested array `[[r11, r12, r13], [r21, ..], [r31, ..]]`
//! (the samples `R_i` themselves: no transposition). `weights` is optional (default: all 1);
//! when present it has one weight per rotation, within
//! [`[MIN_WEIGHT, MAX_WEIGHT]`](crate::io::MAX_WEIGHT). Unknown keys are rejected (a typo
//! such as `"weight"` would otherwise silently mean unit weights). Every rotation is validated
//! with [`crate::so3::rotation_from_rows`] at [`DEFAULT_ROTATION_TOLERANCE`] (item name
//! `"rotation k"`, 0-based). Errors name the file and the line where the offending value ends.
//!
//! An estimate file is `{"rotation": R}` (or `{"estimate": R, ...}` as printed by
//! `rotavg single --json`), read by [`parse_single_estimate`].

use crate::error::{Error, Result};
use crate::single::SingleProblem;
use crate::so3::{DEFAULT_ROTATION_TOLERANCE, Rotation, rotation_from_rows, rotation_to_rows};
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

/// Largest capacity reserved up front from a size hint (no unbounded allocation from input).
const MAX_PREALLOCATION: usize = 1 << 16;

/// Rotation `k` of the list, validated inside its own `deserialize_seq` call so that
/// `serde_json` reports the position where that rotation ends (not where the list ends).
struct RotationSeed(usize);

impl<'de> de::DeserializeSeed<'de> for RotationSeed {
    type Value = Rotation;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Rotation, D::Error> {
        struct V(usize);
        impl<'de> Visitor<'de> for V {
            type Value = Rotation;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a 3x3 rotation as a row-major nested array [[r11, r12, r13], ...]")
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<Rotation, A::Error> {
                let mut rows = [[0.0; 3]; 3];
                for (i, row) in rows.iter_mut().enumerate() {
                    *row = seq
                        .next_element::<[f64; 3]>()?
                        .ok_or_else(|| de::Error::invalid_length(i, &self))?;
                }
                if seq.next_element::<de::IgnoredAny>()?.is_some() {
                    return Err(de::Error::invalid_length(4, &self));
                }
                let item = format!("rotation {}", self.0);
                rotation_from_rows(&rows, DEFAULT_ROTATION_TOLERANCE, &item)
                    .map_err(de::Error::custom)
            }
        }
        d.deserialize_seq(V(self.0))
    }
}

struct Rotations(Vec<Rotation>);

impl<'de> Deserialize<'de> for Rotations {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Rotations;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a list of 3x3 rotations, each a row-major nested array")
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<Rotations, A::Error> {
                let mut out =
                    Vec::with_capacity(seq.size_hint().unwrap_or(0).min(MAX_PREALLOCATION));
                while let Some(r) = seq.next_element_seed(RotationSeed(out.len()))? {
                    out.push(r);
                }
                Ok(Rotations(out))
            }
        }
        d.deserialize_seq(V)
    }
}

/// Weight `k`, validated inside its own `deserialize_f64` call (position of the number).
struct WeightSeed(usize);

impl<'de> de::DeserializeSeed<'de> for WeightSeed {
    type Value = f64;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<f64, D::Error> {
        struct V(usize);
        impl V {
            fn check<E: de::Error>(&self, w: f64) -> std::result::Result<f64, E> {
                if !(w.is_finite() && w > 0.0) {
                    Err(E::custom(Error::InvalidWeight {
                        item: format!("weight {}", self.0),
                        weight: w,
                    }))
                } else if let Some(why) = crate::io::weight_out_of_range(w) {
                    Err(E::custom(format!("weight {}: {why}", self.0)))
                } else {
                    Ok(w)
                }
            }
        }
        impl<'de> Visitor<'de> for V {
            type Value = f64;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a weight (a finite number > 0)")
            }
            fn visit_f64<E: de::Error>(self, w: f64) -> std::result::Result<f64, E> {
                self.check(w)
            }
            fn visit_u64<E: de::Error>(self, w: u64) -> std::result::Result<f64, E> {
                self.check(w as f64)
            }
            fn visit_i64<E: de::Error>(self, w: i64) -> std::result::Result<f64, E> {
                self.check(w as f64)
            }
        }
        d.deserialize_f64(V(self.0))
    }
}

struct Weights(Vec<f64>);

impl<'de> Deserialize<'de> for Weights {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Weights;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a list of weights (finite numbers > 0)")
            }
            fn visit_seq<A: SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<Weights, A::Error> {
                let mut out =
                    Vec::with_capacity(seq.size_hint().unwrap_or(0).min(MAX_PREALLOCATION));
                while let Some(w) = seq.next_element_seed(WeightSeed(out.len()))? {
                    out.push(w);
                }
                Ok(Weights(out))
            }
        }
        d.deserialize_seq(V)
    }
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a JSON object {\"rotations\": [R, ...], \"weights\": [w, ...]} (weights optional)"
)]
struct RawSingle {
    rotations: Rotations,
    #[serde(default)]
    weights: Option<Weights>,
}

/// The file layout, for writing.
#[derive(Serialize)]
struct RawSingleOut<'a> {
    rotations: Vec<[[f64; 3]; 3]>,
    weights: &'a [f64],
}

/// A `serde_json` error as our [`Error::Parse`] at `file:line` (column in the message).
pub(crate) fn json_error(file: &str, e: &serde_json::Error) -> Error {
    let text = e.to_string();
    let message = match text.rfind(" at line ") {
        Some(i) => format!("{} (column {})", &text[..i], e.column()),
        None => text,
    };
    let line = (e.line() > 0).then_some(e.line());
    Error::parse(Some(file), line, message)
}

/// Parse a single-averaging problem from JSON `text`; `file` names the source in errors.
///
/// ```
/// use rotavg::io::single_json::parse_single_json;
/// let text = r#"{"rotations": [[[1,0,0],[0,1,0],[0,0,1]], [[1,0,0],[0,0,-1],[0,1,0]]],
///               "weights": [1, 2]}"#;
/// let p = parse_single_json(text, "example.json")?;
/// assert_eq!(p.len(), 2);
/// assert_eq!(p.weights(), &[1.0, 2.0]);
/// let bad = parse_single_json("{\"rotations\": [[[2,0,0],[0,1,0],[0,0,1]]]}", "bad.json");
/// assert!(bad.unwrap_err().to_string().starts_with("bad.json:1: rotation 0 is not a rotation"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn parse_single_json(text: &str, file: &str) -> Result<SingleProblem> {
    let raw: RawSingle = serde_json::from_str(text).map_err(|e| {
        crate::io::detect::read_by_another_verb(file, text, "single")
            .unwrap_or_else(|| json_error(file, &e))
    })?;
    let weights = raw.weights.map(|w| w.0);
    SingleProblem::new(raw.rotations.0, weights).map_err(|e| {
        // Remaining errors are about the whole lists (empty, length mismatch): point at the key.
        let key = if matches!(e, Error::Empty { .. }) {
            "\"rotations\""
        } else {
            "\"weights\""
        };
        let line = text.lines().position(|l| l.contains(key)).map(|i| i + 1);
        e.in_file(file, line)
    })
}

/// Read a single-averaging problem from a JSON file (see the module docs).
pub fn read_single_json(path: &Path) -> Result<SingleProblem> {
    let name = path.display().to_string();
    let text = super::text::read_text(&name)?;
    parse_single_json(&text, &name)
}

/// The JSON text of a problem in the layout read by [`parse_single_json`].
///
/// ```
/// use rotavg::io::single_json::{parse_single_json, to_single_json};
/// use rotavg::single::SingleProblem;
/// let p = SingleProblem::new(vec![rotavg::so3::exp(&nalgebra::Vector3::new(0.0, 0.0, 0.3))], Some(vec![2.5]))?;
/// let again = parse_single_json(&to_single_json(&p), "p.json")?;
/// assert_eq!(again.weights(), &[2.5]);
/// assert!(rotavg::so3::angle_between(&again.rotations()[0], &p.rotations()[0]) < 1e-15);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn to_single_json(problem: &SingleProblem) -> String {
    let out = RawSingleOut {
        rotations: problem.rotations().iter().map(rotation_to_rows).collect(),
        weights: problem.weights(),
    };
    serde_json::to_string(&out).unwrap_or_default()
}

#[derive(Deserialize)]
#[serde(
    expecting = "a JSON object {\"rotation\": R} (or {\"estimate\": R}, as `--json` prints it)"
)]
struct RawEstimate {
    #[serde(default)]
    rotation: Option<[[f64; 3]; 3]>,
    #[serde(default)]
    estimate: Option<[[f64; 3]; 3]>,
}

/// Parse an estimate file `{"rotation": R}` (or `{"estimate": R, ...}`, the `--json` output of
/// `rotavg single`), validating the rotation.
///
/// ```
/// use rotavg::io::single_json::parse_single_estimate;
/// let r = parse_single_estimate(r#"{"rotation": [[1,0,0],[0,1,0],[0,0,1]]}"#, "e.json")?;
/// assert_eq!(r, rotavg::Rotation::identity());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn parse_single_estimate(text: &str, file: &str) -> Result<Rotation> {
    let raw: RawEstimate = serde_json::from_str(text).map_err(|e| json_error(file, &e))?;
    let rows = raw.rotation.or(raw.estimate).ok_or_else(|| {
        Error::parse(
            Some(file),
            None,
            "expected a key \"rotation\" (or \"estimate\") holding a 3x3 row-major rotation",
        )
    })?;
    rotation_from_rows(&rows, DEFAULT_ROTATION_TOLERANCE, "the estimate")
        .map_err(|e| e.in_file(file, None))
}
