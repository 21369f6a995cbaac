//! Methods by name, as the command line and the reports name them.

use crate::{
    afsm::{AfsmOptions, AliasFreeShadowMap},
    method::{MethodError, ShadowMethod},
    pattern::PatternKind,
    sm::{SmOptions, StandardShadowMap},
};

/// Name and one-line description of every available method.
pub const METHODS: &[(&str, &str)] = &[
    ("sm", "standard shadow map: one depth test per pixel centre (Williams 1978)"),
    ("afsm", "alias-free shadow map: pixel centres as sampling points, 2D BSP (Aila & Laine 2004)"),
    ("afsm-ss", "alias-free shadow map at --rate sub-samples per pixel (default 32)"),
];

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
    /// Sub-samples per pixel (`--rate`), for methods that supersample.
    pub rate: Option<u32>,
    /// Sub-sample pattern (`--pattern`), for methods that supersample.
    pub pattern: Option<PatternKind>,
}

/// The method called `name`, configured by `options` and validated.
pub fn method(name: &str, options: &MethodOptions) -> Result<Box<dyn ShadowMethod>, MethodError> {
    match name {
        "sm" => {
            let d = SmOptions::default();
            let o = SmOptions {
                map_res: options.map_res.unwrap_or(d.map_res),
                constant_bias: options.constant_bias.unwrap_or(d.constant_bias),
                slope_bias: options.slope_bias.unwrap_or(d.slope_bias),
                max_slope: options.max_slope.unwrap_or(d.max_slope),
            };
            o.validate()?;
            Ok(Box::new(StandardShadowMap { options: o }))
        }
        "afsm" => {
            let m = AliasFreeShadowMap::pixel_centres(AfsmOptions::default());
            m.validate()?;
            Ok(Box::new(m))
        }
        "afsm-ss" => {
            let d = AfsmOptions::supersampled();
            let o = AfsmOptions {
                rate: options.rate.unwrap_or(d.rate),
                pattern: options.pattern.unwrap_or(d.pattern),
                ..d
            };
            let m = AliasFreeShadowMap::supersampled(o);
            m.validate()?;
            Ok(Box::new(m))
        }
        _ => Err(MethodError::InvalidOption {
            option: "--method",
            message: format!(
                "unknown method `{name}`; available: {}",
                METHODS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ),
        }),
    }
}
