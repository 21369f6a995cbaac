//! [`Animation`], the resolved animation a [`crate::Scene`] carries: the frame count and the
//! checked tracks, the times of the frames and the shadow-map resolution factor at each.
//! Posing a scene at a frame is [`Animation::pose`]'s; building one from a scene file,
//! [`Animation::resolve`]'s.

use super::error::AnimationError;
use super::interpolate::{sample, Key, Rigid};
use crate::camera::Camera;
use crate::light::Light;

/// Most frames an animation may be sampled at (documented limit; beyond it: bad input).
pub const MAX_FRAMES: u32 = 1000;

/// How a scene moves: tracks of keys over time, sampled at `frames` evenly spaced times.
/// The default is still: one frame, no track.
#[derive(Debug, Clone, PartialEq)]
pub struct Animation {
    /// Frames sampled, 1 to [`MAX_FRAMES`].
    pub(super) frames: u32,
    /// The light at each key, whole (fields a key leaves out taken from the scene's light),
    /// a directional light's direction unit.
    pub(super) light: Vec<Key<Light>>,
    /// The camera at each key, whole.
    pub(super) camera: Vec<Key<Camera>>,
    /// Rigid motions of objects, one per moving object.
    pub(super) objects: Vec<Motion>,
    /// The shadow-map resolution factor at each key.
    pub(super) map_scale: Vec<Key<f64>>,
}

/// The rigid motion of one object.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Motion {
    /// Index of the object in [`crate::Scene::objects`].
    pub(super) object: usize,
    /// The motion at each key, about the centre of the object's bounding box at rest.
    pub(super) keys: Vec<Key<Rigid>>,
}

impl Default for Animation {
    fn default() -> Self {
        Self::still()
    }
}

impl Animation {
    /// One frame, no track.
    pub fn still() -> Self {
        Self {
            frames: 1,
            light: Vec::new(),
            camera: Vec::new(),
            objects: Vec::new(),
            map_scale: Vec::new(),
        }
    }

    /// The frame count of the scene file (at least 1).
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The same animation sampled at `n` frames over the same time span; `n` outside
    /// `1..=MAX_FRAMES` is refused, naming the count and the limit.
    pub fn with_frames(&self, n: u32) -> Result<Self, AnimationError> {
        if !(1..=MAX_FRAMES).contains(&n) {
            return Err(AnimationError::Frames { frames: n, limit: MAX_FRAMES });
        }
        Ok(Self { frames: n, ..self.clone() })
    }

    /// Whether the animation has no track at all (every frame is the rest scene).
    pub fn is_still(&self) -> bool {
        self.light.is_empty()
            && self.camera.is_empty()
            && self.objects.is_empty()
            && self.map_scale.is_empty()
    }

