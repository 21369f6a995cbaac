//! The bytes of a glTF file: the GLB container (spec §4.4), buffers (§3.6.1: the `BIN` chunk,
//! base64 `data:` URIs, relative paths) and the accessors the reader needs (§3.6.2), with every
//! length and offset checked, in `u64`, against the bytes there are.

use super::GltfError;
use std::io::Read;
use std::path::Path;

/// Why the container cannot be read.
pub(super) enum ContainerError {
    Io(std::io::Error),
    Format(String),
}

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at + 4)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The JSON of a `.gltf` or `.glb` (any extension: a GLB is known by its magic), and with
/// `blob` the GLB's `BIN` chunk. Without `blob`, only a GLB's header and JSON chunk are read.
pub(super) fn read_container(
    path: &Path,
    blob: bool,
) -> Result<(Vec<u8>, Option<Vec<u8>>), ContainerError> {
    let mut file = std::fs::File::open(path).map_err(ContainerError::Io)?;
    let size = file.metadata().map_err(ContainerError::Io)?.len();
    let mut head = Vec::with_capacity(20);
    (&mut file).take(20).read_to_end(&mut head).map_err(ContainerError::Io)?;
    if !head.starts_with(GLB_MAGIC) {
        let mut json = head;
        file.read_to_end(&mut json).map_err(ContainerError::Io)?;
        return Ok((json, None));
    }
    let bad = |m: &str| ContainerError::Format(format!("GLB: {m}"));
    let (Some(version), Some(length), Some(json_length), Some(json_type)) =
        (u32_at(&head, 4), u32_at(&head, 8), u32_at(&head, 12), u32_at(&head, 16))
    else {
        return Err(bad("the file ends within its header"));
    };
    if version != 2 {
        return Err(bad(&format!("version {version}, expected 2")));
    }
    if u64::from(length) > size {
        return Err(bad(&format!("the header declares {length} bytes, the file has {size}")));
    }
    if json_type != CHUNK_JSON {
        return Err(bad("the first chunk is not JSON"));
    }
    if 20 + u64::from(json_length) > u64::from(length) {
        return Err(bad(&format!("the JSON chunk of {json_length} bytes overruns the file")));
    }
    let mut json = Vec::new();
    (&mut file).take(u64::from(json_length)).read_to_end(&mut json).map_err(ContainerError::Io)?;
    if !blob {
        return Ok((json, None));
    }
    let rest = u64::from(length) - 20 - u64::from(json_length);
    if rest == 0 {
        return Ok((json, None));
    }
    let mut chunk = Vec::new();
    (&mut file).take(rest).read_to_end(&mut chunk).map_err(ContainerError::Io)?;
    let (Some(bin_length), Some(bin_type)) = (u32_at(&chunk, 0), u32_at(&chunk, 4)) else {
        return Err(bad("a chunk header is cut short"));
    };
    if bin_type != CHUNK_BIN {
        return Err(bad("the second chunk is not BIN"));
    }
    if 8 + u64::from(bin_length) > rest {
        return Err(bad(&format!("the BIN chunk of {bin_length} bytes overruns the file")));
    }
    chunk.truncate(8 + bin_length as usize);
    chunk.drain(..8);
    Ok((json, Some(chunk)))
}

/// Every buffer's bytes, by index.
pub(super) struct Data(Vec<Vec<u8>>);

impl Data {
    /// Loads every buffer of `document`: the `BIN` chunk, a `data:` URI or a file beside
    /// `path`; each must hold at least its declared `byteLength`.
    pub(super) fn load(
        document: &gltf::Document,
        mut blob: Option<Vec<u8>>,
        path: &Path,
    ) -> Result<Self, GltfError> {
        let mut buffers = Vec::with_capacity(document.buffers().len());
        for buffer in document.buffers() {
            let index = buffer.index();
            let fail = |message: String| GltfError::Buffer {
                path: path.to_owned(),
                buffer: index,
                message,
            };
            let bytes = match buffer.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                    fail("refers to the GLB's BIN chunk, which the file lacks".into())
                })?,
                gltf::buffer::Source::Uri(uri) => {
                    if let Some(rest) = uri.strip_prefix("data:") {
                        let Some((_, encoded)) = rest.split_once(";base64,") else {
                            return Err(fail("a data: URI must be base64".into()));
                        };
                        base64(encoded).map_err(fail)?
                    } else if uri.split('/').next().is_some_and(|first| first.contains(':')) {
                        return Err(fail(format!(
                            "the URI {uri} is neither relative nor data: (other schemes are not \
                             read)"
                        )));
                    } else {
                        let relative = percent_decode(uri).map_err(fail)?;
                        let file = path.parent().unwrap_or(Path::new("")).join(relative);
                        match std::fs::read(&file) {
                            Ok(bytes) => bytes,
                            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                                return Err(GltfError::MissingBuffer {
                                    path: path.to_owned(),
                                    buffer: index,
                                    looked: file,
                                });
                            }
                            Err(e) => return Err(fail(format!("{}: {e}", file.display()))),
                        }
                    }
                }
            };
            if bytes.len() < buffer.length() {
                return Err(fail(format!(
                    "holds {} bytes, fewer than its byteLength {}",
                    bytes.len(),
                    buffer.length()
                )));
            }
            buffers.push(bytes);
        }
        Ok(Self(buffers))
    }
}

