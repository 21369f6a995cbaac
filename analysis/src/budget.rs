//! The memory budget: what a run will need, estimated before anything is built, against what
//! the machine has (`MemAvailable` of `/proc/meminfo`, and the control group's `memory.max`
//! where it is lower) or the user's `--max-memory`.
//!
//! The estimate is a linear model of the work's sizes: triangles (the scene's meshes, the
//! frame's triangle array and the structures built over it), pixels (the G-buffer, the
//! visibility, the pixel classes), sub-samples (pixels times the rate) and shadow-map texels.
//! Its coefficients are peak resident set sizes measured with `/usr/bin/time -f %M` on the
//! built-in scenes (`random-100k` and `random-1m` at 320 x 240 for the per-triangle terms, `cage`
//! at 1600 x 1200 for the per-pixel ones) on this project's 2-core, 24 GB machines, each
//! rounded up by about a half, so that the estimate is an upper bound of what was measured
//! (`estimates_bound_the_measured_peaks`). A refusal names the estimate, its largest parts,
//! the limit and where the limit comes from, and what to lower.
//!
//! Our own code rather than a crate: no crate knows what our methods allocate.

use std::fmt;

/// Bytes of a gibibyte.
const GIB: f64 = (1u64 << 30) as f64;

/// The process itself, its thread pool and the shared tables, measured on the smallest scenes.
const BASE: u64 = 64 << 20;
/// Per triangle: the scene's meshes, the frame's triangle array, the light depth map's
/// rasterizer set-up and the G-buffer's (measured 260 B between `random-100k` and `random-1m`
/// with `sm`).
const PER_TRIANGLE: u64 = 400;
/// Per pixel: G-buffer (position, normal, depth, triangle), visibility, shaded image.
const PER_PIXEL: u64 = 160;

/// What one method or reference adds, per unit of the work's sizes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Cost {
    per_triangle: u64,
    per_pixel: u64,
    per_sample: u64,
    per_texel: u64,
    maps: u64,
}

/// What `method` adds to the base (see the module doc for how it was measured).
fn method_cost(method: &str) -> Cost {
    let c = Cost::default();
    match method {
        "sm" | "pcf-gems16" | "pcf-gems4" | "pcf-reeves" => Cost { per_texel: 12, maps: 1, ..c },
        "pcf-bs-2x2" | "pcf-bs-fast-2x2" | "pcf-bs-fast-4x4" => {
            Cost { per_texel: 12, maps: 4, ..c }
        }
        // The irregular z-buffer: samples binned in light space, the BSP over the blockers.
        "afsm" => Cost { per_triangle: 120, per_sample: 96, ..c },
        "afsm-ss" => Cost { per_triangle: 120, per_sample: 96, ..c },
        // The frustum-traced IZB: per pixel its lists' entries (about 2.4 texels a footprint,
        // 8 B each while sorted) and masks; per caster its (texel, caster) pairs. Measured
        // 80 B a pixel over sm on cage at 1600 x 1200, next to nothing a triangle on random-1m.
        "ftizb" => Cost { per_triangle: 64, per_pixel: 128, ..c },
        // Silhouettes, facets and their pairs: 540 B a triangle measured on random-1m.
        "pan09" => Cost { per_triangle: 800, per_sample: 8, per_texel: 24, maps: 1, ..c },
        // Conservative rasterization into 128-bit triangle texels (f32 texels: the same).
        "spsm" | "spsm-f32" => {
            Cost { per_triangle: 200, per_sample: 16, per_texel: 48, maps: 1, ..c }
        }
        "raytrace" => raytrace_cost(),
        "exact" => exact_cost(),
        // A method this table does not know: the heaviest known one's per-unit costs.
        _ => Cost { per_triangle: 800, per_pixel: 2048, per_sample: 96, per_texel: 48, maps: 4 },
    }
}

/// `raytrace`: the BVH and its frame copy of the triangles (256 B a triangle measured on
/// random-1m), the camera hits per sub-sample.
fn raytrace_cost() -> Cost {
    Cost { per_triangle: 400, per_sample: 64, ..Cost::default() }
}

