//! Suites: which scenes, methods, parameters and frame size a report sweeps, read from a TOML
//! file that a user can copy and edit (`shadowbench report --suite FILE`). The built-in suites
//! live in `reports/suites/` and are compiled in.
//!
//! ```toml
//! name = "quick"
//! description = "every method on small frames"
//! width = 320
//! height = 240
//! warmup = 1        # untimed runs before the timed ones
//! repeats = 3       # timed runs; the report gives median, min and max
//! reference = "auto" # exact where it applies, else raytrace at ref_rate; or "exact", "raytrace"
//! ref_rate = 64
//! scenes = ["plane-square", "cage"]
//!
//! [[run]]
//! method = "pcf-reeves"
//! map_res = [512, 1024]   # each list is swept; a run is every combination
//! rate = [4, 16]
//!
//! [[table]]                  # a paper's table, see `tables`
//! paper = "lecocq-table2"
//! ```
//!
//! Unknown keys and bad values are errors that name the file and the key (and the line,
//! through the TOML parser).

use crate::tables::TableSpec;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A suite could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SuiteError {
    /// The file could not be read.
    #[error("cannot read suite {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The file is not a valid suite (TOML syntax, unknown key, wrong type).
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// The parser's message, with line and key.
        message: String,
    },
    /// A value is out of range.
    #[error("{path}: `{key}`: {message}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// The key.
        key: String,
        /// What is wrong.
        message: String,
    },
}

/// Which reference each scene is measured against.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReferenceChoice {
    /// `exact` where the scene has a planar receiver and no transparency, else `raytrace`.
    #[default]
    Auto,
    /// Always `exact` (scenes where it does not apply are reported as skipped).
    Exact,
    /// Always `raytrace` at `ref_rate`.
    Raytrace,
}

/// One method and the parameter values to sweep; absent lists take the method's default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// Method name (see `shadowbench render --help`).
    pub method: String,
    /// Shadow map resolutions.
    #[serde(default)]
    pub map_res: Vec<u32>,
    /// Sub-sample rates (supersampling methods, `pcf-reeves`' samples).
    #[serde(default)]
    pub rate: Vec<u32>,
    /// Depth precisions (`pcf-bs-*`).
    #[serde(default)]
    pub depth_bits: Vec<u32>,
    /// Devices to run on (`cpu`, `gpu`); default the CPU only. With both, the report shows
    /// CPU and GPU times side by side.
    #[serde(default)]
    pub device: Vec<methods::registry::Device>,
}

/// One panel of an image grid: a method and its parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanelSpec {
    /// Method name.
    pub method: String,
    /// Label; default: the method and its parameters.
    #[serde(default)]
    pub label: Option<String>,
    /// Shadow map resolution.
    #[serde(default)]
    pub map_res: Option<u32>,
    /// Sample rate.
    #[serde(default)]
    pub rate: Option<u32>,
    /// Depth precision.
    #[serde(default)]
    pub depth_bits: Option<u32>,
    /// Show the pixel classes of `spsm` / `spsm-f32` in Lecocq et al.'s Fig. 14 colours
    /// (green: shadowed by the 3x3 neighbourhood, red: silhouette recovery) instead of the
    /// shaded result.
    #[serde(default)]
    pub classes: bool,
}

/// An image grid with a zoomed inset, like the papers' comparison figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    /// Title (name the figure it reproduces).
    pub title: String,
    /// Scene (one of the suite's scenes).
    pub scene: String,
    /// The inset's region as fractions of the frame: `[x, y, width, height]`.
    pub inset: [f64; 4],
    /// The panels, left to right.
    pub panels: Vec<PanelSpec>,
    /// Also show the reference and the last panel's 10x error image (Pan et al. Fig. 8).
    #[serde(default)]
    pub reference: bool,
}

/// A suite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Suite {
    /// Name, shown in the report.
    pub name: String,
    /// One line on what the suite is for.
    #[serde(default)]
    pub description: String,
    /// Frame width; 0 takes each scene's own.
    #[serde(default)]
    pub width: u32,
    /// Frame height; 0 takes each scene's own.
    #[serde(default)]
    pub height: u32,
    /// Untimed runs before the timed ones. Default 1.
    #[serde(default = "one")]
    pub warmup: u32,
    /// Timed runs. Default 3.
    #[serde(default = "three")]
    pub repeats: u32,
    /// Reference choice. Default `auto`.
    #[serde(default)]
    pub reference: ReferenceChoice,
    /// Sub-samples per pixel of the `raytrace` reference. Default 256.
    #[serde(default = "ref_rate")]
    pub ref_rate: u32,
    /// Built-in scene names or scene file paths.
    pub scenes: Vec<String>,
    /// Methods and their sweeps.
    #[serde(rename = "run")]
    pub runs: Vec<RunSpec>,
    /// Image grids.
    #[serde(default, rename = "grid")]
    pub grids: Vec<GridSpec>,
    /// The papers' tables ([`crate::tables`]).
    #[serde(default, rename = "table")]
    pub tables: Vec<TableSpec>,
}

fn one() -> u32 {
    1
}
fn three() -> u32 {
    3
}
fn ref_rate() -> u32 {
    256
}

