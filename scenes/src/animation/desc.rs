//! The `[animation]` table of a scene file as written: the frame count and the keys of each
//! track, before they are checked and resolved against the scene ([`super::Animation::resolve`]).
//! Every table refuses unknown keys, and every vector takes exactly three values
//! ([`crate::arrays`]), so that a parse error names the line and the key.

use glam::DVec3;
use serde::{Deserialize, Serialize};

fn one() -> u32 {
    1
}

fn is_zero(v: &DVec3) -> bool {
    *v == DVec3::ZERO
}

/// `[animation]`: how many frames to sample, and the tracks. Default: one frame, no track (a
/// still scene).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AnimationDesc {
    /// Frames sampled evenly over the time span of all keys, 1 to [`super::MAX_FRAMES`]
    /// (default 1).
    #[serde(default = "one")]
    pub frames: u32,
    /// Keys of the scene's light (`[[animation.light]]`), of the light's kind.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub light: Vec<LightKey>,
    /// Keys of the camera (`[[animation.camera]]`), of the camera's kind.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub camera: Vec<CameraKey>,
    /// Rigid motions of objects (`[[animation.object]]`), one track per object.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub object: Vec<ObjectTrack>,
    /// Keys of the shadow-map resolution factor (`[[animation.map_scale]]`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub map_scale: Vec<ScaleKey>,
}

impl Default for AnimationDesc {
    fn default() -> Self {
        Self {
            frames: 1,
            light: Vec::new(),
            camera: Vec::new(),
            object: Vec::new(),
            map_scale: Vec::new(),
        }
    }
}

/// A key of the light: `direction` for a directional light, `position`, `target` and
/// `fov_deg` for a spot light. A field left out keeps the scene light's value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightKey {
    /// Time of the key (any finite value; the keys of a track strictly increase).
    pub time: f64,
    /// Direction the light travels (directional light; any finite non-zero magnitude).
    #[serde(
        default,
        deserialize_with = "crate::arrays::option_dvec3",
        skip_serializing_if = "Option::is_none"
    )]
    pub direction: Option<DVec3>,
    /// Position (spot light).
    #[serde(
        default,
        deserialize_with = "crate::arrays::option_dvec3",
        skip_serializing_if = "Option::is_none"
    )]
    pub position: Option<DVec3>,
    /// Point aimed at (spot light).
    #[serde(
        default,
        deserialize_with = "crate::arrays::option_dvec3",
        skip_serializing_if = "Option::is_none"
    )]
    pub target: Option<DVec3>,
    /// Full opening angle in degrees, in (0, 170] (spot light).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov_deg: Option<f64>,
}

/// A key of the camera: `eye`, `target`, `up`, and `fov_y_deg` (perspective) or `height`
/// (orthographic). A field left out keeps the scene camera's value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraKey {
    /// Time of the key.
    pub time: f64,
    /// Eye position.
    #[serde(
        default,
        deserialize_with = "crate::arrays::option_dvec3",
        skip_serializing_if = "Option::is_none"
    )]
    pub eye: Option<DVec3>,
    /// Point looked at.
    #[serde(
        default,
        deserialize_with = "crate::arrays::option_dvec3",
        skip_serializing_if = "Option::is_none"
    )]
    pub target: Option<DVec3>,
    /// Up hint.
    #[serde(
        default,
        deserialize_with = "crate::arrays::option_dvec3",
        skip_serializing_if = "Option::is_none"
    )]
    pub up: Option<DVec3>,
    /// Vertical field of view in degrees (perspective camera).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fov_y_deg: Option<f64>,
    /// Height of the view volume (orthographic camera).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
}

/// The rigid motion of one object (`[[animation.object]]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectTrack {
    /// The object's name, as its `[[object]]` `name` (or the default name, the shape's kind
    /// and index: `plane0`).
    pub name: String,
    /// The keys (`[[animation.object.key]]`), at least one.
    #[serde(rename = "key")]
    pub keys: Vec<ObjectKey>,
}

/// A key of an object's rigid motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectKey {
    /// Time of the key.
    pub time: f64,
    /// Translation added after the object's own transform (default zero).
    #[serde(default, deserialize_with = "crate::arrays::dvec3", skip_serializing_if = "is_zero")]
    pub translate: DVec3,
    /// Rotation in degrees about x, then y, then z, as `[object.transform] rotate_deg`, about
    /// the centre of the object's bounding box at rest (default zero).
    #[serde(default, deserialize_with = "crate::arrays::dvec3", skip_serializing_if = "is_zero")]
    pub rotate_deg: DVec3,
}

/// A key of the shadow-map resolution factor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScaleKey {
    /// Time of the key.
    pub time: f64,
    /// The factor the run's map resolution is multiplied by: positive and finite.
    pub value: f64,
}