/// `exact`: the pixel classes, the casters' light-space grid, the shadow polygons and their
/// unions per receiver.
fn exact_cost() -> Cost {
    Cost { per_triangle: 2400, per_pixel: 2048, ..Cost::default() }
}

/// The sizes of a run's work.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Work<'a> {
    /// The scene's triangles (an upper bound, known before the scene is built).
    pub triangles: u64,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// The method (a name of `methods::registry::METHODS`, or a reference's).
    pub method: &'a str,
    /// Its sub-samples per pixel (1 for a method without).
    pub rate: u32,
    /// Its shadow-map resolution (the map is `map_res x map_res`; ignored by methods without).
    pub map_res: u32,
    /// The reference the run is compared against and its edge rate (`compare`, a report), if
    /// any: `exact` with its edge pixels ray traced, or `raytrace`.
    pub reference: Option<(&'a str, u32)>,
}

/// An estimate of a run's peak memory, with its parts.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Bytes in all.
    pub bytes: u64,
    /// The parts, largest first: what they are and their bytes (none where only the total is
    /// known, as a report's plan keeps it).
    pub parts: Vec<(&'static str, u64)>,
}

/// Bytes as `12.3 GB` (gibibytes, one decimal; `MB` below one).
pub fn bytes_text(b: u64) -> String {
    let g = b as f64 / GIB;
    if g >= 1.0 {
        format!("{g:.1} GB")
    } else {
        format!("{:.0} MB", b as f64 / (1u64 << 20) as f64)
    }
}

impl fmt::Display for Estimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> =
            self.parts.iter().map(|(what, b)| format!("{what} {}", bytes_text(*b))).collect();
        write!(f, "about {}", bytes_text(self.bytes))?;
        if parts.is_empty() {
            return Ok(());
        }
        write!(f, " ({})", parts.join(", "))
    }
}

/// `a * b` in `u64`, saturating: a budget of absurd sizes is refused, never wraps.
fn mul(a: u64, b: u64) -> u64 {
    a.saturating_mul(b)
}

fn cost_bytes(c: Cost, w: &Work<'_>, pixels: u64, samples: u64) -> u64 {
    let texels = mul(u64::from(w.map_res), u64::from(w.map_res));
    mul(c.per_triangle, w.triangles)
        .saturating_add(mul(c.per_pixel, pixels))
        .saturating_add(mul(c.per_sample, samples))
        .saturating_add(mul(mul(c.per_texel, texels), c.maps))
}

/// The estimated peak memory of `w` (see the module doc).
pub fn estimate(w: &Work<'_>) -> Estimate {
    let pixels = mul(u64::from(w.width), u64::from(w.height));
    let samples = mul(pixels, u64::from(w.rate.max(1)));
    let mut parts = vec![
        ("process", BASE),
        ("scene and frame", mul(PER_TRIANGLE, w.triangles).saturating_add(mul(PER_PIXEL, pixels))),
        ("method", cost_bytes(method_cost(w.method), w, pixels, samples)),
    ];
    if let Some((reference, rate)) = w.reference {
        let cost = if reference == "raytrace" { raytrace_cost() } else { exact_cost() };
        let ref_samples = mul(pixels, u64::from(rate.max(1)));
        // exact ray traces its edge pixels: both structures.
        let mut b = cost_bytes(cost, w, pixels, ref_samples);
        if reference == "exact" {
            b = b.saturating_add(cost_bytes(raytrace_cost(), w, pixels, 0));
        }
        parts.push(("reference", b));
    }
    parts.sort_by_key(|p| std::cmp::Reverse(p.1));
    let bytes = parts.iter().fold(0u64, |s, p| s.saturating_add(p.1));
    Estimate { bytes, parts }
}

/// The memory a run may use, and where that number comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct Limit {
    /// Bytes.
    pub bytes: u64,
    /// Where it comes from, as the refusal names it.
    pub source: String,
}

