//! An outside renderer's result, read to be scored like a method's (`compare
//! --visibility`, a suite's `[[external]]` entries): an EXR of the frame's size with one
//! channel, the lit fraction per pixel in [0, 1] ([`read_visibility`]).
//!
//! The channel must be the file's only one and be named one of [`CHANNELS`] (the workbench's
//! own `visibility.exr` writes `Y`); 16- or 32-bit float samples. Values outside [0, 1] and
//! NaN are refused, not clamped: a lit fraction outside [0, 1] is a renderer's bug that a
//! clamp would hide in the metrics.

use methods::Visibility;
use std::path::{Path, PathBuf};

/// The accepted names of the lit fraction's channel (exact, case-sensitive).
pub const CHANNELS: &[&str] = &["Y", "L", "lit", "visibility"];

/// Why an outside result cannot be scored.
#[derive(Debug, thiserror::Error)]
pub enum ExternalError {
    /// The file is not a readable EXR.
    #[error("{path}: cannot read it as an EXR: {message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The image is not the frame's size.
    #[error("{path}: the image is {found_w}x{found_h}, the frame is {width}x{height}")]
    Size {
        /// The file.
        path: PathBuf,
        /// The image's width.
        found_w: usize,
        /// The image's height.
        found_h: usize,
        /// The frame's width.
        width: u32,
        /// The frame's height.
        height: u32,
    },
    /// Not exactly one channel of an accepted name and type.
    #[error(
        "{path}: needs one layer with one f16 or f32 channel named Y, L, lit or visibility; \
         found {found}"
    )]
    Channel {
        /// The file.
        path: PathBuf,
        /// What the file holds.
        found: String,
    },
    /// A value outside [0, 1], or NaN.
    #[error(
        "{path}: pixel ({x}, {y}) (from the top-left) is {value}; a lit fraction must be in \
         [0, 1] ({count} such pixels)"
    )]
    Value {
        /// The file.
        path: PathBuf,
        /// The first bad pixel's column.
        x: usize,
        /// Its row.
        y: usize,
        /// Its value.
        value: f32,
        /// How many pixels are bad.
        count: usize,
    },
}

/// Reads the lit fraction of a `width x height` frame from the EXR at `path` (see the module
/// documentation for what is accepted).
pub fn read_visibility(path: &Path, width: u32, height: u32) -> Result<Visibility, ExternalError> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| ExternalError::Read { path: path.to_owned(), message: e.to_string() })?;
    let describe = || {
        let layers: Vec<String> = image
            .layer_data
            .iter()
            .map(|l| {
                let names: Vec<String> = l
                    .channel_data
                    .list
                    .iter()
                    .map(|c| {
                        let kind = match c.sample_data {
                            FlatSamples::F16(_) => "f16",
                            FlatSamples::F32(_) => "f32",
                            FlatSamples::U32(_) => "u32",
                        };
                        format!("{} ({kind})", c.name)
                    })
                    .collect();
                names.join(", ")
            })
            .collect();
        format!("{} layer(s): {}", layers.len(), layers.join("; "))
    };
    let channel_error = || ExternalError::Channel { path: path.to_owned(), found: describe() };
    let [layer] = image.layer_data.as_slice() else { return Err(channel_error()) };
    let [channel] = layer.channel_data.list.as_slice() else { return Err(channel_error()) };
    let named = CHANNELS.iter().any(|n| channel.name.eq(n));
    let float = matches!(channel.sample_data, FlatSamples::F16(_) | FlatSamples::F32(_));
    if !(named && float) {
        return Err(channel_error());
    }
    let (w, h) = (layer.size.width(), layer.size.height());
    if (w, h) != (width as usize, height as usize) {
        return Err(ExternalError::Size {
            path: path.to_owned(),
            found_w: w,
            found_h: h,
            width,
            height,
        });
    }
    let lit: Vec<f32> = channel.sample_data.values_as_f32().collect();
    let bad = |v: &f32| !(0.0..=1.0).contains(v);
    if let Some(k) = lit.iter().position(bad) {
        return Err(ExternalError::Value {
            path: path.to_owned(),
            x: k % w,
            y: k / w,
            value: lit[k],
            count: lit.iter().filter(|v| bad(v)).count(),
        });
    }
    Ok(Visibility { width, height, lit, transmittance: None })
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::*;

    fn write(path: &Path, name: &str, (w, h): (usize, usize), value: f32) {
        let channels = vec![AnyChannel::new(name, FlatSamples::F32(vec![value; w * h]))];
        let layer = Layer::new(
            (w, h),
            LayerAttributes::default(),
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels.into()),
        );
        Image::from_layer(layer).write().to_file(path).expect("writes");
    }

    #[test]
    fn the_workbench_visibility_reads_back_and_bad_files_are_refused_naming_the_cause() {
        let dir = tempfile::tempdir().expect("tempdir");
        let own = dir.path().join("visibility.exr");
        let lit: Vec<f32> = (0..12).map(|k| k as f32 / 11.0).collect();
        let v = Visibility { width: 4, height: 3, lit, transmittance: None };
        crate::output::write_visibility_exr(&own, &v).expect("writes");
        assert_eq!(read_visibility(&own, 4, 3).expect("reads"), v);

        let e = read_visibility(&own, 5, 3).expect_err("size").to_string();
        assert!(e.contains("4x3") && e.contains("5x3") && e.contains("visibility.exr"), "{e}");

        let rgb = dir.path().join("rgb.exr");
        let t = Visibility { transmittance: Some(vec![[1.0; 3]; 12]), ..v.clone() };
        crate::output::write_visibility_exr(&rgb, &t).expect("writes");
        let e = read_visibility(&rgb, 4, 3).expect_err("channels").to_string();
        assert!(e.contains("rgb.exr") && e.contains("R (f32)"), "{e}");

        let z = dir.path().join("z.exr");
        write(&z, "Z", (4, 3), 0.5);
        assert!(matches!(read_visibility(&z, 4, 3), Err(ExternalError::Channel { .. })));

        for value in [1.5, -0.25, f32::NAN] {
            let p = dir.path().join("bad.exr");
            write(&p, "lit", (4, 3), value);
            let e = read_visibility(&p, 4, 3).expect_err("value");
            assert!(matches!(e, ExternalError::Value { count: 12, x: 0, y: 0, .. }), "{e}");
        }
        let missing = dir.path().join("missing.exr");
        let e = read_visibility(&missing, 4, 3).expect_err("missing").to_string();
        assert!(e.contains("missing.exr"), "{e}");
    }
}
