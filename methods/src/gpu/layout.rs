//! Rust structs that the kernels read as WGSL structs, checked against the shaders.
//!
//! A `#[repr(C)]` parameter block is uploaded as bytes and read by a WGSL struct of the same
//! fields; nothing but this check ties the two. [`wgsl_mirror!`] names, for one Rust struct, the
//! WGSL struct that mirrors it, the shader source that declares it (as a pipeline composes it)
//! and its fields in order; it adds a test to the struct's module that parses that source with
//! naga (the shader compiler wgpu itself uses) and requires the WGSL struct's size and every
//! member's name, offset and size to be the Rust struct's. A field added, removed, renamed,
//! resized or moved on one side only fails that test (`tests` below shows it failing).
//!
//! The layouts checked: `common::ProjectorData` and `common::Xyz` (`common.wgsl`, every
//! projector the kernels read), `raster::Params` (`raster.wgsl`), `sm::Params`
//! (`receiver.wgsl`, shared by `sm` and the PCF kernels), `filtered::FParams` (`filtered.wgsl`,
//! the filtered shadow maps' kernels), `spsm::texel::Params`
//! (`texel.wgsl`), `spsm::antialias::Record` (`spsm/antialias.wgsl`, a silhouette per
//! uncertain pixel), `spsm::raster::SetupData` (`spsm/setup.wgsl`, a prepared triangle)
//! and `Dims`, `spsm::antialias::Dims`, `spsm::pack::PackParams` (`spsm/pack.wgsl`), `pan09::params::Params` and `PlaneData`
//! (`pan09/params.wgsl`, pan09's per-frame constants), `pan09::facets::FacetF` and `FacetU`
//! (`pan09/facet_layout.wgsl`, a silhouette facet's record), afsm's `FParams`, `UParams`,
//! `BlockerOutline`, `BlockerPlane` and `BlockerU` (`afsm/layout.wgsl`) and
//! `ftizb::TangentParams` (`ftizb/tangent.wgsl`).

/// Declares that the `#[repr(C)]` struct `$ty` is mirrored by the WGSL struct `$name` of the
/// shader source `$source` (an expression giving a `String`), fields `[$field, ...]` in
/// order, and adds the test `wgsl_layout::matches_the_shader` to the calling module. A module
/// with several such structs lists them in one call, separated by `;`; the one test checks
/// each and names every mismatch.
macro_rules! wgsl_mirror {
    ($($ty:ty, $name:literal, $source:expr, [$($field:ident),+ $(,)?]);+ $(;)?) => {
        #[cfg(test)]
        mod wgsl_layout {
            #[allow(unused_imports)]
            use super::*;

            #[test]
            fn matches_the_shader() {
                fn size<S, T>(_: fn(&S) -> &T) -> usize {
                    std::mem::size_of::<T>()
                }
                let mut failures: Vec<String> = Vec::new();
                $(
                    let fields = [$(
                        $crate::gpu::layout::Field {
                            name: stringify!($field),
                            offset: std::mem::offset_of!($ty, $field),
                            size: size::<$ty, _>(|s| &s.$field),
                        },
                    )+];
                    let source: String = $source;
                    let mismatches = $crate::gpu::layout::mismatches(
                        &fields,
                        std::mem::size_of::<$ty>(),
                        &source,
                        $name,
                    );
                    if !mismatches.is_empty() {
                        failures.push(format!(
                            "{} and the WGSL struct {}: {}",
                            stringify!($ty),
                            $name,
                            mismatches.join("; ")
                        ));
                    }
                )+
                assert!(failures.is_empty(), "{}", failures.join("\n"));
            }
        }
    };
}
pub(crate) use wgsl_mirror;

/// One field of a Rust struct: name, byte offset and size.
#[cfg(test)]
#[derive(Debug, Clone, Copy)]
pub(crate) struct Field {
    pub name: &'static str,
    pub offset: usize,
    pub size: usize,
}

