//! Method parameters, declared once: each is a [`Param`] (its key in suites and run records,
//! its command-line flag, its help and the kind of value it takes), and each method's entry in
//! the registry's table ([`crate::registry::METHODS`]) lists the parameters it uses. The
//! command line makes one flag per declared parameter, with its help and the methods that use
//! it; a suite's `[[run]]` sweeps any of them as a list; a value given to a method that does
//! not declare the parameter is noted (command line) or refused with its line (suite).
//!
//! The values travel in [`MethodOptions`]: the parameters the published techniques share
//! ([`SHARED`]) have typed fields, read by the techniques' option structs; a parameter a
//! method declares in its own module is held in [`MethodOptions::own`] and read there by its
//! key ([`MethodOptions::count`], [`MethodOptions::real`], [`MethodOptions::choice`]).
//! [`MethodOptions::get`] and [`MethodOptions::set`] reach both by key, for the command line,
//! the suites and the reports.

use crate::{light_fit::LightFit, pan09::VisibilityMode, pattern::PatternKind};
use std::collections::BTreeMap;

/// The kind of value a parameter takes; the method checks its range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A whole number from 0 to 2^32 - 1.
    Count,
    /// A whole number from 0 to 2^64 - 1.
    Seed,
    /// A real number.
    Real,
    /// One of the listed names, each with its help.
    Choice(&'static [(&'static str, &'static str)]),
}

/// A method parameter.
#[derive(Debug, PartialEq, Eq)]
pub struct Param {
    /// Its key in suites and run records (`map_res`).
    pub key: &'static str,
    /// Its command-line flag (`--map-res`).
    pub flag: &'static str,
    /// The name of its value in `--help` (`R`).
    pub value_name: &'static str,
    /// Its help: what it sets, its range and its default (per method where they differ).
    pub help: &'static str,
    /// The values it takes.
    pub kind: Kind,
}

/// A parameter's value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// Of a [`Kind::Count`].
    Count(u32),
    /// Of a [`Kind::Seed`].
    Seed(u64),
    /// Of a [`Kind::Real`].
    Real(f64),
    /// Of a [`Kind::Choice`]: one of its names.
    Choice(&'static str),
}

impl Value {
    /// The value as a run record and a report write it.
    pub fn to_json(self) -> serde_json::Value {
        match self {
            Value::Count(v) => v.into(),
            Value::Seed(v) => v.into(),
            Value::Real(v) => v.into(),
            Value::Choice(v) => v.into(),
        }
    }

    /// The value as text (`512`, `0.5`, `rotated`).
    pub fn text(self) -> String {
        match self {
            Value::Count(v) => v.to_string(),
            Value::Seed(v) => v.to_string(),
            Value::Real(v) => v.to_string(),
            Value::Choice(v) => v.to_owned(),
        }
    }
}

impl Param {
    /// The value `text` stands for (a command-line value); the error says what is allowed.
    pub fn parse(&'static self, text: &str) -> Result<Value, String> {
        let t = text.trim();
        match self.kind {
            Kind::Count => t
                .parse()
                .map(Value::Count)
                .map_err(|_| format!("`{text}` is not a whole number from 0 to {}", u32::MAX)),
            Kind::Seed => t
                .parse()
                .map(Value::Seed)
                .map_err(|_| format!("`{text}` is not a whole number from 0 to {}", u64::MAX)),
            Kind::Real => match t.parse::<f64>() {
                Ok(v) => Ok(Value::Real(v)),
                Err(_) => Err(format!("`{text}` is not a number")),
            },
            Kind::Choice(names) => names
                .iter()
                .find(|(n, _)| *n == t)
                .map(|(n, _)| Value::Choice(n))
                .ok_or_else(|| format!("`{text}` is not one of {}", self.choices())),
        }
    }

    /// The value of an integer in a file (a suite): the error says what is allowed.
    pub fn from_integer(&'static self, v: i64) -> Result<Value, String> {
        match self.kind {
            Kind::Count => u32::try_from(v)
                .map(Value::Count)
                .map_err(|_| format!("{v} is not a whole number from 0 to {}", u32::MAX)),
            Kind::Seed => u64::try_from(v)
                .map(Value::Seed)
                .map_err(|_| format!("{v} is not a whole number from 0 to {}", u64::MAX)),
            Kind::Real => Ok(Value::Real(v as f64)),
            Kind::Choice(_) => Err(format!("{v} is not one of {}", self.choices())),
        }
    }

    /// The value of a floating-point number in a file (a suite).
    pub fn from_float(&'static self, v: f64) -> Result<Value, String> {
        match self.kind {
            Kind::Real => Ok(Value::Real(v)),
            _ => Err(format!("{v} is not {}", self.expected())),
        }
    }

