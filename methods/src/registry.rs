//! Methods by name, as the command line and the reports name them.
//!
//! The sample rates a method takes (`--rate`) are listed in one place, [`rates`], derived from
//! the shared pattern's rates ([`crate::pattern::RATES`], capped at
//! [`crate::pattern::MAX_METHOD_RATE`] for the techniques whose masks hold the sub-samples);
//! [`method`] checks a given rate against that list before building anything, so the error
//! lists exactly the rates the method accepts.

use crate::{
    afsm::{AfsmOptions, AliasFreeShadowMap},
    depth_test::{DepthCode, MapOptions},
    method::{MethodError, ShadowMethod},
    pan09::{Pan09, Pan09Options, VisibilityMode},
    pattern::{PatternKind, MAX_METHOD_RATE, RATES},
    pcf_bs::{BrabecSeidelPcf, BsOptions, Variant, DEFAULT_DEPTH_BITS},
    pcf_gems::{GemsPcf, GemsSamples},
    pcf_reeves::{ReevesOptions, ReevesPcf},
    sm::StandardShadowMap,
    spsm::{Spsm, SpsmOptions, TexelFormat},
};

/// Name and one-line description of every available method.
pub const METHODS: &[(&str, &str)] = &[
    ("sm", "standard shadow map: one depth test per pixel centre (Williams 1978)"),
    (
        "pcf-reeves",
        "percentage-closer filtering of the pixel's footprint, N jittered samples (Reeves et al. \
         1987)",
    ),
    ("pcf-bs-2x2", "PCF 2x2 from four jittered maps packed as RGBA, 5 levels (Brabec & Seidel)"),
    (
        "pcf-bs-fast-2x2",
        "fast PCF: one map, each texel packed with its 2x2 neighbourhood (Brabec & Seidel)",
    ),
    ("pcf-bs-fast-4x4", "fast PCF over 4x4 texels in four accumulated passes (Brabec & Seidel)"),
    ("pcf-gems16", "16 bilinear PCF lookups over a 4x4-texel region (GPU Gems ch. 11)"),
    ("pcf-gems4", "4 of the 16 lookups, dithered by screen position (GPU Gems ch. 11)"),
    ("afsm", "alias-free shadow map: pixel centres as sampling points, 2D BSP (Aila & Laine 2004)"),
    ("afsm-ss", "alias-free shadow map at --rate sub-samples per pixel (default 32)"),
    (
        "spsm",
        "sub-pixel shadow map: 128-bit triangle texels, silhouette recovery, AA at uncertain \
         pixels with --rate (Lecocq et al. 2014)",
    ),
    ("spsm-f32", "sub-pixel shadow map with unpacked f32 texels (Lecocq et al. 2014)"),
    (
        "pan09",
        "fast sub-pixel antialiased shadow maps: silhouette mask map, facets, half-plane bitmask \
         lookup table, --rate sub-samples (default 32) (Pan et al. 2009)",
    ),
];

/// Where a method runs (`--device`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Device {
    /// The CPU methods (default).
    #[default]
    Cpu,
    /// The GPU kernels (the `gpu` module, with the `gpu` feature): every method has them
    /// (the references run on the CPU only).
    Gpu,
}

impl Device {
    /// The name, as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Device::Cpu => "cpu",
            Device::Gpu => "gpu",
        }
    }
}

/// Options shared by the methods; `None` takes the method's documented default.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct MethodOptions {
    /// Shadow map resolution (`--map-res`).
    pub map_res: Option<u32>,
    /// Constant depth bias (`--constant-bias`).
    pub constant_bias: Option<f64>,
    /// Slope-scaled depth bias (`--slope-bias`).
    pub slope_bias: Option<f64>,
    /// Bound of the slope ratio (`--max-slope`).
    pub max_slope: Option<f64>,
    /// Sub-samples per pixel (`--rate`), for methods that supersample or sample a filter.
    pub rate: Option<u32>,
    /// Sub-sample pattern (`--pattern`), for methods that supersample.
    pub pattern: Option<PatternKind>,
    /// Bits per stored depth (`--depth-bits`), for depth-as-colour maps.
    pub depth_bits: Option<u32>,
    /// Seed of stochastic sampling (`--seed`).
    pub seed: Option<u64>,
    /// Exponent of the derivative code `x^n` (`--derivative-power`), for packed SPSM texels.
    pub derivative_power: Option<u32>,
    /// How `pan09` turns half-planes into sub-sample masks (`--visibility`).
    pub visibility: Option<VisibilityMode>,
    /// Where the method runs (`--device`); default the CPU.
    pub device: Device,
}

