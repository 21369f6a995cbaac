//! What a pixel's square sees of the scene, as `exact` classifies it from the camera's view of
//! the triangles (the rule is in [`crate::exact::classes`]). Metrics are reported per class, so
//! that the camera's geometric aliasing on silhouettes (`edge`) is kept apart from the shadow
//! error on surfaces (`planar`, `surface`).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The class of a pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[repr(u8)]
pub enum PixelClass {
    /// The square sees no geometry (background only).
    Uncovered = 0,
    /// The square sees one planar object and nothing else.
    Planar = 1,
    /// The square is tiled, without gap or overlap, by front-facing triangles of one
    /// continuous surface, with nothing in front of them.
    Surface = 2,
    /// Anything else: a depth discontinuity, several objects, background, or a visible back
    /// face inside the square.
    Edge = 3,
}

impl PixelClass {
    /// Every class, in code order.
    pub const ALL: [Self; 4] = [Self::Uncovered, Self::Planar, Self::Surface, Self::Edge];

    /// The class's name, as in `metrics.json` and `run.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Uncovered => "uncovered",
            Self::Planar => "planar",
            Self::Surface => "surface",
            Self::Edge => "edge",
        }
    }

    /// The class's code in `class_ids.png` (0 uncovered, 1 planar, 2 surface, 3 edge).
    pub fn code(self) -> u8 {
        self as u8
    }

    /// The colour of the class in `classes.png`.
    pub fn colour(self) -> [u8; 3] {
        match self {
            Self::Uncovered => [0, 0, 0],
            Self::Planar => [70, 130, 220],
            Self::Surface => [90, 190, 90],
            Self::Edge => [230, 80, 60],
        }
    }

    /// Whether `exact` evaluates pixels of this class (the shadow-only pixels).
    pub fn is_shadow_only(self) -> bool {
        matches!(self, Self::Planar | Self::Surface)
    }
}

/// Number of pixels of each class, in [`PixelClass::ALL`] order.
pub fn counts(classes: &[PixelClass]) -> [u64; 4] {
    // In parallel: a frame's classes counted in one thread kept the others waiting (0.9 ms of
    // `exact` on `bunny-plane` at 800 x 600, two threads).
    classes
        .par_chunks(1 << 14)
        .map(|part| {
            let mut n = [0u64; 4];
            for &c in part {
                n[c as usize] += 1;
            }
            n
        })
        .reduce(|| [0; 4], |a, b| std::array::from_fn(|k| a[k] + b[k]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_follow_the_order_of_all() {
        for (k, c) in PixelClass::ALL.iter().enumerate() {
            assert_eq!(usize::from(c.code()), k);
        }
        assert_eq!(counts(&[PixelClass::Edge, PixelClass::Planar, PixelClass::Edge]), [0, 1, 0, 2]);
        assert_eq!(serde_json::to_string(&PixelClass::Surface).expect("serialises"), "\"surface\"");
    }
}