    /// What the parameter takes, in words (`a whole number`, `one of grid, rotated`).
    pub fn expected(&self) -> String {
        match self.kind {
            Kind::Count | Kind::Seed => "a whole number".into(),
            Kind::Real => "a number".into(),
            Kind::Choice(_) => format!("one of {}", self.choices()),
        }
    }

    fn choices(&self) -> String {
        match self.kind {
            Kind::Choice(names) => names.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "),
            _ => String::new(),
        }
    }
}

/// Shadow map resolution.
pub static MAP_RES: Param = Param {
    key: "map_res",
    flag: "--map-res",
    value_name: "R",
    help: "Shadow map resolution R (the map is R x R texels), 1 to 16384; default 1024 (512 for \
           `pan09`, the paper's).",
    kind: Kind::Count,
};

/// Constant depth bias.
pub static CONSTANT_BIAS: Param = Param {
    key: "constant_bias",
    flag: "--constant-bias",
    value_name: "B",
    help: "Constant depth bias as a fraction of the scene's light depth range; default 1e-5 \
           (for `pcf-bs-*`: max(1e-5, 2^(1 - depth bits)), the least valid at that precision).",
    kind: Kind::Real,
};

/// Slope-scaled depth bias.
pub static SLOPE_BIAS: Param = Param {
    key: "slope_bias",
    flag: "--slope-bias",
    value_name: "S",
    help: "Slope-scaled depth bias in units of the receiver's depth change over the farthest \
           texel a method compares against; default 1. Values >= 1 keep lit planes free of \
           shadow acne for every shadow-map method.",
    kind: Kind::Real,
};

/// Bound of the slope ratio.
pub static MAX_SLOPE: Param = Param {
    key: "max_slope",
    flag: "--max-slope",
    value_name: "M",
    help: "Upper bound of the receiver slope ratio used by the slope bias; default 1000 (planes \
           up to 89.94° from the light keep their lit parts lit; beyond, the run records a \
           warning).",
    kind: Kind::Real,
};

/// Sub-samples per pixel.
pub static RATE: Param = Param {
    key: "rate",
    flag: "--rate",
    value_name: "N",
    help: "Sub-samples per pixel for methods that supersample and for `raytrace`: 1, 4, 8, 16, \
           32, 64, 128 (up to 1024 for `raytrace`); default 1 (32 for `afsm-ss`, `pan09` and `ftizb`). \
           For `pcf-reeves`, the jittered samples per pixel footprint (the same values up to \
           1024); default 16. For `spsm`, the sub-samples of uncertain pixels (1: no \
           antialiasing, the default).",
    kind: Kind::Count,
};

/// The sub-sample pattern.
pub static PATTERN: Param = Param {
    key: "pattern",
    flag: "--pattern",
    value_name: "PATTERN",
    help: "Sub-sample pattern, shared by every method at equal rate; default grid.",
    kind: Kind::Choice(&[
        ("grid", "Regular grid, shifted so that one sample is at the pixel centre."),
        ("rotated", "Rotated grid (N-rooks lattice) with one sample at the pixel centre."),
    ]),
};

/// Bits per stored depth of depth-as-colour maps.
pub static DEPTH_BITS: Param = Param {
    key: "depth_bits",
    flag: "--depth-bits",
    value_name: "BITS",
    help: "Bits per stored depth of Brabec & Seidel's depth-as-colour maps: 8, 12, 24 or 32 (the \
           paper's hardware had 8, at best 12); default 32.",
    kind: Kind::Count,
};

/// Seed of stochastic sampling.
pub static SEED: Param = Param {
    key: "seed",
    flag: "--seed",
    value_name: "SEED",
    help: "Seed of stochastic sampling (`pcf-reeves`' jitter); default 0.",
    kind: Kind::Seed,
};

/// Exponent of `spsm`'s derivative code.
pub static DERIVATIVE_POWER: Param = Param {
    key: "derivative_power",
    flag: "--derivative-power",
    value_name: "N",
    help: "Exponent n of the x^n code of `spsm`'s 8-bit depth derivatives, 1 (linear) to 9; \
           default 5.",
    kind: Kind::Count,
};

/// How `pan09` turns half-planes into masks.
pub static MASKS: Param = Param {
    key: "masks",
    flag: "--masks",
    value_name: "MODE",
    help: "How `pan09` turns a blocker's half-planes into sub-sample masks; default table.",
    kind: Kind::Choice(&[
        (
            "table",
            "The paper's precomputed lookup table of quantized half-planes (sub-samples within \
             1/128 pixel of a blocker's edge may flip).",
        ),
        ("exact", "Each half-plane tested against each sub-sample in f64."),
    ]),
};

