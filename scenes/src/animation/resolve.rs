//! A scene file's `[animation]` checked and resolved against its rest scene
//! ([`Animation::resolve`]): every key made whole (fields a key leaves out taken from the scene),
//! object names turned into indices, and every bad input refused with the key as written.
//!
//! The checks hold for every time, not only the sampled frames, so that an animation
//! resampled at any count ([`Animation::with_frames`]) stays valid: a camera's or spot's
//! position and target are interpolated linearly, so they stay within the range of their
//! keys and meet between two keys only when the two views point in opposite directions; a
//! rigid motion keeps an object within the sphere about its centre that holds it, moved by
//! the translations of the keys.

use super::desc::{AnimationDesc, CameraKey, LightKey, ObjectTrack, ScaleKey};
use super::error::AnimationError;
use super::interpolate::{opposite, Key, Rigid, OPPOSITE_TOLERANCE};
use super::timeline::{Animation, Motion, MAX_FRAMES};
use crate::camera::Camera;
use crate::light::Light;
use crate::limits::{apart, beyond_range, MIN_EXTENT};
use crate::projection::direction_between;
use crate::scene::Scene;
use glam::{DQuat, DVec3};

/// Bad input at `key`.
fn invalid(key: impl Into<String>, message: impl Into<String>) -> AnimationError {
    AnimationError::Invalid { key: key.into(), message: message.into() }
}

/// A pose beyond the supported range at `key`.
fn out_of_range(key: impl Into<String>, message: impl Into<String>) -> AnimationError {
    AnimationError::OutOfRange { key: key.into(), message: message.into() }
}

impl Animation {
    /// The animation `desc` of the scene `rest` (resolved, still), checked: the frame count
    /// in `1..=MAX_FRAMES`; each track's times finite and strictly increasing; light and
    /// camera keys of the scene's kinds, each a valid light or camera
    /// ([`Light::validate`], [`Camera::validate`]) within the coordinate range, consecutive
    /// directions, up hints and views not opposite (within [`OPPOSITE_TOLERANCE`] radians);
    /// each object track naming one object of `rest` that no other track names, with at least
    /// one key, finite translations and rotations, and no pose beyond the coordinate range;
    /// map scales positive and finite. Errors name the key as written
    /// (`animation.light[2].time`).
    pub fn resolve(desc: &AnimationDesc, rest: &Scene) -> Result<Self, AnimationError> {
        if !(1..=MAX_FRAMES).contains(&desc.frames) {
            return Err(invalid(
                "animation.frames",
                format!("must be in 1..={MAX_FRAMES}, got {}", desc.frames),
            ));
        }
        let light = light_track(&desc.light, &rest.light)?;
        let camera = camera_track(&desc.camera, &rest.camera)?;
        let mut objects: Vec<Motion> = Vec::with_capacity(desc.object.len());
        for (j, track) in desc.object.iter().enumerate() {
            let motion = motion(j, track, rest, &objects)?;
            objects.push(motion);
        }
        check_extent(&objects, rest)?;
        let map_scale = scale_track(&desc.map_scale)?;
        Ok(Animation { frames: desc.frames, light, camera, objects, map_scale })
    }
}

/// Checks the times of the track `track` (`animation.light`): finite, strictly increasing.
fn check_times(track: &str, times: impl Iterator<Item = f64>) -> Result<(), AnimationError> {
    let mut previous: Option<f64> = None;
    for (k, time) in times.enumerate() {
        let key = || format!("{track}[{k}].time");
        if !time.is_finite() {
            return Err(invalid(key(), format!("must be finite, got {time}")));
        }
        if let Some(p) = previous.filter(|&p| time <= p) {
            return Err(invalid(
                key(),
                format!(
                    "{time} is not after the previous key's time {p}: the keys of a track \
                     strictly increase in time"
                ),
            ));
        }
        previous = Some(time);
    }
    Ok(())
}

/// Refuses a point beyond the coordinate range, at `key`.
fn check_point(key: String, p: DVec3) -> Result<(), AnimationError> {
    match beyond_range(p.abs().max_element()) {
        Some(message) => Err(out_of_range(key, message)),
        None => Ok(()),
    }
}