    /// The first and last key times over all tracks; `None` without a track.
    fn span(&self) -> Option<(f64, f64)> {
        let tracks = [times(&self.light), times(&self.camera), times(&self.map_scale)]
            .into_iter()
            .chain(self.objects.iter().map(|m| times(&m.keys)));
        tracks.flatten().reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// The time of frame `i`: frames spread evenly from the first key's time (frame 0) to
    /// the last key's (the last frame), over all tracks, both ends exactly; one frame is at
    /// the first key's time. A frame beyond the last is the last; without a track, 0.
    pub fn time(&self, i: u32) -> f64 {
        let Some((first, last)) = self.span() else { return 0.0 };
        let end = self.frames.saturating_sub(1);
        let i = i.min(end);
        if i == 0 {
            return first;
        }
        if i == end {
            return last;
        }
        let s = f64::from(i) / f64::from(end);
        first * (1.0 - s) + last * s
    }

    /// Whether the camera moves: a camera track with keys that differ.
    pub fn moves_camera(&self) -> bool {
        self.camera.windows(2).any(|w| w[0].value != w[1].value)
    }

    /// The shadow-map resolution factor at frame `i`, piecewise linear between its keys
    /// (Lecocq et al. 2014, section 6: the map's resolution varied at run time); 1 without a
    /// `map_scale` track. The run's map resolution is multiplied by it; rounding the product
    /// to whole texels is the runner's.
    pub fn map_scale(&self, i: u32) -> f64 {
        sample(&self.map_scale, self.time(i)).unwrap_or(1.0)
    }

    /// The light at frame `i`, `None` without a light track.
    pub(super) fn light_at(&self, i: u32) -> Option<Light> {
        sample(&self.light, self.time(i))
    }

    /// The camera at frame `i`, `None` without a camera track.
    pub(super) fn camera_at(&self, i: u32) -> Option<Camera> {
        sample(&self.camera, self.time(i))
    }
}

/// The first and last times of a track, `None` when it is empty.
fn times<T>(keys: &[Key<T>]) -> Option<(f64, f64)> {
    Some((keys.first()?.time, keys.last()?.time))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scale_track(times: &[f64]) -> Animation {
        let map_scale = times.iter().map(|&time| Key { time, value: 1.0 }).collect();
        Animation { frames: 5, map_scale, ..Animation::still() }
    }

    #[test]
    fn still_is_the_default_with_one_frame_at_time_zero() {
        let still = Animation::still();
        assert_eq!(still, Animation::default());
        assert!(still.is_still() && !still.moves_camera());
        assert_eq!(
            (still.frames(), still.time(0), still.time(7), still.map_scale(3)),
            (1, 0.0, 0.0, 1.0)
        );
    }

    #[test]
    fn frame_times_span_the_keys_evenly() {
        let a = scale_track(&[0.1, 0.25, 0.3]);
        let times: Vec<f64> = (0..5).map(|i| a.time(i)).collect();
        assert_eq!(times[0].to_bits(), 0.1f64.to_bits());
        assert_eq!(times[4].to_bits(), 0.3f64.to_bits());
        for (i, t) in times.iter().enumerate() {
            let want = 0.1 + 0.2 * i as f64 / 4.0;
            assert!((t - want).abs() < 1e-16, "frame {i}: {t} vs {want}");
        }
        assert_eq!(a.time(99), a.time(4));
        let one = a.with_frames(1).expect("one frame");
        assert_eq!(one.time(0), 0.1);
        // The span is over every track.
        let mut b = scale_track(&[2.0, 3.0]);
        b.light =
            vec![Key { time: -1.0, value: Light::Directional { direction: -glam::DVec3::Y } }];
        assert_eq!((b.time(0), b.time(4)), (-1.0, 3.0));
    }

    #[test]
    fn the_camera_moves_when_its_keys_differ() {
        let camera = |x: f64| Camera::Orthographic {
            eye: glam::DVec3::new(x, 5.0, 1.0),
            target: glam::DVec3::ZERO,
            up: glam::DVec3::Y,
            height: 4.0,
        };
        let keys = |xs: &[f64]| -> Vec<Key<Camera>> {
            xs.iter().enumerate().map(|(k, &x)| Key { time: k as f64, value: camera(x) }).collect()
        };
        for (xs, moves) in
            [(&[][..], false), (&[1.0], false), (&[1.0, 1.0], false), (&[1.0, 1.0, 2.0], true)]
        {
            let a = Animation { frames: 3, camera: keys(xs), ..Animation::still() };
            assert_eq!(a.moves_camera(), moves, "{xs:?}");
            assert_eq!(a.is_still(), xs.is_empty(), "{xs:?}");
        }
    }

    #[test]
    fn with_frames_refuses_zero_and_beyond_the_limit() {
        let a = scale_track(&[0.0, 1.0]);
        for n in [0, MAX_FRAMES + 1, u32::MAX] {
            let err = a.with_frames(n).expect_err("refused");
            assert_eq!(err, AnimationError::Frames { frames: n, limit: MAX_FRAMES });
            let message = err.to_string();
            assert!(message.contains(&n.to_string()) && message.contains("1..=1000"), "{message}");
        }
        for n in [1, 2, MAX_FRAMES] {
            let b = a.with_frames(n).expect("within the limit");
            let last = if n == 1 { 0.0 } else { 1.0 };
            assert_eq!((b.frames(), b.time(0), b.time(n - 1)), (n, 0.0, last));
        }
    }
}