/// The map options given, with `defaults` for those not given; validated.
fn map_options(options: &MethodOptions, d: MapOptions) -> Result<MapOptions, MethodError> {
    let o = MapOptions {
        map_res: options.map_res.unwrap_or(d.map_res),
        constant_bias: options.constant_bias.unwrap_or(d.constant_bias),
        slope_bias: options.slope_bias.unwrap_or(d.slope_bias),
        max_slope: options.max_slope.unwrap_or(d.max_slope),
    };
    o.validate()?;
    Ok(o)
}

/// The sample rates (`--rate`) the method called `name` accepts, or `None` when it takes no
/// rate: `pcf-reeves` every rate of the shared patterns (its jittered footprint samples);
/// the supersampling techniques (`afsm-ss`, `pan09`, `spsm`, `spsm-f32`) those up to
/// [`MAX_METHOD_RATE`], the width of their sub-sample masks.
pub fn rates(name: &str) -> Option<Vec<u32>> {
    let up_to = |max: u32| RATES.iter().copied().filter(|&r| r <= max).collect();
    match name {
        "pcf-reeves" => Some(RATES.to_vec()),
        "afsm-ss" | "pan09" | "spsm" | "spsm-f32" => Some(up_to(MAX_METHOD_RATE)),
        _ => None,
    }
}

/// Sub-samples per pixel the method `name` keeps in memory at once with `options`: the
/// alias-free shadow map's sampling points (`afsm-ss`: its rate, about 35 bytes each); 1 for
/// the others, whose memory grows with the pixels and the map only. For frame size limits.
pub fn stored_samples(name: &str, options: &MethodOptions) -> u32 {
    match name {
        "afsm-ss" => options.rate.unwrap_or(AfsmOptions::supersampled().rate),
        _ => 1,
    }
}

/// Checks `options.rate` against [`rates`]`(name)`; the error lists exactly those rates.
fn check_rate(name: &str, options: &MethodOptions) -> Result<(), MethodError> {
    let (Some(rate), Some(accepted)) = (options.rate, rates(name)) else {
        return Ok(());
    };
    if accepted.contains(&rate) {
        return Ok(());
    }
    Err(MethodError::InvalidOption {
        option: "--rate",
        message: format!(
            "{name} takes {} samples per pixel, got {rate}",
            accepted.iter().map(u32::to_string).collect::<Vec<_>>().join(", ")
        ),
    })
}

/// The method called `name`, configured by `options` and validated, on `options.device`.
pub fn method(name: &str, options: &MethodOptions) -> Result<Box<dyn ShadowMethod>, MethodError> {
    check_rate(name, options)?;
    let cpu = cpu_method(name, options)?;
    let method = match options.device {
        Device::Cpu => cpu,
        Device::Gpu => gpu_method(name, options)?,
    };
    #[cfg(feature = "slowdown")]
    let method = crate::slowdown::wrap(name, method)?;
    Ok(method)
}