/// The built-in suites: name and TOML text.
pub const BUILTIN_SUITES: &[(&str, &str)] = &[
    ("quick", include_str!("../suites/quick.toml")),
    ("papers", include_str!("../suites/papers.toml")),
    ("full", include_str!("../suites/full.toml")),
];

impl Suite {
    /// Parses and checks suite `text`, naming `path` in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Self, SuiteError> {
        let suite: Suite = toml::from_str(text)
            .map_err(|e| SuiteError::Parse { path: path.to_owned(), message: e.to_string() })?;
        let invalid = |key: &str, message: String| SuiteError::Invalid {
            path: path.to_owned(),
            key: key.to_owned(),
            message,
        };
        if suite.repeats == 0 {
            return Err(invalid("repeats", "must be at least 1".into()));
        }
        for (key, v) in [("width", suite.width), ("height", suite.height)] {
            if v > 16384 {
                return Err(invalid(key, format!("must be at most 16384, got {v}")));
            }
        }
        if (suite.width == 0) != (suite.height == 0) {
            return Err(invalid("width", "give both width and height, or neither".into()));
        }
        if suite.scenes.is_empty() {
            return Err(invalid("scenes", "must name at least one scene".into()));
        }
        if suite.runs.is_empty() {
            return Err(invalid("run", "must list at least one [[run]]".into()));
        }
        for (k, g) in suite.grids.iter().enumerate() {
            if !suite.scenes.contains(&g.scene) {
                return Err(invalid(
                    &format!("grid[{k}].scene"),
                    format!("`{}` is not one of the suite's scenes", g.scene),
                ));
            }
            if g.panels.is_empty() {
                return Err(invalid(&format!("grid[{k}].panels"), "must not be empty".into()));
            }
            let [x, y, w, h] = g.inset;
            if !((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y) && w > 0.0 && h > 0.0) {
                return Err(invalid(
                    &format!("grid[{k}].inset"),
                    "x and y in [0, 1), width and height > 0 (fractions of the frame)".into(),
                ));
            }
        }
        for (k, t) in suite.tables.iter().enumerate() {
            if (t.width == 0) != (t.height == 0) || t.width > 16384 || t.height > 16384 {
                return Err(invalid(
                    &format!("table[{k}].width"),
                    "give both width and height (at most 16384), or neither".into(),
                ));
            }
        }
        Ok(suite)
    }

    /// A built-in suite by name, or a suite file by path.
    pub fn load(name_or_path: &str) -> Result<Self, SuiteError> {
        if let Some((name, text)) = BUILTIN_SUITES.iter().find(|(n, _)| *n == name_or_path) {
            return Self::parse(text, Path::new(&format!("built-in suite `{name}`")));
        }
        let path = Path::new(name_or_path);
        let text = std::fs::read_to_string(path).map_err(|e| SuiteError::Io {
            path: path.to_owned(),
            message: if e.kind() == std::io::ErrorKind::NotFound {
                format!(
                    "no such file, and not a built-in suite ({})",
                    BUILTIN_SUITES.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
                )
            } else {
                e.to_string()
            },
        })?;
        Self::parse(&text, path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtin_suites_parse() {
        for (name, _) in BUILTIN_SUITES {
            let s = Suite::load(name).expect("built-in parses");
            assert_eq!(&s.name, name);
        }
    }

    #[test]
    fn errors_name_the_key() {
        let p = Path::new("s.toml");
        let base = "name = \"x\"\nscenes = [\"cage\"]\n[[run]]\nmethod = \"sm\"\n";
        let e = Suite::parse(&format!("{base}colour = 3\n"), p).expect_err("unknown key");
        assert!(e.to_string().contains("colour"), "{e}");
        let e = Suite::parse(&format!("repeats = 0\n{base}"), p).expect_err("zero repeats");
        assert!(e.to_string().contains("repeats"), "{e}");
        let e = Suite::parse(&format!("{base}map_res = \"big\"\n"), p).expect_err("bad type");
        assert!(e.to_string().contains("map_res"), "{e}");
        assert!(Suite::parse(base, p).is_ok());
        let grid = "[[grid]]\ntitle = \"g\"\nscene = \"spheres\"\ninset = [0.1, 0.1, 0.2, 0.2]\n\
                    panels = [{ method = \"sm\" }]\n";
        let e = Suite::parse(&format!("{base}{grid}"), p).expect_err("scene not in the suite");
        assert!(e.to_string().contains("grid[0].scene"), "{e}");
        let grid = grid.replace("spheres", "cage").replace("[0.1, 0.1", "[1.5, 0.1");
        let e = Suite::parse(&format!("{base}{grid}"), p).expect_err("inset outside");
        assert!(e.to_string().contains("grid[0].inset"), "{e}");
        let e = Suite::parse(&format!("{base}[[table]]\npaper = \"table-9\"\n"), p)
            .expect_err("unknown table");
        assert!(e.to_string().contains("table-9"), "{e}");
        let e =
            Suite::parse(&format!("{base}[[table]]\npaper = \"lecocq-table2\"\nwidth = 64\n"), p)
                .expect_err("width without height");
        assert!(e.to_string().contains("table[0].width"), "{e}");
        let e = Suite::load("/no/such/suite.toml").expect_err("missing");
        assert!(e.to_string().contains("quick"), "{e}");
    }
}