/// Refuses the first field of `fields` (name, whether the key gives it) that the key gives,
/// at `key(name)`, saying what keys of this kind take.
fn refuse_given(
    fields: &[(&str, bool)],
    key: impl Fn(&str) -> String,
    takes: &str,
) -> Result<(), AnimationError> {
    match fields.iter().find(|(_, given)| *given) {
        Some((name, _)) => Err(invalid(key(name), takes)),
        None => Ok(()),
    }
}

/// The key before key `k` (at least 1) of the track `track`, as written.
fn before(track: &str, k: usize) -> String {
    format!("{track}[{}]", k.saturating_sub(1))
}

/// Refuses a view from `from` to `to` (points named `names`, e.g. `("eye", "target")`) that
/// points opposite to the previous key's, at `key`: interpolated linearly, the two points
/// would meet between the keys.
fn check_view(
    key: String,
    previous: Option<(DVec3, DVec3)>,
    (from, to): (DVec3, DVec3),
    names: (&str, &str),
    (track, k): (&str, usize),
) -> Result<(), AnimationError> {
    let Some((p, q)) = previous else { return Ok(()) };
    match (direction_between(p, q), direction_between(from, to)) {
        (Some(a), Some(b)) if opposite(a, b) => Err(invalid(
            key,
            format!(
                "turns the view ({1} - {0}) opposite to that of `{2}` (within \
                 {OPPOSITE_TOLERANCE:e} radians): between the keys the {0} would meet the {1}",
                names.0,
                names.1,
                before(track, k)
            ),
        )),
        _ => Ok(()),
    }
}

/// Refuses a direction (`name`: `direction`, `up`) opposite to the previous key's, at `key`:
/// no unique turn between them.
fn check_turn(
    key: String,
    previous: Option<DVec3>,
    direction: DVec3,
    name: &str,
    (track, k): (&str, usize),
) -> Result<(), AnimationError> {
    let Some(p) = previous else { return Ok(()) };
    match (crate::direction::unit(p), crate::direction::unit(direction)) {
        (Some(a), Some(b)) if opposite(a, b) => Err(invalid(
            key,
            format!(
                "is opposite to the {name} of `{}` (within {OPPOSITE_TOLERANCE:e} radians): the \
                 turn between them has no unique path",
                before(track, k)
            ),
        )),
        _ => Ok(()),
    }
}

/// The light track: each key made whole from the scene's light, checked, directions unit.
fn light_track(keys: &[LightKey], rest: &Light) -> Result<Vec<Key<Light>>, AnimationError> {
    const TRACK: &str = "animation.light";
    check_times(TRACK, keys.iter().map(|k| k.time))?;
    let mut track: Vec<Key<Light>> = Vec::with_capacity(keys.len());
    for (k, key) in keys.iter().enumerate() {
        let name = |field: &str| format!("{TRACK}[{k}].{field}");
        let value = match *rest {
            Light::Directional { direction } => {
                refuse_given(
                    &[
                        ("position", key.position.is_some()),
                        ("target", key.target.is_some()),
                        ("fov_deg", key.fov_deg.is_some()),
                    ],
                    name,
                    "the scene's light is directional: its keys take `direction` alone",
                )?;
                Light::Directional { direction: key.direction.unwrap_or(direction) }
            }
            Light::Spot { position, target, fov_deg } => {
                refuse_given(
                    &[("direction", key.direction.is_some())],
                    name,
                    "the scene's light is a spot: its keys take `position`, `target` and `fov_deg`",
                )?;
                Light::Spot {
                    position: key.position.unwrap_or(position),
                    target: key.target.unwrap_or(target),
                    fov_deg: key.fov_deg.unwrap_or(fov_deg),
                }
            }
        };
        value.validate().map_err(|(field, message)| {
            // A target that meets the position the key moved names the position.
            match field == "target" && key.target.is_none() && key.position.is_some() {
                true => invalid(name("position"), "must differ from the target"),
                false => invalid(name(field), message),
            }
        })?;
        // Every key of the track is of the scene's kind.
        let previous = track.last().map(|p| &p.value);
        match value {
            Light::Directional { direction } => {
                let previous = previous.and_then(|p| match *p {
                    Light::Directional { direction } => Some(direction),
                    Light::Spot { .. } => None,
                });
                check_turn(name("direction"), previous, direction, "direction", (TRACK, k))?;
            }
            Light::Spot { position, target, .. } => {
                check_point(name("position"), position)?;
                check_point(name("target"), target)?;
                let previous = previous.and_then(|p| match *p {
                    Light::Spot { position, target, .. } => Some((position, target)),
                    Light::Directional { .. } => None,
                });
                let moved = match key.target.is_none() && key.position.is_some() {
                    true => "position",
                    false => "target",
                };
                let view = (position, target);
                check_view(name(moved), previous, view, ("position", "target"), (TRACK, k))?;
            }
        }
        track.push(Key { time: key.time, value: value.normalized() });
    }
    Ok(track)
}

