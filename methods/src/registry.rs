//! Methods by name, as the command line, the suites and the reports name them: one table,
//! [`METHODS`], with an entry per method (name, description, the sample rates it takes, the
//! parameters it uses, its CPU and GPU constructors). A method is added by writing its module
//! and one entry here; its parameters reach `--help`, the command line, the suites, the run
//! records and the reports from the entry (`docs/adding-a-method.md` walks through
//! [`vsm`], which was added that way).
//!
//! The sample rates a method takes (`--rate`) come from its entry's [`Rates`], derived from
//! the shared pattern's rates ([`crate::pattern::RATES`], capped at
//! [`crate::pattern::MAX_METHOD_RATE`] for the techniques whose masks hold the sub-samples);
//! [`method`] checks a given rate against that list before building anything, so the error
//! lists exactly the rates the method accepts.

use crate::{
    afsm::{AfsmOptions, AliasFreeShadowMap},
    depth_test::{DepthCode, MapOptions},
    ftizb::{Ftizb, FtizbOptions},
    method::{MethodError, ShadowMethod},
    pan09::{Pan09, Pan09Options},
    params::{self, Param},
    pattern::{MAX_METHOD_RATE, RATES},
    pcf_bs::{BrabecSeidelPcf, BsOptions, Variant, DEFAULT_DEPTH_BITS},
    pcf_gems::{GemsPcf, GemsSamples},
    pcf_reeves::{ReevesOptions, ReevesPcf},
    sm::StandardShadowMap,
    spsm::{Spsm, SpsmOptions, TexelFormat},
};

pub use crate::params::{Device, MethodOptions};

// Methods added by their module beside this table and their entry in it alone (see
// `docs/adding-a-method.md`).
pub mod esm;
pub mod msm;
pub mod vsm;

/// Builds a method from the options given (validated).
pub type Build = fn(&MethodOptions) -> Result<Box<dyn ShadowMethod>, MethodError>;

/// The sub-sample rates (`--rate`) a method takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rates {
    /// It takes no rate.
    None,
    /// Every rate of the shared patterns ([`RATES`]).
    All,
    /// Those up to [`MAX_METHOD_RATE`], the width of its sub-sample masks.
    Masks,
}

/// Which techniques a method belongs with: the reports compare today's techniques with the
/// published ones the workbench began with in a section of their own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// The 2001-2014 techniques of the papers the workbench began with (shadow maps, the
    /// percentage-closer filters, alias-free shadow maps, Pan et al.'s and Lecocq et al.'s
    /// sub-pixel maps) and their variants.
    Seed,
    /// A technique today's shadow papers compare against: the filtered maps (variance,
    /// exponential, moment shadow maps) and the frustum-traced irregular z-buffer.
    Today,
}

/// A method's entry in the table.
pub struct MethodEntry {
    /// Its name, as on the command line.
    pub name: &'static str,
    /// One line on what it is, with its paper.
    pub description: &'static str,
    /// Which techniques it belongs with in the reports.
    pub family: Family,
    /// The rates it takes.
    pub rates: Rates,
    /// The parameters it uses (`rate` among them when it takes rates).
    pub params: &'static [&'static Param],
    /// When it keeps every sub-sample of the frame in memory at once: its default rate (for
    /// frame size limits, [`stored_samples`]).
    pub stores_samples: Option<u32>,
    /// Its CPU constructor.
    pub cpu: Build,
    /// Its GPU constructor, when it has GPU kernels (and this build has the `gpu` feature).
    pub gpu: Option<Build>,
}

/// `Some(constructor)` in a build with the GPU kernels, `None` without.
macro_rules! gpu {
    ($build:expr) => {{
        #[cfg(feature = "gpu")]
        let build: Option<Build> = Some($build);
        #[cfg(not(feature = "gpu"))]
        let build: Option<Build> = None;
        build
    }};
}
pub(crate) use gpu;

/// The parameters of `afsm-ss`, `pan09` and `spsm-f32`'s sub-samples.
static SUPERSAMPLED: &[&Param] = &[&params::RATE, &params::PATTERN];

