//! Mesh loaders: Wavefront OBJ, OFF and PLY, chosen by the file's extension (`.obj`, `.off`,
//! `.ply`, any case).
//!
//! Every loader returns a validated [`Mesh`] in `f64`: polygons are fan-triangulated
//! (`v0 vk vk+1`), and normals, texture coordinates, colours and materials are ignored. The text
//! formats (OBJ, OFF, the PLY header and ASCII body) accept a leading UTF-8 byte-order mark and
//! lines ended by LF, CRLF or a CR alone (old Mac OS), counted alike in messages. Bad
//! input is a [`LoadError::Parse`] naming the file and, where there is one, the 1-based line
//! (for binary PLY, the element index and byte offset instead); a file that cannot be read is a
//! [`LoadError::Io`]. Non-finite coordinates and out-of-range indices are caught by the parsers
//! so that the error names the line; [`LoadError::Invalid`] is left for what only the whole mesh
//! shows (a file without triangles). No input makes a loader panic.
//!
//! See [`obj`], [`off`] and [`ply`] for what each format accepts.

pub mod obj;
pub mod off;
pub mod ply;

use crate::mesh::{Mesh, MeshError};
use std::fmt;
use std::path::{Path, PathBuf};

/// The mesh file formats the loaders read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// Object File Format (`.off`).
    Off,
    /// Polygon File Format (`.ply`), ASCII or binary.
    Ply,
}

impl MeshFormat {
    /// The format named by `path`'s extension (case-insensitive), if it is one the loaders read.
    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(Self::Obj),
            "off" => Some(Self::Off),
            "ply" => Some(Self::Ply),
            _ => None,
        }
    }
}

/// Why a mesh file could not be loaded. Every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file is malformed.
    #[error("{path}: {}{message}", LinePrefix(*.line))]
    Parse {
        /// The file.
        path: PathBuf,
        /// The 1-based line where the problem is, when the format has lines and the problem is
        /// on one.
        line: Option<usize>,
        /// What is wrong (for binary PLY, with the element index and byte offset).
        message: String,
    },
    /// The file parses but the mesh is unusable (e.g. it has no triangles).
    #[error("{path}: {source}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong with the mesh.
        source: MeshError,
    },
    /// The extension is not one of `.obj`, `.off`, `.ply`.
    #[error("{path}: unsupported mesh format (expected a .obj, .off or .ply file)")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
}

impl LoadError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Io { path, .. }
            | Self::Parse { path, .. }
            | Self::Invalid { path, .. }
            | Self::UnsupportedFormat { path } => path,
        }
    }

    /// The 1-based line the error is on, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            Self::Parse { line, .. } => *line,
            _ => None,
        }
    }
}

/// Formats `line N: ` when a line is known.
struct LinePrefix(Option<usize>);

impl fmt::Display for LinePrefix {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(line) => write!(f, "line {line}: "),
            None => Ok(()),
        }
    }
}

/// A parser's complaint, before the file's path is attached.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Syntax {
    line: Option<usize>,
    message: String,
}

impl Syntax {
    /// A complaint about 1-based line `line`.
    fn at(line: usize, message: impl Into<String>) -> Self {
        Self { line: Some(line), message: message.into() }
    }

    /// A complaint that no single line is to blame for.
    fn whole(message: impl Into<String>) -> Self {
        Self { line: None, message: message.into() }
    }

    fn into_error(self, path: &Path) -> LoadError {
        LoadError::Parse { path: path.to_owned(), line: self.line, message: self.message }
    }
}

/// Loads the mesh in `path`, choosing the format by the extension (case-insensitive `.obj`,
/// `.off`, `.ply`).
pub fn load_mesh(path: &Path) -> Result<Mesh, LoadError> {
    let format = MeshFormat::from_path(path)
        .ok_or_else(|| LoadError::UnsupportedFormat { path: path.to_owned() })?;
    let bytes =
        std::fs::read(path).map_err(|source| LoadError::Io { path: path.to_owned(), source })?;
    load_mesh_from_bytes(&bytes, format, path)
}

/// Loads a mesh of the given format from memory; `name` is the path that errors name.
pub fn load_mesh_from_bytes(
    bytes: &[u8],
    format: MeshFormat,
    name: &Path,
) -> Result<Mesh, LoadError> {
    let parsed = match format {
        MeshFormat::Obj => obj::parse(bytes),
        MeshFormat::Off => off::parse(bytes),
        MeshFormat::Ply => ply::parse(bytes),
    };
    let mesh = parsed.map_err(|e| e.into_error(name))?;
    mesh.validate().map_err(|source| LoadError::Invalid { path: name.to_owned(), source })?;
    Ok(mesh)
}

/// The UTF-8 byte-order mark some editors put at the start of a text file.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// `bytes` without a leading byte-order mark.
fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(BOM).unwrap_or(bytes)
}

/// The text of a text-format file: without a leading byte-order mark, invalid UTF-8 replaced
/// (it can only be in comments or malformed numbers, which are named as such).
fn text(bytes: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(strip_bom(bytes))
}

/// The lines of `text`, each ended by LF, CRLF or a CR alone, without their ends. As with
/// [`str::lines`], a final line end does not start another line.
fn lines(text: &str) -> Lines<'_> {
    Lines { rest: text }
}

/// Iterator of [`lines`].
#[derive(Debug, Clone)]
struct Lines<'a> {
    rest: &'a str,
}

impl<'a> Iterator for Lines<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        if self.rest.is_empty() {
            return None;
        }
        let Some(end) = self.rest.find(['\r', '\n']) else {
            return Some(std::mem::take(&mut self.rest));
        };
        let line = &self.rest[..end];
        let terminator = if self.rest[end..].starts_with("\r\n") { 2 } else { 1 };
        self.rest = &self.rest[end + terminator..];
        Some(line)
    }
}

/// Number of lines in `text` as [`lines`] counts them: the line an unexpected end of file is
/// reported on.
fn last_line(text: &str) -> usize {
    lines(text).count()
}

/// Parses a coordinate, rejecting what is not a number and what is not finite.
fn coordinate(token: &str, line: usize) -> Result<f64, Syntax> {
    let value: f64 =
        token.parse().map_err(|_| Syntax::at(line, format!("malformed number `{token}`")))?;
    if !value.is_finite() {
        return Err(Syntax::at(line, format!("non-finite coordinate `{token}`")));
    }
    Ok(value)
}

/// Appends the fan `v0 vk vk+1` of `polygon` (at least 3 vertices) to `triangles`.
fn fan(polygon: &[u32], triangles: &mut Vec<[u32; 3]>) {
    if let Some((&first, rest)) = polygon.split_first() {
        triangles.extend(rest.windows(2).map(|w| [first, w[0], w[1]]));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_end_with_lf_crlf_or_cr() {
        fn split(text: &str) -> Vec<&str> {
            lines(text).collect()
        }
        assert_eq!(split("a\nb\r\nc\rd"), ["a", "b", "c", "d"]);
        assert_eq!(split("a\r\rb\r\n\nc\n"), ["a", "", "b", "", "c"]);
        assert_eq!(split("a\r"), ["a"]);
        assert!(split("").is_empty());
        assert_eq!(last_line("v 1\rv 2\r\rf 1 2 3\r"), 4);
    }

    #[test]
    fn a_byte_order_mark_is_not_text() {
        assert_eq!(text(b"\xEF\xBB\xBFv 0 0 0"), "v 0 0 0");
        assert_eq!(text(b"v 0 0 0"), "v 0 0 0");
        assert_eq!(strip_bom(b"\xEF\xBB"), b"\xEF\xBB");
    }
}
