//! Mesh loaders: Wavefront OBJ, OFF and PLY, chosen by the file's extension (`.obj`, `.off`,
//! `.ply`, any case); `.gltf` and `.glb` are handed to [`crate::gltf_file`], whose meshes a
//! scene file may take as one object.
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
//! A folder named as a mesh file is [`LoadError::Folder`], not an I/O error.
//!
//! [`triangle_bound`] bounds a file's triangle count from above without loading it: from the
//! counts of the OFF and PLY headers and from the file's size (an OBJ has no header), so that a
//! scene can be refused before it is built. See [`obj`], [`off`] and [`ply`] for what each
//! format accepts and how each bound is made.

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
    /// The path names a folder.
    #[error("{path}: is a folder, not a mesh file")]
    Folder {
        /// The folder.
        path: PathBuf,
    },
    /// The extension is not one of `.obj`, `.off`, `.ply`, `.gltf`, `.glb`.
    #[error("{path}: unsupported mesh format (expected a .obj, .off, .ply, .gltf or .glb file)")]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
    },
    /// A glTF file cannot be read: the glTF error, which names the file and the cause.
    #[error(transparent)]
    Gltf(Box<crate::gltf_file::GltfError>),
}

impl From<crate::gltf_file::GltfError> for LoadError {
    fn from(e: crate::gltf_file::GltfError) -> Self {
        Self::Gltf(Box::new(e))
    }
}

