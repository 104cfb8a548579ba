//! [`Side`]: which region a closed surface bounds — the solid inside it, or the space
//! around it out to a bounding sphere. Every stage that treats the two differently
//! (the volume mesher, the loop stage, the analytic shapes, the report) names them with
//! this one type. A loop found inside goes around a narrow part of the solid: a
//! *handle*; one found outside goes around a narrow part of the space: a *tunnel*.
//!
//! Serialized as `"inside"` / `"outside"`; fields that name a loop's kind serialize it
//! as `"handle"` / `"tunnel"` through [`Side::serialize_as_neck`] (read back by
//! [`Side::deserialize_from_neck`]).

use std::fmt;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The solid bounded by the surface, or the shell between it and a bounding sphere.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    /// The solid bounded by the surface: its necks are handles.
    Inside,
    /// The shell between the surface and a bounding sphere: its necks are tunnels.
    Outside,
}

impl Side {
    /// Both sides, inside first (the order of every per-side list).
    pub const BOTH: [Side; 2] = [Side::Inside, Side::Outside];

    /// `"inside"` or `"outside"`.
    pub fn name(self) -> &'static str {
        match self {
            Side::Inside => "inside",
            Side::Outside => "outside",
        }
    }

    /// The name of a neck loop found on this side: `"handle"` or `"tunnel"`.
    pub fn neck_name(self) -> &'static str {
        match self {
            Side::Inside => "handle",
            Side::Outside => "tunnel",
        }
    }

    /// The side whose neck loops are called `name` (`"handle"` or `"tunnel"`).
    pub fn from_neck_name(name: &str) -> Option<Side> {
        Side::BOTH.into_iter().find(|s| s.neck_name() == name)
    }

    /// For `#[serde(serialize_with = ..)]` on a loop's kind: `"handle"` or `"tunnel"`.
    pub fn serialize_as_neck<S: Serializer>(side: &Side, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(side.neck_name())
    }

    /// For `#[serde(deserialize_with = ..)]`: the inverse of [`Side::serialize_as_neck`].
    pub fn deserialize_from_neck<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Side, D::Error> {
        let name = String::deserialize(deserializer)?;
        Side::from_neck_name(&name).ok_or_else(|| {
            serde::de::Error::custom(format!("'{name}' is not a loop kind (handle or tunnel)"))
        })
    }
}

impl fmt::Display for Side {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}