impl Limit {
    /// `--max-memory` when given, else what the machine has available now
    /// ([`Limit::available`]); `None` when neither is known (the check is then skipped).
    pub fn new(max_memory: Option<u64>) -> Option<Self> {
        match max_memory {
            Some(bytes) => Some(Limit { bytes, source: "--max-memory".into() }),
            None => Self::available(),
        }
    }

    /// `MemAvailable` of `/proc/meminfo`, or the control group's `memory.max` less its
    /// `memory.current` where that is lower.
    pub fn available() -> Option<Self> {
        let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
        let available = meminfo.as_deref().and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("MemAvailable:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
                .map(|kb| kb.saturating_mul(1024))
        });
        let read = |f: &str| {
            std::fs::read_to_string(format!("/sys/fs/cgroup/{f}"))
                .ok()
                .and_then(|t| t.trim().parse::<u64>().ok())
        };
        let group =
            read("memory.max").map(|max| max.saturating_sub(read("memory.current").unwrap_or(0)));
        match (available, group) {
            (Some(a), Some(g)) if g < a => Some(Limit {
                bytes: g,
                source: "the memory left in this control group (/sys/fs/cgroup/memory.max)".into(),
            }),
            (Some(a), _) => Some(Limit {
                bytes: a,
                source: "the memory available now (MemAvailable of /proc/meminfo)".into(),
            }),
            (None, Some(g)) => Some(Limit {
                bytes: g,
                source: "the memory left in this control group (/sys/fs/cgroup/memory.max)".into(),
            }),
            (None, None) => None,
        }
    }
}

/// A run would need more memory than its limit.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{what} needs {estimate}, more than the {} of {}; lower {lower}, or raise the limit with \
     --max-memory if the machine has more",
    bytes_text(.limit.bytes),
    .limit.source
)]
pub struct OverBudget {
    /// What the estimate is of (a scene, method and frame).
    pub what: String,
    /// The estimate.
    pub estimate: Estimate,
    /// The limit.
    pub limit: Limit,
    /// What to lower, from the estimate's largest part.
    pub lower: String,
}

/// Checks `w`'s estimate against `limit`; `what` names the run in the refusal.
pub fn check(w: &Work<'_>, limit: &Limit, what: &str) -> Result<Estimate, OverBudget> {
    let estimate = estimate(w);
    if estimate.bytes <= limit.bytes {
        return Ok(estimate);
    }
    let lower = match (estimate.parts.first().map(|p| p.0), w.method) {
        (Some("reference"), _) => {
            "the frame size (--width, --height), the scene's triangles or --ref-rate"
        }
        (Some("method"), "exact") => "the frame size (--width, --height) or the scene's triangles",
        (Some("method"), _) => {
            "the frame size (--width, --height), --rate, --map-res or the scene's triangles"
        }
        _ => {
            "the scene's triangles (fewer or smaller objects) or the frame size (--width, --height)"
        }
    };
    Err(OverBudget {
        what: what.to_owned(),
        estimate,
        limit: limit.clone(),
        lower: lower.to_owned(),
    })
}

/// Why a size could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "`{0}` is not a size: give bytes with an optional unit K, M, G or T (powers of 1024, an \
     optional B after it), such as 8G or 512M"
)]
pub struct BadSize(pub String);