/// Every method, in the order the command line and the reports list them.
pub static METHODS: &[MethodEntry] = &[
    MethodEntry {
        name: "sm",
        description: "standard shadow map: one depth test per pixel centre (Williams 1978)",
        family: Family::Seed,
        rates: Rates::None,
        params: params::MAP,
        stores_samples: None,
        cpu: |o| Ok(Box::new(StandardShadowMap { options: map(o)? })),
        gpu: gpu!(|o| Ok(Box::new(crate::gpu::sm::GpuShadowMap { options: map(o)? }))),
    },
    MethodEntry {
        name: "pcf-reeves",
        description: "percentage-closer filtering of the pixel's footprint, N jittered samples \
                      (Reeves et al. 1987)",
        family: Family::Seed,
        rates: Rates::All,
        params: params::map_and![&params::RATE, &params::SEED],
        stores_samples: None,
        cpu: |o| Ok(Box::new(ReevesPcf { options: reeves_options(o)? })),
        gpu: gpu!(|o| Ok(Box::new(crate::gpu::pcf::GpuPcf::Reeves {
            options: reeves_options(o)?
        }))),
    },
    MethodEntry {
        name: "pcf-bs-2x2",
        description: "PCF 2x2 from four jittered maps packed as RGBA, 5 levels (Brabec & Seidel)",
        family: Family::Seed,
        rates: Rates::None,
        params: BS,
        stores_samples: None,
        cpu: |o| bs(o, Variant::Stratified2x2),
        gpu: gpu!(|o| gpu_bs(o, Variant::Stratified2x2)),
    },
    MethodEntry {
        name: "pcf-bs-fast-2x2",
        description: "fast PCF: one map, each texel packed with its 2x2 neighbourhood (Brabec & \
                      Seidel)",
        family: Family::Seed,
        rates: Rates::None,
        params: BS,
        stores_samples: None,
        cpu: |o| bs(o, Variant::Fast2x2),
        gpu: gpu!(|o| gpu_bs(o, Variant::Fast2x2)),
    },
    MethodEntry {
        name: "pcf-bs-fast-4x4",
        description: "fast PCF over 4x4 texels in four accumulated passes (Brabec & Seidel)",
        family: Family::Seed,
        rates: Rates::None,
        params: BS,
        stores_samples: None,
        cpu: |o| bs(o, Variant::Fast4x4),
        gpu: gpu!(|o| gpu_bs(o, Variant::Fast4x4)),
    },
    MethodEntry {
        name: "pcf-gems16",
        description: "16 bilinear PCF lookups over a 4x4-texel region (GPU Gems ch. 11)",
        family: Family::Seed,
        rates: Rates::None,
        params: params::MAP,
        stores_samples: None,
        cpu: |o| Ok(Box::new(GemsPcf { options: map(o)?, samples: GemsSamples::Sixteen })),
        gpu: gpu!(|o| gpu_gems(o, GemsSamples::Sixteen)),
    },
    MethodEntry {
        name: "pcf-gems4",
        description: "4 of the 16 lookups, dithered by screen position (GPU Gems ch. 11)",
        family: Family::Seed,
        rates: Rates::None,
        params: params::MAP,
        stores_samples: None,
        cpu: |o| Ok(Box::new(GemsPcf { options: map(o)?, samples: GemsSamples::FourDithered })),
        gpu: gpu!(|o| gpu_gems(o, GemsSamples::FourDithered)),
    },
    MethodEntry {
        name: "afsm",
        description: "alias-free shadow map: pixel centres as sampling points, 2D BSP (Aila & \
                      Laine 2004)",
        family: Family::Seed,
        rates: Rates::None,
        params: &[],
        stores_samples: None,
        cpu: |_| {
            let m = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
            m.validate()?;
            Ok(Box::new(m))
        },
        gpu: gpu!(|_| Ok(Box::new(crate::gpu::afsm::GpuAfsm { options: AfsmOptions::default() }))),
    },
    MethodEntry {
        name: "afsm-ss",
        description: "alias-free shadow map at --rate sub-samples per pixel (default 32)",
        family: Family::Seed,
        rates: Rates::Masks,
        params: SUPERSAMPLED,
        stores_samples: Some(32),
        cpu: |o| {
            let m = AliasFreeShadowMap::supersampled(afsm_ss_options(o));
            m.validate()?;
            Ok(Box::new(m))
        },
        gpu: gpu!(|o| Ok(Box::new(crate::gpu::afsm_ss::GpuAfsmSs { options: afsm_ss_options(o) }))),
    },
    MethodEntry {
        name: "spsm",
        description: "sub-pixel shadow map: 128-bit triangle texels, silhouette recovery, AA at \
                      uncertain pixels with --rate (Lecocq et al. 2014)",
        family: Family::Seed,
        rates: Rates::Masks,
        params: &[
            &params::MAP_RES,
            &params::CONSTANT_BIAS,
            &params::FRUSTUM,
            &params::DERIVATIVE_POWER,
            &params::RATE,
            &params::PATTERN,
        ],
        stores_samples: None,
        cpu: |o| Ok(Box::new(Spsm { options: spsm_options(TexelFormat::Packed, o)? })),
        gpu: gpu!(|o| Ok(Box::new(crate::gpu::spsm::GpuSpsm {
            options: spsm_options(TexelFormat::Packed, o)?
        }))),
    },
    MethodEntry {
        name: "spsm-f32",
        description: "sub-pixel shadow map with unpacked f32 texels (Lecocq et al. 2014)",
        family: Family::Seed,
        rates: Rates::Masks,
        params: &[
            &params::MAP_RES,
            &params::CONSTANT_BIAS,
            &params::FRUSTUM,
            &params::RATE,
            &params::PATTERN,
        ],
        stores_samples: None,
        cpu: |o| Ok(Box::new(Spsm { options: spsm_options(TexelFormat::F32, o)? })),
        gpu: gpu!(|o| Ok(Box::new(crate::gpu::spsm::GpuSpsm {
            options: spsm_options(TexelFormat::F32, o)?
        }))),
    },
    MethodEntry {
        name: "pan09",
        description: "fast sub-pixel antialiased shadow maps: silhouette mask map, facets, \
                      half-plane bitmask lookup table, --rate sub-samples (default 32) (Pan et \
                      al. 2009)",
        family: Family::Seed,
        rates: Rates::Masks,
        params: params::map_and![&params::RATE, &params::PATTERN, &params::MASKS],
        stores_samples: None,
        cpu: |o| Ok(Box::new(Pan09::new(pan09_options(o)?)?)),
        gpu: gpu!(|o| Ok(Box::new(crate::gpu::pan09::GpuPan09::new(pan09_options(o)?)?))),
    },
    MethodEntry {
        name: "ftizb",
        description: "frustum-traced irregular z-buffer: pixel footprints on their tangent \
                      planes in a light-space grid, casters rasterized conservatively, each \
                      pair's --rate sub-samples (default 32) tested exactly (Wyman et al. 2015)",
        family: Family::Today,
        rates: Rates::Masks,
        params: &[&params::RATE, &params::PATTERN, &IZB_RES],
        stores_samples: None,
        cpu: |o| Ok(Box::new(Ftizb { options: ftizb_options(o)? })),
        gpu: gpu!(|o| Ok(Box::new(crate::gpu::ftizb::GpuFtizb { options: ftizb_options(o)? }))),
    },
    vsm::ENTRY,
    esm::ENTRY,
    msm::ENTRY,
];

