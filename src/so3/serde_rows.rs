//! Serde helpers: rotations as row-major nested arrays `[[r11, r12, r13], [..], [..]]`, the JSON
//! layout of contract section 5. Use with `#[serde(with = "rotavg::so3::serde_rows::rotation")]` or
//! `#[serde(with = "rotavg::so3::serde_rows::rotations")]`. Deserialisation validates the rotation with
//! [`crate::so3::DEFAULT_ROTATION_TOLERANCE`].
//!
//! ```
//! use rotavg::Rotation;
//! #[derive(serde::Serialize, serde::Deserialize)]
//! struct Pose {
//!     #[serde(with = "rotavg::so3::serde_rows::rotation")]
//!     rotation: Rotation,
//! }
//! let json = serde_json::to_string(&Pose { rotation: Rotation::identity() }).unwrap();
//! assert_eq!(json, r#"{"rotation":[[1.0,0.0,0.0],[0.0,1.0,0.0],[0.0,0.0,1.0]]}"#);
//! // Reading validates: a reflection is refused.
//! let bad = r#"{"rotation":[[1,0,0],[0,1,0],[0,0,-1]]}"#;
//! assert!(serde_json::from_str::<Pose>(bad).is_err());
//! ```

/// One rotation as a row-major nested array.
pub mod rotation {
    use crate::so3::{DEFAULT_ROTATION_TOLERANCE, Rotation, rotation_from_rows, rotation_to_rows};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Serialise.
    pub fn serialize<S: Serializer>(r: &Rotation, s: S) -> Result<S::Ok, S::Error> {
        rotation_to_rows(r).serialize(s)
    }

    /// Deserialise and validate.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Rotation, D::Error> {
        let rows = <[[f64; 3]; 3]>::deserialize(d)?;
        rotation_from_rows(&rows, DEFAULT_ROTATION_TOLERANCE, "rotation")
            .map_err(serde::de::Error::custom)
    }
}

/// A list of rotations, each a row-major nested array.
pub mod rotations {
    use crate::so3::{DEFAULT_ROTATION_TOLERANCE, Rotation, rotation_from_rows, rotation_to_rows};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Serialise.
    pub fn serialize<S: Serializer>(rs: &[Rotation], s: S) -> Result<S::Ok, S::Error> {
        rs.iter()
            .map(rotation_to_rows)
            .collect::<Vec<_>>()
            .serialize(s)
    }

    /// Deserialise and validate.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<Rotation>, D::Error> {
        let rows = Vec::<[[f64; 3]; 3]>::deserialize(d)?;
        rows.iter()
            .enumerate()
            .map(|(k, r)| {
                rotation_from_rows(r, DEFAULT_ROTATION_TOLERANCE, &format!("rotation {k}"))
                    .map_err(serde::de::Error::custom)
            })
            .collect()
    }
}

/// An optional list of rotations (`null` or a list of row-major nested arrays).
pub mod option_rotations {
    use crate::so3::Rotation;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Serialise.
    pub fn serialize<S: Serializer>(rs: &Option<Vec<Rotation>>, s: S) -> Result<S::Ok, S::Error> {
        let rows: Option<Vec<[[f64; 3]; 3]>> = rs
            .as_ref()
            .map(|rs| rs.iter().map(crate::so3::rotation_to_rows).collect());
        rows.serialize(s)
    }

    /// Deserialise and validate.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<Rotation>>, D::Error> {
        #[derive(Deserialize)]
        struct Rows(#[serde(with = "super::rotations")] Vec<Rotation>);
        Ok(Option::<Rows>::deserialize(d)?.map(|r| r.0))
    }
}

/// An optional rotation (`null` or a row-major nested array).
pub mod optional_rotation {
    use crate::so3::{DEFAULT_ROTATION_TOLERANCE, Rotation, rotation_from_rows, rotation_to_rows};
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// Serialise.
    pub fn serialize<S: Serializer>(r: &Option<Rotation>, s: S) -> Result<S::Ok, S::Error> {
        r.as_ref().map(rotation_to_rows).serialize(s)
    }

    /// Deserialise and validate.
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Rotation>, D::Error> {
        Option::<[[f64; 3]; 3]>::deserialize(d)?
            .map(|rows| {
                rotation_from_rows(&rows, DEFAULT_ROTATION_TOLERANCE, "rotation")
                    .map_err(serde::de::Error::custom)
            })
            .transpose()
    }
}
