//! References by name, and references run as methods (so that `render --method exact`
//! writes the same files as any method and `compare` can compare one reference to another).

use crate::{
    exact::ExactCoverage,
    raytrace::RayTrace,
    reference::{Reference, ReferenceError},
};
use instrumentation::Recorder;
use methods::{
    params::{self, Param},
    pattern::{PatternKind, SamplePattern},
    Frame, MethodError, MethodOptions, ShadowMethod, Visibility,
};

/// Name and one-line description of every reference.
pub const REFERENCES: &[(&str, &str)] = &[
    (
        "exact",
        "exact lit area per pixel on every visible surface (polygon union, exact pixel \
         clipping); edge pixels ray traced",
    ),
    ("raytrace", "ray-traced supersampling: one camera and one shadow ray per sub-sample"),
];

/// The parameters a reference run as a method takes: its rate and pattern (`exact`'s for its
/// edge pixels).
pub static REFERENCE_PARAMS: &[&Param] = &[&params::RATE, &params::PATTERN];

/// The parameters the method or reference called `name` uses (its entry's in
/// [`methods::registry::METHODS`], [`REFERENCE_PARAMS`] for a reference), or `None` when there
/// is no such method.
pub fn params_of(name: &str) -> Option<&'static [&'static Param]> {
    if REFERENCES.iter().any(|(n, _)| *n == name) {
        return Some(REFERENCE_PARAMS);
    }
    methods::registry::entry(name).map(|m| m.params)
}

/// Default sub-sample rate of the `raytrace` reference in `compare`.
pub const DEFAULT_REF_RATE: u32 = 256;

/// The reference called `name`; `rate` and `pattern` configure `raytrace`, and `exact`'s
/// reference of its `edge` pixels (`raytrace` at that rate).
pub fn reference(
    name: &str,
    rate: u32,
    pattern: PatternKind,
) -> Result<Box<dyn Reference>, ReferenceError> {
    match name {
        "exact" => Ok(Box::new(ExactCoverage { edge: Some(raytrace(rate, pattern)?) })),
        "raytrace" => Ok(Box::new(raytrace(rate, pattern)?)),
        _ => Err(ReferenceError::InvalidOption {
            option: "--reference",
            message: format!(
                "unknown reference `{name}`; available: {}",
                REFERENCES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ),
        }),
    }
}

/// `raytrace` at `rate` sub-samples of `pattern`.
fn raytrace(rate: u32, pattern: PatternKind) -> Result<RayTrace, ReferenceError> {
    let pattern = SamplePattern::new(rate, pattern).map_err(|e| match e {
        MethodError::InvalidOption { message, .. } => {
            ReferenceError::InvalidOption { option: "--ref-rate", message }
        }
        other => ReferenceError::NotApplicable(other.to_string()),
    })?;
    Ok(RayTrace { pattern })
}

/// A reference run as a method: its lit fraction rounded to `f32`.
pub struct ReferenceMethod(pub Box<dyn Reference>);

impl ShadowMethod for ReferenceMethod {
    fn name(&self) -> &'static str {
        self.0.name()
    }

    fn params(&self) -> serde_json::Map<String, serde_json::Value> {
        self.0.params()
    }

    fn run(&self, frame: &Frame<'_>, rec: &mut Recorder) -> Result<Visibility, MethodError> {
        let image = self.0.evaluate(frame, rec).map_err(|e| match e {
            ReferenceError::InvalidOption { option, message } => {
                MethodError::InvalidOption { option, message }
            }
            ReferenceError::NotApplicable(m) => MethodError::NotApplicable(m),
        })?;
        Ok(image.to_visibility())
    }
}

/// A method or a reference by name: references take `options.rate` and `options.pattern`
/// as their sub-sample rate (default 1) and pattern.
pub fn technique(
    name: &str,
    options: &MethodOptions,
) -> Result<Box<dyn ShadowMethod>, MethodError> {
    if REFERENCES.iter().any(|(n, _)| *n == name) {
        if options.device != methods::registry::Device::Cpu {
            return Err(MethodError::InvalidOption {
                option: "--device",
                message: format!("the reference `{name}` runs on the CPU only"),
            });
        }
        let r = reference(name, options.rate.unwrap_or(1), options.pattern.unwrap_or_default())
            .map_err(|e| match e {
                ReferenceError::InvalidOption { message, .. } => {
                    MethodError::InvalidOption { option: "--rate", message }
                }
                ReferenceError::NotApplicable(m) => MethodError::NotApplicable(m),
            })?;
        return Ok(Box::new(ReferenceMethod(r)));
    }
    methods::method(name, options).map_err(|e| match e {
        MethodError::InvalidOption { option: "--method", message } => MethodError::InvalidOption {
            option: "--method",
            message: format!(
                "{message}; references: {}",
                REFERENCES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ),
        },
        other => other,
    })
}
