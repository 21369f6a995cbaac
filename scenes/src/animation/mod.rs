//! Animated scenes: the light, the camera, rigid motions of objects and the shadow-map
//! resolution, each a track of keys over time, sampled at a number of frames. Shadow aliasing
//! shows most in motion, as flicker and crawling edges from frame to frame (Lecocq et al.,
//! "Sub-Pixel Shadow Mapping", I3D 2014, sections 2 and 6; Pan et al., "Fast, Sub-pixel
//! Antialiased Shadow Maps", CGF 28(7), Pacific Graphics 2009, section 1); an animated scene
//! lets that be measured.
//!
//! ```toml
//! [animation]
//! frames = 24                     # samples over the time span of the keys (1..=1000); default 1
//!
//! [[animation.light]]             # keys of the scene's light, of the same kind as [light]
//! time = 0.0
//! direction = [-0.5, -1.0, -0.4]  # directional: direction; spot: position, target, fov_deg
//!
//! [[animation.camera]]            # eye, target, up, and fov_y_deg (perspective) or height
//! time = 0.0                      # (orthographic); a key leaving a field out keeps the scene
//! eye = [0, 5, 8]                 # camera's value
//! target = [0, 1.5, 0]
//!
//! [[animation.object]]            # a rigid motion of the object named so in [[object]]
//! name = "square"
//!   [[animation.object.key]]
//!   time = 0.0
//!   translate = [0, 0, 0]         # added after the object's own transform (default zero)
//!   rotate_deg = [0, 0, 0]        # about x, then y, then z, as [object.transform] rotate_deg,
//!                                 # about the centre of the object's bounding box at rest
//!
//! [[animation.map_scale]]         # shadow-map resolution factor
//! time = 0.0
//! value = 0.5
//! ```
//!
//! Semantics:
//!
//! - Frames are spread evenly over the time span of all keys of all tracks: frame 0 at the
//!   first key's time, the last frame at the last key's, both exactly ([`Animation::time`]);
//!   one frame is at the first key's time. `frames` defaults to 1 and may not exceed
//!   [`MAX_FRAMES`]; [`Animation::with_frames`] samples the same span at another count.
//! - Each track is piecewise between consecutive keys, holds its first value before its first
//!   key and its last after its last; at a key's time it is the key's value, bit for bit (the
//!   key itself, not a blend). Points, fields of view, heights, translations and map scales are
//!   interpolated linearly; directions (a directional light's, a camera's up hint) by
//!   spherical linear interpolation of unit vectors, at a constant angular rate along the
//!   great circle; rotations as unit quaternions (from the Euler angles) by slerp, the shorter
//!   way round, so a turn of more than half a revolution needs keys in between.
//! - A field a light or camera key leaves out keeps the scene's value; a key's `near` is the
//!   scene camera's. The scene's directional light and each key's direction are unit vectors
//!   once resolved.
//! - An object moves rigidly: at each time, its rest mesh (after its own transform) is
//!   rotated about the centre of its rest bounding box, then translated. Triangles keep their
//!   order and indices, so triangle ids are the same in every frame. One track per object;
//!   objects are named as the scene names them (`name`, or the shape's kind and index,
//!   `plane0`).
//! - `map_scale` multiplies the run's shadow-map resolution, piecewise linearly (Lecocq et
//!   al. 2014, section 6: the resolution varied at run time); the runner rounds the product to
//!   whole texels. Without the track the factor is 1.
//!
//! Bad input is refused, naming the file, the line and the key as written: a track's times
//! not finite or not strictly increasing (`animation.light[2].time`), a zero or non-finite
//! direction, `frames` 0 or beyond [`MAX_FRAMES`] (`animation.frames`), a light or camera
//! key of another kind than the scene's, a light or camera key making an invalid light or
//! camera ([`crate::Light::validate`], [`crate::Camera::validate`]), consecutive directions
//! or up hints opposite to each other, or consecutive views (target - eye, target - position)
//! opposite, within [`OPPOSITE_TOLERANCE`] (1e-6) radians (no unique path between them;
//! between the keys, the eye would meet the target), an object name that names no object or
//! several, a second track for one object, a track without keys, a non-finite translation or
//! rotation, a map scale not positive and finite, and a motion that could put geometry, a
//! camera or a spot light beyond [`crate::limits`] at any time, not only at the frames
//! sampled (see [`Animation::resolve`]).

mod desc;
mod error;
mod interpolate;
mod pose;
mod resolve;
mod timeline;

pub use desc::{AnimationDesc, CameraKey, LightKey, ObjectKey, ObjectTrack, ScaleKey};
pub use error::AnimationError;
pub use interpolate::OPPOSITE_TOLERANCE;
pub use timeline::{Animation, MAX_FRAMES};
