//! `heightfield`: a bumpy, densely tessellated receiver.
//!
//! Stands for the bumpy receiver of Pan et al. 2009, Fig. 9: "generated from a height field and
//! densely tessellated \[so\] that the projection area of most triangles are less than one
//! pixel". A `size` x `size` square centred on the origin at y ≈ 0, split into `resolution` x
//! `resolution` quads of two triangles, each vertex lifted by the sum of `waves` plane sine
//! waves with random directions and phases and wavelengths within ±25 % of `wavelength`; the
//! sum is then scaled so that the largest |y| over the vertices is exactly `amplitude`.
//!
//! Invariants: `2 * resolution²` triangles, `(resolution + 1)²` shared vertices, an open
//! sheet; every triangle counter-clockwise seen from above (its normal has y > 0 whatever the
//! bumps); heights in `[-amplitude, amplitude]`. The default (256², 131 072 triangles over
//! 20 x 20) makes triangles of about 0.08 units, a pixel or two at 800 x 600; the `bumpy`
//! scene uses 512² for sub-pixel triangles.

use super::plane::grid;
use super::rng::{sin_cos, Rng};
use super::{count_at_least, non_negative, positive, triangle_budget, Generator, ParamError};
use crate::mesh::Mesh;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Parameters of the `heightfield` generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HeightfieldParams {
    /// Side of the square, in world units. Default 20.
    pub size: f64,
    /// Quads along each side (two triangles each). Default 256.
    pub resolution: u32,
    /// Largest |height| of the bumps, in world units (0 gives a flat grid). Default 0.15.
    pub amplitude: f64,
    /// Typical wavelength of the bumps, in world units. Default 1.5.
    pub wavelength: f64,
    /// Number of sine waves summed. Default 6.
    pub waves: u32,
    /// Random seed. Default 1.
    pub seed: u64,
}

impl Default for HeightfieldParams {
    fn default() -> Self {
        Self { size: 20.0, resolution: 256, amplitude: 0.15, wavelength: 1.5, waves: 6, seed: 1 }
    }
}

impl Generator for HeightfieldParams {
    /// The number of triangles [`Generator::generate`] builds: `2 * resolution²` (saturating).
    fn triangle_count(&self) -> u64 {
        (u64::from(self.resolution) * u64::from(self.resolution)).saturating_mul(2)
    }

    fn validate(&self) -> Result<(), ParamError> {
        positive("size", self.size)?;
        count_at_least("resolution", self.resolution, 1)?;
        triangle_budget("resolution", self.triangle_count())?;
        non_negative("amplitude", self.amplitude)?;
        positive("wavelength", self.wavelength)?;
        count_at_least("waves", self.waves, 1)?;
        if self.waves > 1000 {
            return Err(ParamError::new(
                "waves",
                format!("must be at most 1000, got {}", self.waves),
            ));
        }
        Ok(())
    }

    fn generate(&self) -> Mesh {
        if self.validate().is_err() {
            return Mesh::default();
        }
        let mut rng = Rng::new(self.seed);
        // Each wave: wave vector (kx, kz) and phase.
        let waves: Vec<(f64, f64, f64)> = (0..self.waves)
            .map(|_| {
                let (s, c) = sin_cos(rng.range(0.0, TAU));
                let k = TAU / (self.wavelength * rng.range(0.75, 1.25));
                (k * c, k * s, rng.range(0.0, TAU))
            })
            .collect();
        let height = |x: f64, z: f64| {
            waves.iter().map(|&(kx, kz, phase)| sin_cos(kx * x + kz * z + phase).0).sum::<f64>()
        };
        let mut mesh = grid(self.size, self.resolution, height);
        let peak = mesh.positions.iter().fold(0.0f64, |m, p| m.max(p.y.abs()));
        let scale = if peak > 0.0 { self.amplitude / peak } else { 0.0 };
        for p in &mut mesh.positions {
            // Clamped so that rounding cannot push a height past the amplitude.
            p.y = (p.y * scale).clamp(-self.amplitude, self.amplitude);
        }
        mesh
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::bit_identical;
    use super::*;

    #[test]
    fn bumps_reach_the_amplitude_and_triangles_face_up() {
        let p = HeightfieldParams { resolution: 40, size: 8.0, ..Default::default() };
        let mesh = p.generate();
        assert_eq!(mesh.triangle_count(), 2 * 40 * 40);
        assert_eq!(mesh.positions.len(), 41 * 41);
        let peak = mesh.positions.iter().fold(0.0f64, |m, p| m.max(p.y.abs()));
        assert!((peak - 0.15).abs() < 1e-15, "{peak}");
        assert!(mesh.plane().is_none());
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.corners(t);
            assert!((b - a).cross(c - a).y > 0.0);
        }
        let (lo, hi) = mesh.bounds().expect("vertices");
        assert_eq!((lo.x, lo.z, hi.x, hi.z), (-4.0, -4.0, 4.0, 4.0));
    }

    #[test]
    fn zero_amplitude_is_flat() {
        let mesh =
            HeightfieldParams { resolution: 4, amplitude: 0.0, ..Default::default() }.generate();
        assert!(mesh.positions.iter().all(|p| p.y == 0.0));
    }

    #[test]
    fn seeds_decide_the_bumps() {
        let p = HeightfieldParams { resolution: 16, ..Default::default() };
        assert!(bit_identical(&p.generate(), &p.generate()));
        assert_ne!(p.generate(), HeightfieldParams { seed: 2, ..p.clone() }.generate());
    }

    #[test]
    fn validation_names_the_key() {
        let bad = |p: HeightfieldParams| p.validate().expect_err("invalid").key;
        let d = HeightfieldParams::default;
        assert_eq!(bad(HeightfieldParams { size: -1.0, ..d() }), "size");
        assert_eq!(bad(HeightfieldParams { resolution: 0, ..d() }), "resolution");
        assert_eq!(bad(HeightfieldParams { resolution: 4000, ..d() }), "resolution");
        assert_eq!(bad(HeightfieldParams { amplitude: -0.1, ..d() }), "amplitude");
        assert_eq!(bad(HeightfieldParams { wavelength: 0.0, ..d() }), "wavelength");
        assert_eq!(bad(HeightfieldParams { waves: 0, ..d() }), "waves");
    }
}