/// What an accessor must be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Want {
    /// `VEC3` of `FLOAT`, not normalised: three values a vertex.
    Positions,
    /// `SCALAR` of unsigned byte, short or int.
    Indices,
}

/// The accessor's values, checked to be what `want` says and to lie within its buffer view
/// and buffer. The error says what is wrong, for the caller to name mesh, primitive and
/// accessor.
pub(super) fn read_accessor(
    accessor: &gltf::Accessor,
    data: &Data,
    want: Want,
) -> Result<Vec<f64>, String> {
    use gltf::accessor::{DataType, Dimensions};
    let (dimensions, data_type) = (accessor.dimensions(), accessor.data_type());
    let size = match want {
        Want::Positions => {
            if dimensions != Dimensions::Vec3 || data_type != DataType::F32 || accessor.normalized()
            {
                return Err(format!(
                    "is {dimensions:?} of {data_type:?}{}, expected Vec3 of F32",
                    if accessor.normalized() { " normalized" } else { "" }
                ));
            }
            12
        }
        Want::Indices => match (dimensions, data_type) {
            (Dimensions::Scalar, DataType::U8) => 1,
            (Dimensions::Scalar, DataType::U16) => 2,
            (Dimensions::Scalar, DataType::U32) => 4,
            _ => {
                return Err(format!(
                    "is {dimensions:?} of {data_type:?}, expected Scalar of U8, U16 or U32"
                ));
            }
        },
    };
    if accessor.sparse().is_some() {
        return Err("is sparse; sparse accessors are not read".into());
    }
    let Some(view) = accessor.view() else {
        return Err("has no buffer view; such accessors are not read".into());
    };
    let bytes = &data.0[view.buffer().index()];
    let stride = view.stride().unwrap_or(size) as u64;
    if stride < size as u64 {
        return Err(format!("byteStride {stride} is below the element's {size} bytes"));
    }
    let count = accessor.count() as u64;
    let view_end = view.offset() as u64 + view.length() as u64;
    if view_end > bytes.len() as u64 {
        return Err(format!(
            "buffer view {} ends at byte {view_end}, beyond its buffer's {}",
            view.index(),
            bytes.len()
        ));
    }
    let start = view.offset() as u64 + accessor.offset() as u64;
    let end = match count {
        0 => start,
        n => (n - 1)
            .checked_mul(stride)
            .and_then(|s| s.checked_add(start + size as u64))
            .ok_or(format!("count {count} with byteStride {stride} overflows"))?,
    };
    if end > view_end {
        return Err(format!(
            "{count} elements end at byte {end}, beyond buffer view {} (which ends at {view_end})",
            view.index()
        ));
    }
    let components = if want == Want::Positions { 3 } else { 1 };
    let mut values = Vec::with_capacity(count as usize * components);
    for k in 0..count {
        // Within `bytes`, as checked above.
        let at = (start + k * stride) as usize;
        let element = &bytes[at..at + size];
        match size {
            1 => values.push(f64::from(element[0])),
            2 => values.push(f64::from(u16::from_le_bytes([element[0], element[1]]))),
            4 => values.push(f64::from(u32::from_le_bytes([
                element[0], element[1], element[2], element[3],
            ]))),
            _ => values.extend(
                element
                    .chunks_exact(4)
                    .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]]))),
            ),
        }
    }
    Ok(values)
}

/// Decodes standard base64 (RFC 4648 §4), padding optional, nothing else allowed.
fn base64(text: &str) -> Result<Vec<u8>, String> {
    let body = text.trim_end_matches('=');
    if text.len() - body.len() > 2 || body.len() % 4 == 1 {
        return Err("the data: URI is not valid base64".into());
    }
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (i, c) in body.bytes().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => {
                return Err(format!(
                    "the data: URI is not valid base64 (character {} at {i})",
                    char::from(c).escape_default()
                ));
            }
        };
        acc = (acc << 6) | u32::from(v);
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

/// A relative URI's path: `%XX` escapes decoded, the result UTF-8.
fn percent_decode(uri: &str) -> Result<String, String> {
    let bad = || format!("the URI {uri} has a bad percent escape");
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes.get(i + 1..i + 3).ok_or_else(bad)?;
            let hex = std::str::from_utf8(hex).map_err(|_| bad())?;
            out.push(u8::from_str_radix(hex, 16).map_err(|_| bad())?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("the URI {uri} does not decode to UTF-8"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_decodes_with_and_without_padding_and_refuses_the_rest() {
        assert_eq!(base64("").as_deref(), Ok(&b""[..]));
        assert_eq!(base64("TWFu").as_deref(), Ok(&b"Man"[..]));
        assert_eq!(base64("TWE=").as_deref(), Ok(&b"Ma"[..]));
        assert_eq!(base64("TWE").as_deref(), Ok(&b"Ma"[..]));
        assert_eq!(base64("TQ==").as_deref(), Ok(&b"M"[..]));
        assert_eq!(base64("+/8=").as_deref(), Ok(&[0xfb, 0xff][..]));
        for bad in ["T", "TQ===", "TW!u", "TW u"] {
            assert!(base64(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn percent_escapes_decode_and_bad_ones_are_refused() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Ok("a b.bin"));
        assert_eq!(percent_decode("d%C3%A9j%C3%A0.bin").as_deref(), Ok("déjà.bin"));
        for bad in ["a%2", "a%zz", "%FF.bin"] {
            assert!(percent_decode(bad).is_err(), "{bad}");
        }
    }
}