/// The light-space grid of `ftizb`.
pub static IZB_RES: Param = Param {
    key: "izb_res",
    flag: "--izb-res",
    value_name: "N",
    help: "Texels per side of `ftizb`'s light-space grid, 1 to 4096; 0 (the default): the \
           frame's larger side. Changes the cost, never the result.",
    kind: params::Kind::Count,
};

/// `ftizb`'s options from the shared ones, validated.
fn ftizb_options(options: &MethodOptions) -> Result<FtizbOptions, MethodError> {
    let d = FtizbOptions::default();
    let o = FtizbOptions {
        rate: options.rate.unwrap_or(d.rate),
        pattern: options.pattern.unwrap_or(d.pattern),
        izb_res: options.count(IZB_RES.key, d.izb_res),
        ..d
    };
    o.validate()?;
    Ok(o)
}

/// The parameters of Brabec and Seidel's methods.
static BS: &[&Param] = params::map_and![&params::DEPTH_BITS];

/// The entry of the method called `name`.
pub fn entry(name: &str) -> Option<&'static MethodEntry> {
    METHODS.iter().find(|m| m.name == name)
}

/// Every parameter some method declares, each once, in the table's order.
pub fn all_params() -> Vec<&'static Param> {
    let mut out: Vec<&'static Param> = Vec::new();
    for p in METHODS.iter().flat_map(|m| m.params.iter().copied()) {
        if !out.iter().any(|q| q.key == p.key) {
            out.push(p);
        }
    }
    out
}

/// The map options given, with the defaults for those not given; validated.
pub fn map(options: &MethodOptions) -> Result<MapOptions, MethodError> {
    map_options(options, MapOptions::default())
}

/// The map options given, with `defaults` for those not given; validated.
fn map_options(options: &MethodOptions, d: MapOptions) -> Result<MapOptions, MethodError> {
    let o = MapOptions {
        map_res: options.map_res.unwrap_or(d.map_res),
        constant_bias: options.constant_bias.unwrap_or(d.constant_bias),
        slope_bias: options.slope_bias.unwrap_or(d.slope_bias),
        max_slope: options.max_slope.unwrap_or(d.max_slope),
        frustum: options.frustum.unwrap_or(d.frustum),
    };
    o.validate()?;
    Ok(o)
}

/// The sample rates (`--rate`) the method called `name` accepts, or `None` when it takes no
/// rate (or there is no such method): see [`Rates`].
pub fn rates(name: &str) -> Option<Vec<u32>> {
    match entry(name)?.rates {
        Rates::None => None,
        Rates::All => Some(RATES.to_vec()),
        Rates::Masks => Some(RATES.iter().copied().filter(|&r| r <= MAX_METHOD_RATE).collect()),
    }
}