impl LoadError {
    /// The file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            Self::Io { path, .. }
            | Self::Parse { path, .. }
            | Self::Invalid { path, .. }
            | Self::Folder { path }
            | Self::UnsupportedFormat { path } => path,
            Self::Gltf(e) => e.path(),
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

/// Whether `path` names a glTF file (`.gltf`, `.glb`, any case): a scene file of its own,
/// read by [`crate::gltf_file`], which a scene file may also take as one object's mesh.
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Loads the mesh in `path`, choosing the format by the extension (case-insensitive `.obj`,
/// `.off`, `.ply`; `.gltf` and `.glb` give every triangle primitive instanced by their scene, in
/// world space, as one mesh: [`crate::gltf_file::read_mesh`]).
pub fn load_mesh(path: &Path) -> Result<Mesh, LoadError> {
    if is_gltf(path) {
        return Ok(crate::gltf_file::read_mesh(path)?);
    }
    let format = format_of(path)?;
    let bytes =
        std::fs::read(path).map_err(|source| LoadError::Io { path: path.to_owned(), source })?;
    load_mesh_from_bytes(&bytes, format, path)
}

/// An upper bound of the number of triangles [`load_mesh`] makes of `path`, read from the
/// file's size and, for OFF and PLY, its header (the first 64 KiB, or the whole file when its
/// header is longer); nothing else of the file is read. A malformed header is the
/// error loading would give. The bound is exact for a binary PLY of triangles; for text files
/// it is loose, as the size of their numbers is not known.
pub fn triangle_bound(path: &Path) -> Result<u64, LoadError> {
    if is_gltf(path) {
        // Exact: counted from the accessors, without reading a buffer.
        return Ok(crate::gltf_file::mesh_triangles(path)?);
    }
    let format = format_of(path)?;
    let io = |source| LoadError::Io { path: path.to_owned(), source };
    let size = std::fs::metadata(path).map_err(io)?.len();
    let bound = |bytes: &[u8]| match format {
        MeshFormat::Obj => Ok(obj::triangle_bound(size)),
        MeshFormat::Off => off::triangle_bound(bytes, size),
        MeshFormat::Ply => ply::triangle_bound(bytes, size),
    };
    if format == MeshFormat::Obj {
        return bound(&[]).map_err(|e| e.into_error(path));
    }
    let mut prefix = Vec::new();
    let whole = {
        use std::io::Read;
        let file = std::fs::File::open(path).map_err(io)?;
        file.take(PREFIX).read_to_end(&mut prefix).map_err(io)?;
        prefix.len() as u64 == size
    };
    if !whole {
        // Whole lines only, so that no count is cut short; a header that does not fit (an
        // error without a line or on the last line read) is read again from the whole file.
        let end = prefix.iter().rposition(|&b| b == b'\n' || b == b'\r').map_or(0, |n| n + 1);
        match bound(&prefix[..end]) {
            Ok(bound) => return Ok(bound),
            Err(e) if e.line.is_some_and(|line| line < last_line(&text(&prefix[..end]))) => {
                return Err(e.into_error(path));
            }
            Err(_) => prefix = std::fs::read(path).map_err(io)?,
        }
    }
    bound(&prefix).map_err(|e| e.into_error(path))
}

/// How much of a file [`triangle_bound`] reads first: every header in practice.
const PREFIX: u64 = 64 * 1024;

/// The format of `path`, which must not be a folder.
fn format_of(path: &Path) -> Result<MeshFormat, LoadError> {
    if path.is_dir() {
        return Err(LoadError::Folder { path: path.to_owned() });
    }
    MeshFormat::from_path(path)
        .ok_or_else(|| LoadError::UnsupportedFormat { path: path.to_owned() })
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

    /// Writes `bytes` to `dir/name` and returns the triangle bound and the loaded count.
    fn bound_and_count(dir: &Path, name: &str, bytes: &[u8]) -> (u64, u64) {
        let path = dir.join(name);
        std::fs::write(&path, bytes).expect("writes");
        let bound = triangle_bound(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mesh = load_mesh(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        (bound, mesh.triangle_count() as u64)
    }

    /// A PLY header for `vertices` float vertices and `faces` faces with `uchar`-counted `int`
    /// indices.
    fn ply_header(format: &str, vertices: usize, faces: usize) -> String {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\n\
             property float y\nproperty float z\nelement face {faces}\n\
             property list uchar int vertex_indices\nend_header\n"
        )
    }

    /// A fan of `n` triangles: `n + 2` vertices on a circle, as one polygon or as triangles.
    fn fan_points(n: usize) -> Vec<[f64; 3]> {
        (0..n + 2).map(|i| [(i as f64).cos(), (i as f64).sin(), 0.0]).collect()
    }

    #[test]
    fn triangle_bounds_hold_every_format_and_bind_binary_ply_exactly() {
        let dir = tempfile::tempdir().expect("tempdir");
        let dir = dir.path();
        let mut cases: Vec<(String, Vec<u8>)> = vec![
            ("cube.obj".into(), include_bytes!("../../tests/data/cube.obj").to_vec()),
            ("cube.off".into(), include_bytes!("../../tests/data/cube.off").to_vec()),
            ("cube.ply".into(), include_bytes!("../../tests/data/cube.ply").to_vec()),
        ];
        for n in [1, 5, 300] {
            let points = fan_points(n);
            let nv = points.len();
            let xyz: Vec<String> =
                points.iter().map(|p| format!("{} {} {}", p[0], p[1], p[2])).collect();
            let polygon: Vec<String> = (0..nv).map(|i| i.to_string()).collect();
            let one_based: Vec<String> = (1..=nv).map(|i| i.to_string()).collect();
            let triangles: Vec<String> = (1..nv - 1).map(|i| format!("0 {i} {}", i + 1)).collect();
            let obj_v: String = xyz.iter().map(|v| format!("v {v}\n")).collect();
            cases.push((
                format!("polygon{n}.obj"),
                format!("{obj_v}f {}\n", one_based.join(" ")).into(),
            ));
            let off = format!("OFF\n{nv} 1 0\n{}\n{nv} {}\n", xyz.join("\n"), polygon.join(" "));
            cases.push((format!("polygon{n}.off"), off.into()));
            let off = format!(
                "OFF\n{nv} {n} 0\n{}\n{}\n",
                xyz.join("\n"),
                triangles.iter().map(|t| format!("3 {t}")).collect::<Vec<_>>().join("\n")
            );
            cases.push((format!("triangles{n}.off"), off.into()));
            let ply = format!(
                "{}{}\n{nv} {}\n",
                ply_header("ascii", nv, 1),
                xyz.join("\n"),
                polygon.join(" ")
            );
            cases.push((format!("polygon{n}.ply"), ply.into()));
            for (big, format) in [(false, "binary_little_endian"), (true, "binary_big_endian")] {
                let mut ply = ply_header(format, nv, n).into_bytes();
                for p in &points {
                    for c in p {
                        let c = *c as f32;
                        ply.extend(if big { c.to_be_bytes() } else { c.to_le_bytes() });
                    }
                }
                for i in 1..nv as i32 - 1 {
                    ply.push(3);
                    for v in [0, i, i + 1] {
                        ply.extend(if big { v.to_be_bytes() } else { v.to_le_bytes() });
                    }
                }
                let (bound, count) =
                    bound_and_count(dir, &format!("triangles{n}-{format}.ply"), &ply);
                assert_eq!((bound, count), (n as u64, n as u64), "{format}: exact");
            }
        }
        for (name, bytes) in &cases {
            let (bound, count) = bound_and_count(dir, name, bytes);
            assert!(bound >= count, "{name}: bound {bound} below the {count} triangles");
        }
        // The cube's quads: the bounds are loose, but not absurd.
        let (bound, count) = bound_and_count(dir, "cube.off", &cases[1].1);
        assert!(count == 12 && bound < 100, "cube.off: {bound}");
    }

    #[test]
    fn a_header_past_the_first_read_is_found() {
        let dir = tempfile::tempdir().expect("tempdir");
        let comments = "# a long comment\n".repeat(PREFIX as usize / 8);
        let off = format!("{comments}OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        let ply = ply_header("ascii", 3, 1)
            .replace("end_header", &format!("{}end_header", comments.replace('#', "comment")))
            + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        for (name, text) in [("long.off", off), ("long.ply", ply)] {
            let (bound, count) = bound_and_count(dir.path(), name, text.as_bytes());
            assert!(count == 1 && bound >= 1, "{name}: {bound}");
        }
    }

    #[test]
    fn a_bound_names_a_bad_header_and_a_folder_as_loading_does() {
        let dir = tempfile::tempdir().expect("tempdir");
        let bad = dir.path().join("bad.off");
        std::fs::write(&bad, "OFF\n3 many\n").expect("writes");
        let e = triangle_bound(&bad).expect_err("bad counts");
        assert_eq!((e.path(), e.line()), (bad.as_path(), Some(2)), "{e}");
        // In a large file, a header error is named from the first read when lines follow it,
        // from the whole file when none does.
        let lines = dir.path().join("lines.off");
        std::fs::write(&lines, format!("OFF\n3 many\n{}", "0 0 0\n".repeat(20_000)))
            .expect("writes");
        let sparse = dir.path().join("sparse.off");
        let file = std::fs::File::create(&sparse).expect("creates");
        std::io::Write::write_all(&mut &file, b"OFF\n3 many\n").expect("writes");
        file.set_len(1_000_000).expect("a sparse file");
        for large in [lines, sparse] {
            let e = triangle_bound(&large).expect_err("bad counts");
            assert_eq!((e.path(), e.line()), (large.as_path(), Some(2)), "{e}");
        }
        let folder = dir.path().join("folder.obj");
        std::fs::create_dir(&folder).expect("mkdir");
        for e in
            [triangle_bound(&folder).expect_err("folder"), load_mesh(&folder).expect_err("folder")]
        {
            assert!(matches!(e, LoadError::Folder { .. }), "{e}");
            assert!(e.to_string().ends_with("folder.obj: is a folder, not a mesh file"), "{e}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_not_text() {
        assert_eq!(text(b"\xEF\xBB\xBFv 0 0 0"), "v 0 0 0");
        assert_eq!(text(b"v 0 0 0"), "v 0 0 0");
        assert_eq!(strip_bom(b"\xEF\xBB"), b"\xEF\xBB");
    }
}