/// The camera track: each key made whole from the scene's camera, checked.
fn camera_track(keys: &[CameraKey], rest: &Camera) -> Result<Vec<Key<Camera>>, AnimationError> {
    const TRACK: &str = "animation.camera";
    check_times(TRACK, keys.iter().map(|k| k.time))?;
    let mut track: Vec<Key<Camera>> = Vec::with_capacity(keys.len());
    for (k, key) in keys.iter().enumerate() {
        let name = |field: &str| format!("{TRACK}[{k}].{field}");
        let value = match *rest {
            Camera::Perspective { eye, target, up, fov_y_deg, near } => {
                refuse_given(
                    &[("height", key.height.is_some())],
                    name,
                    "the scene's camera is perspective: its keys take `eye`, `target`, `up` and \
                     `fov_y_deg`",
                )?;
                Camera::Perspective {
                    eye: key.eye.unwrap_or(eye),
                    target: key.target.unwrap_or(target),
                    up: key.up.unwrap_or(up),
                    fov_y_deg: key.fov_y_deg.unwrap_or(fov_y_deg),
                    near,
                }
            }
            Camera::Orthographic { eye, target, up, height } => {
                refuse_given(
                    &[("fov_y_deg", key.fov_y_deg.is_some())],
                    name,
                    "the scene's camera is orthographic: its keys take `eye`, `target`, `up` and \
                     `height`",
                )?;
                Camera::Orthographic {
                    eye: key.eye.unwrap_or(eye),
                    target: key.target.unwrap_or(target),
                    up: key.up.unwrap_or(up),
                    height: key.height.unwrap_or(height),
                }
            }
        };
        value.validate().map_err(|(field, message)| {
            // A target that meets the eye the key moved names the eye.
            match field == "target" && key.target.is_none() && key.eye.is_some() {
                true => invalid(name("eye"), "must differ from the target"),
                false => invalid(name(field), message),
            }
        })?;
        let (eye, target) = (value.eye(), value.target());
        check_point(name("eye"), eye)?;
        check_point(name("target"), target)?;
        let previous = track.last().map(|p| &p.value);
        let moved = if key.target.is_none() && key.eye.is_some() { "eye" } else { "target" };
        let previous_view = previous.map(|p| (p.eye(), p.target()));
        check_view(name(moved), previous_view, (eye, target), ("eye", "target"), (TRACK, k))?;
        check_turn(name("up"), previous.map(up_of), up_of(&value), "up", (TRACK, k))?;
        track.push(Key { time: key.time, value });
    }
    Ok(track)
}

/// A camera's up hint.
fn up_of(camera: &Camera) -> DVec3 {
    match camera {
        Camera::Perspective { up, .. } | Camera::Orthographic { up, .. } => *up,
    }
}

/// The motion of track `j`: its object found by name, its keys checked, its poses within the
/// coordinate range. `earlier` are the motions of the tracks before it.
fn motion(
    j: usize,
    track: &ObjectTrack,
    rest: &Scene,
    earlier: &[Motion],
) -> Result<Motion, AnimationError> {
    let base = format!("animation.object[{j}]");
    let named: Vec<usize> =
        (0..rest.objects.len()).filter(|&i| rest.objects[i].name == track.name).collect();
    let object = match named[..] {
        [i] => i,
        [] => {
            let names: Vec<String> = rest.objects.iter().map(|o| format!("`{}`", o.name)).collect();
            return Err(invalid(
                format!("{base}.name"),
                format!(
                    "no object is named `{}` (the scene's objects: {})",
                    track.name,
                    names.join(", ")
                ),
            ));
        }
        _ => {
            return Err(invalid(
                format!("{base}.name"),
                format!(
                    "{} objects are named `{}`: give the one that moves a name of its own",
                    named.len(),
                    track.name
                ),
            ))
        }
    };
    if let Some(other) = earlier.iter().position(|m| m.object == object) {
        return Err(invalid(
            format!("{base}.name"),
            format!(
                "`{}` moves in `animation.object[{other}]` already: one track per object",
                track.name
            ),
        ));
    }
    if track.keys.is_empty() {
        return Err(invalid(
            format!("{base}.key"),
            "a track needs at least one key ([[animation.object.key]])",
        ));
    }
    check_times(&format!("{base}.key"), track.keys.iter().map(|k| k.time))?;
    let mut keys = Vec::with_capacity(track.keys.len());
    for (k, key) in track.keys.iter().enumerate() {
        for (field, v) in [("translate", key.translate), ("rotate_deg", key.rotate_deg)] {
            if !v.is_finite() {
                return Err(invalid(format!("{base}.key[{k}].{field}"), "must be finite"));
            }
        }
        keys.push(Key { time: key.time, value: Rigid::new(key.translate, key.rotate_deg) });
    }
    check_reach(&base, &rest.objects[object], &keys)?;
    Ok(Motion { object, keys })
}