/// The GPU kernels of `name`, configured as [`cpu_method`] configures its twin.
#[cfg(feature = "gpu")]
fn gpu_method(name: &str, options: &MethodOptions) -> Result<Box<dyn ShadowMethod>, MethodError> {
    use crate::gpu::{pcf::GpuPcf, sm::GpuShadowMap};
    let map = || map_options(options, MapOptions::default());
    let bs = |variant: Variant| -> Result<Box<dyn ShadowMethod>, MethodError> {
        Ok(Box::new(GpuPcf::BrabecSeidel { options: bs_options(options)?, variant }))
    };
    let gems = |samples: GemsSamples| -> Result<Box<dyn ShadowMethod>, MethodError> {
        Ok(Box::new(GpuPcf::Gems { options: map()?, samples }))
    };
    match name {
        "sm" => Ok(Box::new(GpuShadowMap { options: map()? })),
        "pcf-reeves" => Ok(Box::new(GpuPcf::Reeves { options: reeves_options(options)? })),
        "pcf-bs-2x2" => bs(Variant::Stratified2x2),
        "pcf-bs-fast-2x2" => bs(Variant::Fast2x2),
        "pcf-bs-fast-4x4" => bs(Variant::Fast4x4),
        "pcf-gems16" => gems(GemsSamples::Sixteen),
        "pcf-gems4" => gems(GemsSamples::FourDithered),
        "afsm" => Ok(Box::new(crate::gpu::afsm::GpuAfsm { options: AfsmOptions::default() })),
        "afsm-ss" => {
            Ok(Box::new(crate::gpu::afsm_ss::GpuAfsmSs { options: afsm_ss_options(options) }))
        }
        "pan09" => Ok(Box::new(crate::gpu::pan09::GpuPan09::new(pan09_options(options)?)?)),
        "spsm" | "spsm-f32" => {
            Ok(Box::new(crate::gpu::spsm::GpuSpsm { options: spsm_options(name, options)? }))
        }
        // `method` has checked the name with the CPU twin's registry.
        _ => Err(MethodError::InvalidOption {
            option: "--method",
            message: format!("unknown method `{name}`"),
        }),
    }
}

/// `afsm-ss`'s options from the shared ones (validated by the method).
fn afsm_ss_options(options: &MethodOptions) -> AfsmOptions {
    let d = AfsmOptions::supersampled();
    AfsmOptions {
        rate: options.rate.unwrap_or(d.rate),
        pattern: options.pattern.unwrap_or(d.pattern),
        ..d
    }
}

/// Reeves et al.'s options from the shared ones, validated.
fn reeves_options(options: &MethodOptions) -> Result<ReevesOptions, MethodError> {
    let d = ReevesOptions::default();
    let o = ReevesOptions {
        map: map_options(options, d.map)?,
        samples: options.rate.unwrap_or(d.samples),
        seed: options.seed.unwrap_or(d.seed),
    };
    o.validate()?;
    Ok(o)
}

/// Lecocq et al.'s options for `spsm` or `spsm-f32` from the shared ones, validated.
fn spsm_options(name: &str, options: &MethodOptions) -> Result<SpsmOptions, MethodError> {
    let d = SpsmOptions::default();
    let o = SpsmOptions {
        map: map_options(options, d.map)?,
        texel: if name == "spsm" { TexelFormat::Packed } else { TexelFormat::F32 },
        derivative_power: options.derivative_power.unwrap_or(d.derivative_power),
        rate: options.rate.unwrap_or(d.rate),
        pattern: options.pattern.unwrap_or(d.pattern),
    };
    o.validate()?;
    Ok(o)
}

/// Pan et al.'s options from the shared ones.
fn pan09_options(options: &MethodOptions) -> Result<Pan09Options, MethodError> {
    let d = Pan09Options::default();
    Ok(Pan09Options {
        map: map_options(options, d.map)?,
        rate: options.rate.unwrap_or(d.rate),
        pattern: options.pattern.unwrap_or(d.pattern),
        visibility: options.visibility.unwrap_or(d.visibility),
    })
}

/// Brabec and Seidel's options from the shared ones, validated.
fn bs_options(options: &MethodOptions) -> Result<BsOptions, MethodError> {
    let depth_bits = options.depth_bits.unwrap_or(DEFAULT_DEPTH_BITS);
    // The bits first: the default constant bias is derived from them.
    DepthCode::new(depth_bits, 0.0, 1.0)?;
    let d = BsOptions::with_depth_bits(depth_bits);
    let o = BsOptions { map: map_options(options, d.map)?, depth_bits };
    o.validate()?;
    Ok(o)
}

/// Whether this build has the GPU kernels (the `gpu` feature).
pub const HAS_GPU: bool = cfg!(feature = "gpu");

/// The GPU adapter's name, when this build has GPU kernels and an adapter is found.
pub fn gpu_adapter_name() -> Option<String> {
    #[cfg(feature = "gpu")]
    {
        crate::gpu::GpuContext::shared().ok().map(|c| c.adapter_name())
    }
    #[cfg(not(feature = "gpu"))]
    {
        None
    }
}

/// `--device gpu` in a build without the GPU kernels.
#[cfg(not(feature = "gpu"))]
fn gpu_method(name: &str, _options: &MethodOptions) -> Result<Box<dyn ShadowMethod>, MethodError> {
    Err(MethodError::InvalidOption {
        option: "--device",
        message: format!(
            "`{name}` on the GPU: this build has no GPU kernels (built without the `gpu` \
             feature; rebuild with default features)"
        ),
    })
}