/// Reads a size such as `8G`, `1.5GB`, `512M` or `1000000` (bytes); units are powers of 1024.
pub fn parse_size(text: &str) -> Result<u64, BadSize> {
    let bad = || BadSize(text.to_owned());
    let t = text.trim();
    let t = t.strip_suffix(['B', 'b']).unwrap_or(t);
    let (number, unit) = match t.char_indices().last() {
        Some((k, c)) if c.is_ascii_alphabetic() => (&t[..k], c.to_ascii_uppercase()),
        _ => (t, ' '),
    };
    let scale: f64 = match unit {
        ' ' => 1.0,
        'K' => 1024.0,
        'M' => 1024.0 * 1024.0,
        'G' => GIB,
        'T' => GIB * 1024.0,
        _ => return Err(bad()),
    };
    let n: f64 = number.trim().parse().map_err(|_| bad())?;
    let bytes = n * scale;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(bad());
    }
    Ok(bytes as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn work(triangles: u64, method: &str, rate: u32) -> Work<'_> {
        Work { triangles, width: 320, height: 240, method, rate, map_res: 1024, reference: None }
    }

    /// Peak resident set sizes measured with `/usr/bin/time -f %M` (release build, map 1024,
    /// rate 16 where the method supersamples), in kB: `random-100k` and `random-1m` at
    /// 320 x 240, `cage` (1,586 triangles) at 1600 x 1200.
    #[test]
    fn estimates_bound_the_measured_peaks() {
        let cage: &[(&str, u32, u64)] = &[
            ("sm", 1, 307_628),
            ("afsm", 1, 357_472),
            ("pan09", 16, 474_364),
            ("spsm", 1, 302_040),
            ("ftizb", 16, 463_184),
        ];
        for &(method, rate, kb) in cage {
            let w = Work { width: 1600, height: 1200, ..work(1586, method, rate) };
            let (e, peak) = (estimate(&w), kb * 1024);
            assert!(e.bytes >= peak, "{method} on cage: {e} below {peak} B");
            assert!(e.bytes <= 4 * peak + (256 << 20), "{method} on cage: {e} far above {peak} B");
        }
        let measured: &[(u64, &str, u32, u64)] = &[
            (100_002, "sm", 1, 69_740),
            (100_002, "pcf-bs-2x2", 1, 125_336),
            (100_002, "afsm-ss", 16, 134_992),
            (100_002, "pan09", 16, 128_788),
            (100_002, "spsm", 1, 100_932),
            (100_002, "raytrace", 16, 86_240),
            (100_002, "exact", 1, 216_076),
            (100_002, "ftizb", 16, 56_944),
            (1_000_002, "sm", 1, 304_232),
            (1_000_002, "pcf-bs-2x2", 1, 356_704),
            (1_000_002, "afsm", 1, 299_312),
            (1_000_002, "afsm-ss", 16, 363_640),
            (1_000_002, "pan09", 16, 846_196),
            (1_000_002, "spsm", 1, 446_092),
            (1_000_002, "raytrace", 16, 560_692),
            (1_000_002, "exact", 1, 1_814_216),
            (1_000_002, "ftizb", 16, 307_568),
        ];
        for &(triangles, method, rate, kb) in measured {
            let e = estimate(&work(triangles, method, rate));
            let peak = kb * 1024;
            assert!(e.bytes >= peak, "{method} on {triangles}: {e} below {peak} B");
            assert!(
                e.bytes <= 4 * peak + (256 << 20),
                "{method} on {triangles}: {e} far above {peak} B"
            );
        }
    }

    #[test]
    fn ten_objects_of_19_million_triangles_are_over_any_machine_of_ours() {
        let w = work(190_000_000, "sm", 1);
        let limit = Limit { bytes: 24 << 30, source: "test".into() };
        let e = check(&w, &limit, "scene x").expect_err("refused");
        let text = e.to_string();
        assert!(text.contains("scene x needs about") && text.contains("24.0 GB of test"), "{text}");
        assert!(text.contains("scene's triangles"), "{text}");
        // Absurd sizes saturate rather than wrap.
        let huge = Work { width: u32::MAX, height: u32::MAX, rate: u32::MAX, ..w };
        assert_eq!(estimate(&huge).bytes, u64::MAX);
    }

    #[test]
    fn sizes_read_with_units() {
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("512MB"), Ok(512 << 20));
        assert_eq!(parse_size("1.5g"), Ok(3 << 29));
        assert_eq!(parse_size("4096"), Ok(4096));
        for bad in ["", "G", "-1G", "1X", "nan", "0", "1e30T"] {
            assert!(parse_size(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_machine_says_what_it_has() {
        let l = Limit::available().expect("Linux says");
        assert!(l.bytes > 0 && !l.source.is_empty());
        assert_eq!(Limit::new(Some(5)).map(|l| l.bytes), Some(5));
    }
}