/// Refuses a motion that could take `object` beyond the coordinate range at some time. A
/// translation is interpolated linearly, so it stays within the box of its keys': an object
/// that only translates stays within its bounding box moved by each key; one that rotates,
/// within the sphere about its centre that holds it, moved by each key.
fn check_reach(
    base: &str,
    object: &crate::scene::Object,
    keys: &[Key<Rigid>],
) -> Result<(), AnimationError> {
    let mesh = &object.mesh;
    let Some((lo, hi)) = mesh.bounds() else { return Ok(()) };
    let centre = 0.5 * (lo + hi);
    let rotates = keys.iter().any(|k| k.value.rotation != DQuat::IDENTITY);
    let radius = if rotates {
        mesh.positions.iter().map(|&p| (p - centre).length()).fold(0.0, f64::max)
    } else {
        0.0
    };
    for (k, key) in keys.iter().enumerate() {
        let t = key.value.translate;
        let reach = if rotates {
            // With a margin for the rounding of the rotation about the centre.
            ((centre + t).abs().max_element() + radius) * (1.0 + 16.0 * f64::EPSILON)
        } else {
            // Exact: a translation between keys stays within theirs, coordinate by
            // coordinate, and rounded sums are monotone.
            (lo + t).abs().max((hi + t).abs()).max_element()
        };
        if let Some(message) = beyond_range(reach) {
            let key = match t == DVec3::ZERO {
                true => format!("{base}.key[{k}]"),
                false => format!("{base}.key[{k}].translate"),
            };
            let how = if rotates { "turning about its centre and moved" } else { "moved" };
            return Err(out_of_range(
                key,
                format!("object `{}` {how} here: {message}", object.name),
            ));
        }
    }
    Ok(())
}

/// Refuses motions that may shrink the scene's bounding box below [`MIN_EXTENT`]: a still
/// object keeps its box, a moving one the distance between its farthest vertices, at least
/// its box's diagonal over the square root of 3, and the scene's box holds every object's.
fn check_extent(motions: &[Motion], rest: &Scene) -> Result<(), AnimationError> {
    if motions.is_empty() {
        return Ok(());
    }
    let least = rest
        .objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| {
            let (lo, hi) = o.mesh.bounds()?;
            let diagonal = (hi - lo).length();
            Some(if motions.iter().any(|m| m.object == i) {
                diagonal / 3f64.sqrt()
            } else {
                diagonal
            })
        })
        .fold(0.0, f64::max);
    // With a margin for the rounding of the motions.
    if least * (1.0 - 64.0 * f64::EPSILON) >= MIN_EXTENT {
        return Ok(());
    }
    Err(out_of_range(
        "animation.object",
        format!(
            "the objects are so small that moving them may bring the scene's bounding box \
             below the supported diagonal of {MIN_EXTENT:e}: the motions keep a diagonal of \
             only {}",
            apart(least, MIN_EXTENT)
        ),
    ))
}

/// The map-scale track: times checked, every value positive and finite.
fn scale_track(keys: &[ScaleKey]) -> Result<Vec<Key<f64>>, AnimationError> {
    check_times("animation.map_scale", keys.iter().map(|k| k.time))?;
    keys.iter()
        .enumerate()
        .map(|(k, key)| {
            if key.value > 0.0 && key.value.is_finite() {
                Ok(Key { time: key.time, value: key.value })
            } else {
                Err(invalid(
                    format!("animation.map_scale[{k}].value"),
                    format!("must be positive and finite, got {}", key.value),
                ))
            }
        })
        .collect()
}