/// The light frustum a shadow map is rendered through.
pub static FRUSTUM: Param = Param {
    key: "frustum",
    flag: "--frustum",
    value_name: "FIT",
    help: "Light frustum of the shadow map (directional lights; a spot's map is its cone under \
           every choice); default scene.",
    kind: Kind::Choice(&[
        ("scene", "Fitted to the scene's bounds, the same map every frame."),
        (
            "view",
            "Fitted each frame to the light-space rectangle of the camera's visible samples \
             (1 % margin), depth range the scene's: smaller texels, moving with the camera.",
        ),
        (
            "view-snapped",
            "`view` with its size rounded up to a power of two times the scene fit's and its \
             centre snapped to whole texels of a grid anchored at the world origin: a camera \
             motion moves the map by whole texels.",
        ),
    ]),
};

/// The parameters the published techniques share, with typed fields in [`MethodOptions`].
pub static SHARED: &[&Param] = &[
    &MAP_RES,
    &CONSTANT_BIAS,
    &SLOPE_BIAS,
    &MAX_SLOPE,
    &RATE,
    &PATTERN,
    &DEPTH_BITS,
    &SEED,
    &DERIVATIVE_POWER,
    &MASKS,
    &FRUSTUM,
];

/// A method's parameter list: the parameters of a shadow map and its depth test ([`MAP`]:
/// `map_res`, the biases and the light frustum), then the method's others, so that a parameter
/// every shadow-map method shares is added in one place.
macro_rules! map_and {
    ($($other:expr),* $(,)?) => {
        &[
            &$crate::params::MAP_RES,
            &$crate::params::CONSTANT_BIAS,
            &$crate::params::SLOPE_BIAS,
            &$crate::params::MAX_SLOPE,
            &$crate::params::FRUSTUM,
            $($other),*
        ]
    };
}
pub(crate) use map_and;

/// The parameters of a shadow map and its depth test (`map_res`, the biases and the light
/// frustum).
pub static MAP: &[&Param] = map_and!();

/// Where a method runs (`--device`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Device {
    /// The CPU methods (default).
    #[default]
    Cpu,
    /// The GPU kernels (the `gpu` module, with the `gpu` feature), for the methods whose
    /// entry has them (the references run on the CPU only).
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

/// Options given to a method; `None` (or absent from [`MethodOptions::own`]) takes the
/// method's documented default.
#[derive(Debug, Clone, Default, PartialEq)]
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
    /// How `pan09` turns half-planes into sub-sample masks (`--masks`).
    pub visibility: Option<VisibilityMode>,
    /// The light frustum of shadow maps (`--frustum`).
    pub frustum: Option<LightFit>,
    /// The values of parameters methods declare in their own modules, by key.
    pub own: BTreeMap<&'static str, Value>,
    /// Where the method runs (`--device`); default the CPU.
    pub device: Device,
}

impl MethodOptions {
    /// The value given for the parameter `key`, if any.
    pub fn get(&self, key: &str) -> Option<Value> {
        match key {
            "map_res" => self.map_res.map(Value::Count),
            "constant_bias" => self.constant_bias.map(Value::Real),
            "slope_bias" => self.slope_bias.map(Value::Real),
            "max_slope" => self.max_slope.map(Value::Real),
            "rate" => self.rate.map(Value::Count),
            "pattern" => self.pattern.map(|p| Value::Choice(p.name())),
            "depth_bits" => self.depth_bits.map(Value::Count),
            "seed" => self.seed.map(Value::Seed),
            "derivative_power" => self.derivative_power.map(Value::Count),
            "masks" => self.visibility.map(|v| Value::Choice(v.name())),
            "frustum" => self.frustum.map(|f| Value::Choice(f.as_str())),
            _ => self.own.get(key).copied(),
        }
    }

    /// Sets `param` to `value` (a value of its kind, from [`Param::parse`] or a suite).
    pub fn set(&mut self, param: &'static Param, value: Value) {
        match (param.key, value) {
            ("map_res", Value::Count(v)) => self.map_res = Some(v),
            ("constant_bias", Value::Real(v)) => self.constant_bias = Some(v),
            ("slope_bias", Value::Real(v)) => self.slope_bias = Some(v),
            ("max_slope", Value::Real(v)) => self.max_slope = Some(v),
            ("rate", Value::Count(v)) => self.rate = Some(v),
            ("pattern", Value::Choice(v)) => {
                self.pattern =
                    Some(if v == "rotated" { PatternKind::Rotated } else { PatternKind::Grid });
            }
            ("depth_bits", Value::Count(v)) => self.depth_bits = Some(v),
            ("seed", Value::Seed(v)) => self.seed = Some(v),
            ("derivative_power", Value::Count(v)) => self.derivative_power = Some(v),
            ("masks", Value::Choice(v)) => {
                self.visibility =
                    Some(if v == "exact" { VisibilityMode::Exact } else { VisibilityMode::Table });
            }
            ("frustum", Value::Choice(v)) => self.frustum = v.parse().ok(),
            (key, value) => {
                self.own.insert(key, value);
            }
        }
    }