/// Sub-samples per pixel the method `name` keeps in memory at once with `options`: its rate
/// for a method that stores every sub-sample (`afsm-ss`: its sampling points, about 35 bytes
/// each); 1 for the others, whose memory grows with the pixels and the map only. For frame
/// size limits.
pub fn stored_samples(name: &str, options: &MethodOptions) -> u32 {
    match entry(name).and_then(|m| m.stores_samples) {
        Some(default) => options.rate.unwrap_or(default),
        None => 1,
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
/// The CPU method is built first in either case, so that a GPU run's options are checked
/// by its twin's rules.
pub fn method(name: &str, options: &MethodOptions) -> Result<Box<dyn ShadowMethod>, MethodError> {
    let Some(m) = entry(name) else {
        return Err(MethodError::InvalidOption {
            option: "--method",
            message: format!(
                "unknown method `{name}`; available: {}",
                METHODS.iter().map(|m| m.name).collect::<Vec<_>>().join(", ")
            ),
        });
    };
    check_rate(name, options)?;
    let cpu = (m.cpu)(options)?;
    let method = match options.device {
        Device::Cpu => cpu,
        Device::Gpu => match m.gpu {
            Some(gpu) => gpu(options)?,
            None => return Err(no_gpu(name)),
        },
    };
    #[cfg(feature = "slowdown")]
    let method = crate::slowdown::wrap(name, method)?;
    Ok(method)
}

/// `--device gpu` for a method without GPU kernels, or in a build without any.
fn no_gpu(name: &str) -> MethodError {
    let why = if HAS_GPU {
        "it has no GPU kernels"
    } else {
        "this build has no GPU kernels (built without the `gpu` feature; rebuild with default \
         features)"
    };
    MethodError::InvalidOption {
        option: "--device",
        message: format!("`{name}` on the GPU: {why}"),
    }
}

/// Brabec and Seidel's method of `variant` on the CPU.
fn bs(options: &MethodOptions, variant: Variant) -> Result<Box<dyn ShadowMethod>, MethodError> {
    Ok(Box::new(BrabecSeidelPcf { options: bs_options(options)?, variant }))
}

/// Brabec and Seidel's method of `variant` on the GPU.
#[cfg(feature = "gpu")]
fn gpu_bs(options: &MethodOptions, variant: Variant) -> Result<Box<dyn ShadowMethod>, MethodError> {
    Ok(Box::new(crate::gpu::pcf::GpuPcf::BrabecSeidel { options: bs_options(options)?, variant }))
}

/// GPU Gems' PCF with `samples` on the GPU.
#[cfg(feature = "gpu")]
fn gpu_gems(
    options: &MethodOptions,
    samples: GemsSamples,
) -> Result<Box<dyn ShadowMethod>, MethodError> {
    Ok(Box::new(crate::gpu::pcf::GpuPcf::Gems { options: map(options)?, samples }))
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

/// Lecocq et al.'s options with `texel`s from the shared ones, validated.
fn spsm_options(texel: TexelFormat, options: &MethodOptions) -> Result<SpsmOptions, MethodError> {
    let d = SpsmOptions::default();
    let o = SpsmOptions {
        map: map_options(options, d.map)?,
        texel,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A rate builds a method exactly when [`rates`] lists it, and the error for any other
    /// rate lists exactly those rates: the list and the methods' own validation agree.
    #[test]
    fn rates_are_exactly_what_each_method_accepts() {
        let tried: Vec<u32> = (0..=1100).chain([2048, 4096, 1_000_000, u32::MAX]).collect();
        for name in METHODS.iter().map(|m| m.name) {
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

    /// Every key and every flag is declared once (one `Param` per key), and a method declares
    /// exactly the parameters its run record holds among them.
    #[test]
    fn parameters_are_declared_once_and_as_the_methods_use_them() {
        let all = all_params();
        for p in &all {
            for q in METHODS.iter().flat_map(|m| m.params.iter()) {
                if q.key == p.key || q.flag == p.flag {
                    assert!(std::ptr::eq(*p, *q), "`{}` declared twice", p.key);
                }
            }
            assert_eq!(p.flag, format!("--{}", p.key.replace('_', "-")), "{}", p.key);
        }
        for m in METHODS {
            let used = (m.cpu)(&MethodOptions::default()).expect("builds").params();
            for p in m.params {
                assert!(
                    used.contains_key(p.key),
                    "{} declares {} but does not use it",
                    m.name,
                    p.key
                );
            }
            for key in used.keys().filter(|k| all.iter().any(|p| p.key == k.as_str())) {
                assert!(
                    m.params.iter().any(|p| p.key == key.as_str()),
                    "{} uses {key} without declaring it",
                    m.name
                );
            }
            assert_eq!(m.rates == Rates::None, !m.params.contains(&&params::RATE), "{}", m.name);
        }
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