/// The CPU method called `name`, configured by `options` and validated.
fn cpu_method(name: &str, options: &MethodOptions) -> Result<Box<dyn ShadowMethod>, MethodError> {
    let bs = |variant: Variant| -> Result<Box<dyn ShadowMethod>, MethodError> {
        Ok(Box::new(BrabecSeidelPcf { options: bs_options(options)?, variant }))
    };
    let gems = |samples: GemsSamples| -> Result<Box<dyn ShadowMethod>, MethodError> {
        Ok(Box::new(GemsPcf { options: map_options(options, MapOptions::default())?, samples }))
    };
    match name {
        "sm" => Ok(Box::new(StandardShadowMap {
            options: map_options(options, MapOptions::default())?,
        })),
        "pcf-reeves" => Ok(Box::new(ReevesPcf { options: reeves_options(options)? })),
        "pcf-bs-2x2" => bs(Variant::Stratified2x2),
        "pcf-bs-fast-2x2" => bs(Variant::Fast2x2),
        "pcf-bs-fast-4x4" => bs(Variant::Fast4x4),
        "pcf-gems16" => gems(GemsSamples::Sixteen),
        "pcf-gems4" => gems(GemsSamples::FourDithered),
        "afsm" => {
            let m = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
            m.validate()?;
            Ok(Box::new(m))
        }
        "afsm-ss" => {
            let m = AliasFreeShadowMap::supersampled(afsm_ss_options(options));
            m.validate()?;
            Ok(Box::new(m))
        }
        "spsm" | "spsm-f32" => Ok(Box::new(Spsm { options: spsm_options(name, options)? })),
        "pan09" => Ok(Box::new(Pan09::new(pan09_options(options)?)?)),
        _ => Err(MethodError::InvalidOption {
            option: "--method",
            message: format!(
                "unknown method `{name}`; available: {}",
                METHODS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rate builds a method exactly when [`rates`] lists it, and the error for any other
    /// rate lists exactly those rates: the list and the methods' own validation agree.
    #[test]
    fn rates_are_exactly_what_each_method_accepts() {
        let tried: Vec<u32> = (0..=1100).chain([2048, 4096, 1_000_000, u32::MAX]).collect();
        for (name, _) in METHODS {
            let Some(accepted) = rates(name) else {
                continue;
            };
            let listed = accepted.iter().map(u32::to_string).collect::<Vec<_>>().join(", ");
            for &rate in &tried {
                let built = method(name, &MethodOptions { rate: Some(rate), ..Default::default() });
                match built {
                    Ok(_) => assert!(accepted.contains(&rate), "{name} built at rate {rate}"),
                    Err(e) => {
                        assert!(!accepted.contains(&rate), "{name} refused rate {rate}: {e}");
                        let text = e.to_string();
                        assert!(text.starts_with("--rate: "), "{name} at {rate}: {text}");
                        assert!(
                            text.contains(&format!("takes {listed} samples")),
                            "{name} at {rate}: {text}"
                        );
                    }
                }
            }
        }
        assert_eq!(rates("pan09").and_then(|r| r.last().copied()), Some(MAX_METHOD_RATE));
        assert_eq!(rates("sm"), None);
    }

    #[test]
    fn afsm_ss_stores_its_rate_per_pixel() {
        let o = MethodOptions { rate: Some(64), ..Default::default() };
        assert_eq!(stored_samples("afsm-ss", &o), 64);
        assert_eq!(stored_samples("afsm-ss", &MethodOptions::default()), 32);
        assert_eq!(stored_samples("pan09", &o), 1);
    }

    /// Depth precisions that are not supported are named as such, whatever the default bias
    /// derived from them would have been.
    #[test]
    fn unsupported_depth_bits_name_the_flag() {
        for bits in [0, 16, 33, 1 << 31, 4_000_000_000, u32::MAX] {
            let o = MethodOptions { depth_bits: Some(bits), ..Default::default() };
            let e = method("pcf-bs-fast-2x2", &o).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(e.starts_with("--depth-bits: "), "{bits}: {e}");
        }
    }
}