    /// The keys of the parameters given, in [`SHARED`]'s order, then the method's own.
    pub fn given(&self) -> Vec<(&'static str, Value)> {
        let shared = SHARED.iter().filter_map(|p| self.get(p.key).map(|v| (p.key, v)));
        shared.chain(self.own.iter().map(|(k, v)| (*k, *v))).collect()
    }

    /// The method's own whole-number parameter `key`, or `default`.
    pub fn count(&self, key: &str, default: u32) -> u32 {
        match self.own.get(key) {
            Some(Value::Count(v)) => *v,
            _ => default,
        }
    }

    /// The method's own real parameter `key`, or `default`.
    pub fn real(&self, key: &str, default: f64) -> f64 {
        match self.own.get(key) {
            Some(Value::Real(v)) => *v,
            _ => default,
        }
    }

    /// The method's own choice parameter `key`, or `default`.
    pub fn choice(&self, key: &str, default: &'static str) -> &'static str {
        match self.own.get(key) {
            Some(Value::Choice(v)) => v,
            _ => default,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every shared parameter comes back by key as it was set, and a method's own goes to
    /// `own`.
    #[test]
    fn values_come_back_by_key() {
        let mut o = MethodOptions::default();
        let values = [
            (&MAP_RES, "512"),
            (&CONSTANT_BIAS, "0.001"),
            (&SLOPE_BIAS, "2"),
            (&MAX_SLOPE, "10"),
            (&RATE, "16"),
            (&PATTERN, "rotated"),
            (&DEPTH_BITS, "12"),
            (&SEED, "18446744073709551615"),
            (&DERIVATIVE_POWER, "3"),
            (&MASKS, "exact"),
            (&FRUSTUM, "view-snapped"),
        ];
        assert_eq!(values.len(), SHARED.len());
        for (p, text) in values {
            let v = p.parse(text).expect("parses");
            o.set(p, v);
            assert_eq!(o.get(p.key), Some(v), "{}", p.key);
            assert_eq!(v.text(), text, "{}", p.key);
        }
        assert!(o.own.is_empty());
        assert_eq!(o.pattern, Some(PatternKind::Rotated));
        assert_eq!(o.visibility, Some(VisibilityMode::Exact));
        assert_eq!(o.frustum, Some(LightFit::ViewSnapped));
        static OWN: Param = Param {
            key: "width_x",
            flag: "--width-x",
            value_name: "X",
            help: "",
            kind: Kind::Real,
        };
        o.set(&OWN, Value::Real(0.25));
        assert_eq!(o.real("width_x", 1.0), 0.25);
        assert_eq!(o.given().last(), Some(&("width_x", Value::Real(0.25))));
    }

    #[test]
    fn bad_values_say_what_is_allowed() {
        let e = RATE.parse("-4").expect_err("negative");
        assert!(e.contains("whole number"), "{e}");
        let e = PATTERN.parse("spiral").expect_err("unknown");
        assert!(e.contains("grid, rotated"), "{e}");
        assert!(MAP_RES.from_integer(-1).is_err());
        assert!(MAP_RES.from_float(0.5).is_err());
        assert_eq!(SLOPE_BIAS.from_integer(2), Ok(Value::Real(2.0)));
        let e = FRUSTUM.parse("tight").expect_err("unknown");
        assert!(e.contains("scene, view, view-snapped"), "{e}");
    }

    /// `--frustum` lists exactly the light-frustum policies, in their order and by their names.
    #[test]
    fn frustum_choices_are_the_policies() {
        let Kind::Choice(names) = FRUSTUM.kind else { panic!("a choice") };
        let listed: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
        let policies: Vec<&str> = LightFit::ALL.iter().map(|f| f.as_str()).collect();
        assert_eq!(listed, policies);
        for f in LightFit::ALL {
            let mut o = MethodOptions::default();
            o.set(&FRUSTUM, FRUSTUM.parse(f.as_str()).expect("listed"));
            assert_eq!(o.frustum, Some(f));
        }
    }
}
