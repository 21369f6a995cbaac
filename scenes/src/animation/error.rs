//! Why an animation cannot be built or sampled: [`AnimationError`], which names the scene
//! file's key (`animation.light[2].time`) or the frame count and its limit.

/// Why an animation cannot be built from a scene file or sampled at a frame count.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnimationError {
    /// A frame count outside `1..=limit`.
    #[error("cannot sample an animation at {frames} frames: the count must be in 1..={limit}")]
    Frames {
        /// The count asked for.
        frames: u32,
        /// The most frames an animation may be sampled at ([`super::MAX_FRAMES`]).
        limit: u32,
    },
    /// A key of `[animation]` is bad input.
    #[error("`{key}`: {message}")]
    Invalid {
        /// The key as written, e.g. `animation.light[2].time`.
        key: String,
        /// What is wrong.
        message: String,
    },
    /// A pose would put the camera, the light or geometry beyond [`crate::limits`].
    #[error("`{key}`: {message}")]
    OutOfRange {
        /// The key as written, e.g. `animation.object[0].key[1].translate`.
        key: String,
        /// What is out of range, with the value and the supported range.
        message: String,
    },
}
