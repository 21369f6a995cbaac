//! Resolved scenes: world-space objects with materials, a camera, a light, a default
//! resolution, the effects the content calls for, and the scene's animation.

use crate::{animation::Animation, camera::Camera, light::Light, mesh::Mesh};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Surface colour and opacity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Material {
    /// Linear RGB albedo in [0, 1] (default `[0.8, 0.8, 0.8]`).
    #[serde(deserialize_with = "crate::arrays::exact")]
    pub color: [f64; 3],
    /// Opacity of a shadow caster in [0, 1] (default 1). Below 1 the scene has `transparency`.
    pub opacity: f64,
}

impl Default for Material {
    fn default() -> Self {
        Self { color: [0.8, 0.8, 0.8], opacity: 1.0 }
    }
}

/// One object of a scene, in world space.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// Name, for messages and reports.
    pub name: String,
    /// World-space mesh.
    pub mesh: Mesh,
    /// Material.
    pub material: Material,
    /// Whether the object blocks light (default true).
    pub casts_shadows: bool,
}

/// Effects that can be forced off in a scene file (`[effects]`), even when the content would
/// call for them. `true` keeps the derived value; `false` forces the effect off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EffectSwitches {
    /// Allow `transparency` (default true).
    pub transparency: bool,
    /// Allow `curved_receivers` (default true).
    pub curved_receivers: bool,
    /// Allow `planar_receiver` (default true).
    pub planar_receiver: bool,
}

impl Default for EffectSwitches {
    fn default() -> Self {
        Self { transparency: true, curved_receivers: true, planar_receiver: true }
    }
}

/// What a scene calls for; methods run only the stages these need.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Effects {
    /// Some caster has opacity < 1.
    pub transparency: bool,
    /// Some visible receiver is not planar.
    pub curved_receivers: bool,
    /// Some visible receiver is planar: the exact reference applies to the pixels that see it.
    pub planar_receiver: bool,
}

impl Effects {
    /// The names of the effects that are on, as written in run records.
    pub fn names(&self) -> Vec<&'static str> {
        [
            (self.transparency, "transparency"),
            (self.curved_receivers, "curved_receivers"),
            (self.planar_receiver, "planar_receiver"),
        ]
        .into_iter()
        .filter_map(|(on, name)| on.then_some(name))
        .collect()
    }
}

/// All triangles of a scene in one array, with the object each came from. Triangle ids used
/// by every method are indices into `triangles`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Geometry {
    /// All vertex positions.
    pub positions: Vec<DVec3>,
    /// All triangles.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, the index of its object in [`Scene::objects`].
    pub object: Vec<u32>,
}

impl Geometry {
    /// The three corners of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

/// A resolved scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Name (a built-in's name, or the file stem).
    pub name: String,
    /// Default image width in pixels.
    pub width: u32,
    /// Default image height in pixels.
    pub height: u32,
    /// Camera.
    pub camera: Camera,
    /// Light.
    pub light: Light,
    /// Objects.
    pub objects: Vec<Object>,
    /// Effects forced off by the scene file.
    pub switches: EffectSwitches,
    /// How the scene moves ([`Animation::still`] for a still scene, and for a scene posed at
    /// a frame, [`Animation::pose`]).
    pub animation: Animation,
}

impl Scene {
    /// Total triangle count.
    pub fn triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangle_count()).sum()
    }

    /// Axis-aligned bounds of all objects.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        self.objects.iter().filter_map(|o| o.mesh.bounds()).fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
        )
    }

    /// Every triangle in one array.
    pub fn geometry(&self) -> Geometry {
        let mut g = Geometry::default();
        for (i, o) in self.objects.iter().enumerate() {
            let base = g.positions.len() as u32;
            g.positions.extend_from_slice(&o.mesh.positions);
            g.triangles.extend(o.mesh.triangles.iter().map(|t| t.map(|v| v + base)));
            g.object.extend(std::iter::repeat_n(i as u32, o.mesh.triangle_count()));
        }
        g
    }

    /// Whether some part of the object's bounding box may be seen by the camera at the
    /// scene's resolution (conservative: `true` unless all eight corners lie beyond one side
    /// of the view).
    fn maybe_visible(&self, o: &Object) -> bool {
        let Some((lo, hi)) = o.mesh.bounds() else { return false };
        let cam = self.camera.projector(self.width, self.height);
        let corners = crate::mesh::box_corners(lo, hi);
        if corners.iter().all(|&c| cam.is_perspective() && cam.depth_of(c) < cam.near) {
            return false;
        }
        let projected: Vec<_> = corners.iter().filter_map(|&c| cam.project(c)).collect();
        if projected.len() < 8 {
            return true; // straddles the near plane
        }
        let outside = |f: &dyn Fn(glam::DVec2) -> bool| projected.iter().all(|(xy, _)| f(*xy));
        !(outside(&|p| p.x < 0.0)
            || outside(&|p| p.y < 0.0)
            || outside(&|p| p.x > cam.width)
            || outside(&|p| p.y > cam.height))
    }

    /// The effects the content calls for, less those the scene file forces off.
    pub fn effects(&self) -> Effects {
        let mut e = Effects::default();
        for o in &self.objects {
            if o.casts_shadows && o.material.opacity < 1.0 {
                e.transparency = true;
            }
            if self.maybe_visible(o) {
                if o.mesh.plane().is_some() {
                    e.planar_receiver = true;
                } else {
                    e.curved_receivers = true;
                }
            }
        }
        e.transparency &= self.switches.transparency;
        e.curved_receivers &= self.switches.curved_receivers;
        e.planar_receiver &= self.switches.planar_receiver;
        e
    }

    /// The receiver plane of the exact reference: the visible planar object of largest area,
    /// as `(index of object, unit normal, offset)` with `normal·p = offset`.
    pub fn receiver_plane(&self) -> Option<(usize, DVec3, f64)> {
        self.objects
            .iter()
            .enumerate()
            .filter(|(_, o)| self.maybe_visible(o))
            .filter_map(|(i, o)| o.mesh.plane().map(|(n, d)| (i, n, d, o.mesh.area())))
            .max_by(|a, b| a.3.total_cmp(&b.3))
            .map(|(i, n, d, _)| (i, n, d))
    }
}