/// Where the Rust struct of `fields` (size `size`) and the WGSL struct `name` declared in
/// `source` differ, one line each; empty when they agree.
#[cfg(test)]
pub(crate) fn mismatches(fields: &[Field], size: usize, source: &str, name: &str) -> Vec<String> {
    let module = match naga::front::wgsl::parse_str(source) {
        Ok(m) => m,
        Err(e) => return vec![format!("the shader does not parse: {}", e.emit_to_string(source))],
    };
    let found = module.types.iter().find_map(|(_, t)| match &t.inner {
        naga::TypeInner::Struct { members, span } if t.name.as_deref() == Some(name) => {
            Some((members, *span))
        }
        _ => None,
    });
    let Some((members, span)) = found else {
        return vec![format!("no struct {name} in the shader")];
    };
    let wgsl: Vec<(String, usize, usize)> = members
        .iter()
        .map(|m| {
            let size = module.types[m.ty].inner.size(module.to_ctx());
            (m.name.clone().unwrap_or_default(), m.offset as usize, size as usize)
        })
        .collect();
    let mut out = Vec::new();
    if span as usize != size {
        out.push(format!("size {size} bytes in Rust, {span} in WGSL"));
    }
    for k in 0..fields.len().max(wgsl.len()) {
        match (fields.get(k), wgsl.get(k)) {
            (Some(f), Some((n, offset, size))) => {
                if f.name != n || f.offset != *offset || f.size != *size {
                    out.push(format!(
                        "field {k}: `{}` at {} ({} bytes) in Rust, `{n}` at {offset} ({size} \
                         bytes) in WGSL",
                        f.name, f.offset, f.size
                    ));
                }
            }
            (Some(f), None) => out.push(format!("`{}` is in Rust only", f.name)),
            (None, Some((n, _, _))) => out.push(format!("`{n}` is in WGSL only")),
            (None, None) => {}
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use bytemuck::{Pod, Zeroable};

    #[repr(C)]
    #[derive(Debug, Clone, Copy, Pod, Zeroable)]
    struct Probe {
        scale: f64,
        count: u32,
        pad: u32,
    }

    const PROBE_WGSL: &str = "struct Probe { scale: f64, count: u32, pad: u32, }";

    fn fields() -> Vec<super::Field> {
        let f = |name, offset, size| super::Field { name, offset, size };
        vec![
            f("scale", std::mem::offset_of!(Probe, scale), 8),
            f("count", std::mem::offset_of!(Probe, count), 4),
            f("pad", std::mem::offset_of!(Probe, pad), 4),
        ]
    }

    #[test]
    fn equal_layouts_agree() {
        let m = super::mismatches(&fields(), std::mem::size_of::<Probe>(), PROBE_WGSL, "Probe");
        assert!(m.is_empty(), "{m:?}");
    }

    #[test]
    fn a_field_added_in_wgsl_only_is_found() {
        let wgsl = "struct Probe { scale: f64, count: u32, pad: u32, extra: u32, }";
        let m = super::mismatches(&fields(), std::mem::size_of::<Probe>(), wgsl, "Probe");
        assert!(m.iter().any(|l| l.contains("`extra` is in WGSL only")), "{m:?}");
        assert!(m.iter().any(|l| l.contains("size 16 bytes in Rust, 24 in WGSL")), "{m:?}");
    }

    #[test]
    fn a_field_added_in_rust_only_is_found() {
        let wgsl = "struct Probe { scale: f64, count: u32, }";
        let m = super::mismatches(&fields(), std::mem::size_of::<Probe>(), wgsl, "Probe");
        assert!(m.iter().any(|l| l.contains("`pad` is in Rust only")), "{m:?}");
    }

    #[test]
    fn a_field_moved_or_resized_is_found() {
        let swapped = "struct Probe { scale: f64, pad: u32, count: u32, }";
        let m = super::mismatches(&fields(), std::mem::size_of::<Probe>(), swapped, "Probe");
        assert!(m.iter().any(|l| l.contains("field 1: `count`")), "{m:?}");
        let wider = "struct Probe { scale: f64, count: f64, pad: u32, }";
        let m = super::mismatches(&fields(), std::mem::size_of::<Probe>(), wider, "Probe");
        assert!(m.iter().any(|l| l.contains("(8 bytes) in WGSL")), "{m:?}");
    }

    #[test]
    fn a_missing_struct_or_a_bad_shader_is_said() {
        let m = super::mismatches(&fields(), 16, "struct Other { a: u32, }", "Probe");
        assert_eq!(m, ["no struct Probe in the shader"]);
        let m = super::mismatches(&fields(), 16, "struct Probe {", "Probe");
        assert!(m[0].starts_with("the shader does not parse"), "{m:?}");
    }
}
