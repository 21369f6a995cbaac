//! Mesh loaders: the same cube in every format, binary PLY, every malformed case naming the file
//! and line, no panic on any input, and CGAL's bunny when it has been fetched.

use glam::DVec3;
use proptest::prelude::*;
use proptest::sample::Index;
use scenes::io::{load_mesh, load_mesh_from_bytes, LoadError, MeshFormat};
use scenes::{Mesh, MeshError};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

fn cube() -> Mesh {
    load_mesh(&data("cube.off")).expect("cube.off loads")
}

/// Signed volume enclosed by a closed mesh (positive when its triangles face outwards).
fn volume(mesh: &Mesh) -> f64 {
    (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.corners(t);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// Writes `bytes` as `name` in a fresh temporary folder and loads it.
fn load_as(name: &str, bytes: impl AsRef<[u8]>) -> Result<Mesh, LoadError> {
    let dir = tempfile::tempdir().expect("temporary folder");
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).expect("write");
    load_mesh(&path)
}

/// Loads a malformed file, checks that the message names it and (if given) the line.
fn fails(name: &str, text: impl AsRef<[u8]>, line: Option<usize>) -> String {
    let err = load_as(name, text).expect_err(name);
    let msg = err.to_string();
    assert!(msg.contains(name), "{msg}");
    assert!(!matches!(err, LoadError::Io { .. }), "{msg}");
    assert_eq!(err.line(), line, "{msg}");
    if let Some(line) = line {
        assert!(msg.contains(&format!("line {line}:")), "{msg}");
    }
    msg
}

/// The cube as binary little-endian PLY: positions as float, indices as a uchar/int list, with
/// an extra per-vertex property and an extra element to skip.
fn binary_cube() -> Vec<u8> {
    let mesh = cube();
    let mut bytes = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by the test\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty uchar confidence\n\
         property float z\nelement face {}\nproperty list uchar int vertex_indices\n\
         element note 1\nproperty list ushort char text\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    )
    .into_bytes();
    for p in &mesh.positions {
        bytes.extend((p.x as f32).to_le_bytes());
        bytes.extend((p.y as f32).to_le_bytes());
        bytes.push(200);
        bytes.extend((p.z as f32).to_le_bytes());
    }
    for t in &mesh.triangles {
        bytes.push(3);
        for &v in t {
            bytes.extend((v as i32).to_le_bytes());
        }
    }
    bytes.extend(5u16.to_le_bytes());
    bytes.extend(b"hello");
    bytes
}

#[test]
fn the_cube_is_the_same_in_every_format() {
    let off = cube();
    assert_eq!(off.triangle_count(), 12);
    assert_eq!(off.positions.len(), 8);
    assert!((off.area() - 6.0).abs() < 1e-12);
    assert!((volume(&off) - 1.0).abs() < 1e-12, "faces point outwards");
    for name in ["cube.obj", "cube.ply"] {
        assert_eq!(load_mesh(&data(name)).expect(name), off, "{name}");
    }
}

#[test]
fn quads_are_fan_triangulated() {
    let mesh = cube();
    // Quad `4 0 3 5 4` becomes (0 3 5) and (0 5 4).
    assert_eq!(&mesh.triangles[4..6], &[[0, 3, 5], [0, 5, 4]]);
    let hexagon = "OFF\n6 1 0\n0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 2 0\n-1 1 0\n6 0 1 2 3 4 5\n";
    let mesh = load_mesh_from_bytes(hexagon.as_bytes(), MeshFormat::Off, Path::new("hex.off"))
        .expect("hexagon");
    assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]);
}

#[test]
fn extensions_choose_the_format_in_any_case() {
    let text = std::fs::read(data("cube.off")).expect("read");
    assert_eq!(load_as("CUBE.Off", &text).expect("upper-case extension"), cube());
    assert_eq!(MeshFormat::from_path(Path::new("a/b.PLY")), Some(MeshFormat::Ply));
    assert_eq!(MeshFormat::from_path(Path::new("a/b.obj")), Some(MeshFormat::Obj));
    assert_eq!(MeshFormat::from_path(Path::new("a/off")), None);
}

#[test]
fn binary_little_endian_ply_written_here_loads() {
    let mesh = load_as("cube-binary.ply", binary_cube()).expect("binary cube");
    assert_eq!(mesh, cube());
}

#[test]
fn binary_ply_errors_name_the_element_and_byte() {
    let bytes = binary_cube();
    let body = bytes.windows(11).position(|w| w == b"end_header\n").expect("header") + 11;
    let vertex = 13; // bytes per vertex record
    let face = 13; // bytes per face record

    let end = body + 8 * vertex + 5 * face + 6;
    let msg = fails("truncated.ply", &bytes[..end], None);
    assert!(
        msg.contains("element `face`")
            && msg.contains(&format!("from byte {}", body + 8 * vertex))
            && msg.contains(&format!("ends at byte {end}, after at most 5 of them")),
        "{msg}"
    );
    let msg = fails("no-note.ply", &bytes[..bytes.len() - 3], None);
    assert!(msg.contains("note 0") && msg.contains("truncated"), "{msg}");

    let mut nan = bytes.clone();
    nan[body + 2 * vertex + 4..body + 2 * vertex + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    let msg = fails("nan.ply", &nan, None);
    assert!(msg.contains("vertex 2") && msg.contains("non-finite"), "{msg}");

    let mut out = bytes.clone();
    let last_index = body + 8 * vertex + 11 * face + 9;
    out[last_index..last_index + 4].copy_from_slice(&8i32.to_le_bytes());
    let msg = fails("out-of-range.ply", &out, None);
    assert!(msg.contains("face 11") && msg.contains("vertex index 8 out of range"), "{msg}");

    let mut negative = bytes;
    negative[last_index..last_index + 4].copy_from_slice(&(-1i32).to_le_bytes());
    let msg = fails("negative.ply", &negative, None);
    assert!(msg.contains("face 11") && msg.contains("vertex index -1 out of range"), "{msg}");
}

#[test]
fn missing_files_are_io_errors() {
    let path = Path::new("/nonexistent/shadowbench/missing.obj");
    let err = load_mesh(path).expect_err("missing");
    assert!(matches!(err, LoadError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("missing.obj"), "{err}");
    assert_eq!(err.path(), path);
}

#[test]
fn unsupported_extensions_are_named() {
    for name in ["mesh.stl", "mesh", "mesh.obj.gz"] {
        let err = load_mesh(Path::new(name)).expect_err(name);
        assert!(matches!(err, LoadError::UnsupportedFormat { .. }), "{err:?}");
        assert!(err.to_string().contains(name) && err.to_string().contains("unsupported"), "{err}");
    }
}

#[test]
fn empty_files_name_the_file() {
    fails("empty.off", "", None);
    fails("empty.ply", "", None);
    let err = load_as("empty.obj", "").expect_err("empty obj");
    assert!(matches!(err, LoadError::Invalid { source: MeshError::Empty, .. }), "{err:?}");
    assert!(err.to_string().contains("empty.obj"), "{err}");
    // Vertices but no faces is a valid file without a mesh.
    let err = load_as("points.off", "OFF\n1 0 0\n0 0 0\n").expect_err("no faces");
    assert!(matches!(err, LoadError::Invalid { source: MeshError::Empty, .. }), "{err:?}");
}

const OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const OFF: &str = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
const PLY: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                   property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                   end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

/// `text` with line `line` (1-based) replaced.
fn with_line(text: &str, line: usize, new: &str) -> String {
    let mut lines: Vec<&str> = text.lines().collect();
    lines[line - 1] = new;
    lines.join("\n") + "\n"
}

#[test]
fn the_templates_load() {
    for (name, text) in [("t.obj", OBJ), ("t.off", OFF), ("t.ply", PLY)] {
        assert_eq!(load_as(name, text).expect(name).triangles, vec![[0, 1, 2]], "{name}");
    }
}

#[test]
fn malformed_numbers_name_the_line() {
    let msg = fails("number.obj", with_line(OBJ, 2, "v 1 O 0"), Some(2));
    assert!(msg.contains("malformed number `O`"), "{msg}");
    fails("number.off", with_line(OFF, 4, "1 0 0,5"), Some(4));
    fails("number.ply", with_line(PLY, 11, "1 0 0.0.0"), Some(11));
    fails("count.off", with_line(OFF, 2, "3 one 0"), Some(2));
    fails("count.ply", with_line(PLY, 3, "element vertex three"), Some(3));
    fails("index.obj", with_line(OBJ, 4, "f 1 2 3.0"), Some(4));
    fails("index.off", with_line(OFF, 6, "3 0 1 x"), Some(6));
    fails("index.ply", with_line(PLY, 13, "3 0 1 2.5"), Some(13));
}

#[test]
fn nan_and_inf_name_the_line() {
    for (value, n) in [("nan", 1), ("NaN", 2), ("inf", 3), ("-Infinity", 2), ("1e400", 3)] {
        let line = |x: &str| match n {
            1 => format!("{value} {x} 0"),
            2 => format!("{x} {value} 0"),
            _ => format!("{x} 0 {value}"),
        };
        let msg = fails("nan.obj", with_line(OBJ, 3, &format!("v {}", line("0"))), Some(3));
        assert!(msg.contains("non-finite"), "{msg}");
        fails("nan.off", with_line(OFF, 5, &line("0")), Some(5));
        fails("nan.ply", with_line(PLY, 12, &line("0")), Some(12));
    }
}

#[test]
fn out_of_range_indices_name_the_line() {
    let msg = fails("range.obj", with_line(OBJ, 4, "f 1 2 4"), Some(4));
    assert!(msg.contains("vertex index 4 out of range"), "{msg}");
    let msg = fails("negative.obj", with_line(OBJ, 4, "f 1 2 -4"), Some(4));
    assert!(msg.contains("relative vertex index -4"), "{msg}");
    assert_eq!(
        load_as("relative.obj", with_line(OBJ, 4, "f -3 -2 -1")).expect("relative").triangles,
        vec![[0, 1, 2]]
    );
    fails("zero.obj", with_line(OBJ, 4, "f 0 1 2"), Some(4));
    let msg = fails("range.off", with_line(OFF, 6, "3 0 1 3"), Some(6));
    assert!(msg.contains("vertex index 3 out of range"), "{msg}");
    fails("negative.off", with_line(OFF, 6, "3 0 -1 2"), Some(6));
    let msg = fails("range.ply", with_line(PLY, 13, "3 0 1 3"), Some(13));
    assert!(msg.contains("face 0") && msg.contains("vertex index 3 out of range"), "{msg}");
    fails("negative.ply", with_line(PLY, 13, "3 0 -1 2"), Some(13));
}

#[test]
fn truncated_files_name_the_last_line() {
    let cut =
        |text: &str, lines: usize| text.lines().take(lines).collect::<Vec<_>>().join("\n") + "\n";
    let msg = fails("truncated.off", cut(OFF, 5), Some(5));
    assert!(msg.contains("end of file") && msg.contains("0 of 1 faces"), "{msg}");
    fails("truncated-vertices.off", cut(OFF, 3), Some(3));
    let msg = fails("truncated.ply", cut(PLY, 12), Some(12));
    assert!(msg.contains("end of file"), "{msg}");
    fails("header-only.ply", cut(PLY, 8), Some(8));
    // A vertex line cut in the middle.
    fails("cut-line.off", &OFF[..OFF.find("1 0 0").expect("vertex") + 3], Some(4));
}

#[test]
fn structural_errors_name_the_line() {
    fails("two.off", with_line(OFF, 6, "2 0 1"), Some(6));
    fails("short.off", with_line(OFF, 6, "4 0 1 2"), Some(6));
    fails("two.obj", with_line(OBJ, 4, "f 1 2"), Some(4));
    fails("two.ply", with_line(PLY, 13, "2 0 1"), Some(13));
    fails("no-z.ply", with_line(PLY, 6, "property float w"), Some(3));
    let no_face = PLY.replace("element face 1\nproperty list uchar int vertex_indices\n", "");
    let msg = fails("no-face.ply", no_face, Some(7));
    assert!(msg.contains("no `face` element"), "{msg}");
    fails("magic.ply", with_line(PLY, 1, "ply2"), Some(1));
    fails("header.off", with_line(OFF, 1, "OFFF"), Some(1));
}

/// `text` with a byte-order mark (if `bom`) and every LF replaced by `end`.
fn recode(text: &str, bom: bool, end: &str) -> Vec<u8> {
    let mut bytes = if bom { b"\xEF\xBB\xBF".to_vec() } else { Vec::new() };
    bytes.extend(text.replace('\n', end).into_bytes());
    bytes
}

#[test]
fn text_formats_accept_a_byte_order_mark_and_every_line_end() {
    for name in ["cube.obj", "cube.off", "cube.ply"] {
        let text = std::fs::read_to_string(data(name)).expect("read");
        // An OBJ that starts with a vertex, which a byte-order mark used to hide.
        let text = match name {
            "cube.obj" => text
                .lines()
                .filter(|l| l.starts_with(['v', 'f']))
                .map(|l| format!("{l}\n"))
                .collect(),
            _ => text,
        };
        for (bom, end) in
            [(true, "\n"), (false, "\r\n"), (false, "\r"), (true, "\r\n"), (true, "\r")]
        {
            let mesh = load_as(name, recode(&text, bom, end));
            assert_eq!(mesh.expect(name), cube(), "{name}, BOM {bom}, line end {end:?}");
        }
    }
    // Line numbers count CR-only and CRLF lines alike, after a byte-order mark.
    for end in ["\r", "\r\n"] {
        let bad = |text: String| recode(&text, true, end);
        fails("bom.obj", bad(with_line(OBJ, 3, "v 0 x 0")), Some(3));
        fails("bom.off", bad(with_line(OFF, 5, "0 x 0")), Some(5));
        fails("bom.ply", bad(with_line(PLY, 12, "0 x 0")), Some(12));
        fails("bom-header.ply", bad(with_line(PLY, 4, "property real x")), Some(4));
        fails("cut.off", bad(OFF.replace("3 0 1 2\n", "")), Some(5));
    }
}

#[test]
fn a_ply_element_that_ends_early_is_named_where_it_ends() {
    // The header declares 10 vertices; the file holds 3 and then the face.
    let msg = fails("vertices.ply", PLY.replace("vertex 3", "vertex 10"), Some(13));
    assert!(msg.contains("element `vertex` ends early, after 3 of the 10"), "{msg}");
    // Two faces declared, one present: the file ends in the face element.
    let msg = fails("faces.ply", PLY.replace("face 1", "face 2"), Some(13));
    assert!(msg.contains("element `face` ends early, after 1 of the 2"), "{msg}");
    // Blank lines do not count as records.
    let msg = fails("blank.ply", PLY.replace("vertex 3", "vertex 4") + "\n\n", Some(13));
    assert!(msg.contains("element `vertex` ends early, after 3 of the 4"), "{msg}");

    // Binary: 8 vertices of 13 bytes and 12 faces of 13 bytes follow the header.
    let bytes = binary_cube();
    let body = bytes.windows(11).position(|w| w == b"end_header\n").expect("header") + 11;
    let declare = |from: &str, to: &str| {
        let header = String::from_utf8_lossy(&bytes[..body]).replace(from, to);
        [header.as_bytes(), &bytes[body..]].concat()
    };
    let msg = fails("faces.ply", declare("face 12", "face 19"), None);
    let faces = body + 8 * 13;
    assert!(
        msg.contains(&format!(
            "in element `face`: line 9 declares 19 records of at least 13 bytes each from byte \
             {faces}, and the file ends at byte {}, after at most 12 of them",
            bytes.len()
        )),
        "{msg}"
    );
    let msg = fails("vertices.ply", declare("vertex 8", "vertex 30"), None);
    let (body, size) = (body + 1, bytes.len() + 1); // one more digit in the header
    assert!(
        msg.contains(&format!(
            "in element `vertex`: line 4 declares 30 records of 13 bytes each from byte {body}, \
             and the file ends at byte {size}, after at most {} of them",
            (size - body) / 13
        )),
        "{msg}"
    );
}

#[test]
fn cgal_bunny_loads_when_fetched() {
    let dir = std::env::var_os("SHADOWBENCH_MODELS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("models"));
    let path = dir.join("bunny00.off");
    if !path.exists() {
        eprintln!("skipped: {} is missing; run `scripts/fetch-models` to fetch it", path.display());
        return;
    }
    let bunny = load_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!((70_000..80_000).contains(&bunny.triangle_count()), "{}", bunny.triangle_count());
    let (lo, hi) = bunny.bounds().expect("vertices");
    assert!((hi - lo).cmpgt(DVec3::ZERO).all());
}

/// Every loader on `bytes`: must return, never panic.
fn load_all(bytes: &[u8]) {
    for (format, name) in
        [(MeshFormat::Obj, "f.obj"), (MeshFormat::Off, "f.off"), (MeshFormat::Ply, "f.ply")]
    {
        if let Err(e) = load_mesh_from_bytes(bytes, format, Path::new(name)) {
            assert!(e.to_string().contains(name), "{e}");
        }
    }
}

/// Applies edits (position, byte, kind) to `base`: replace, insert or delete a byte.
fn mutate(base: &[u8], edits: &[(Index, u8, u8)]) -> Vec<u8> {
    let mut bytes = base.to_vec();
    for (at, byte, kind) in edits {
        let i = at.index(bytes.len() + 1);
        match kind % 3 {
            0 if i < bytes.len() => bytes[i] = *byte,
            1 => bytes.insert(i, *byte),
            _ if i < bytes.len() => {
                bytes.remove(i);
            }
            _ => {}
        }
    }
    bytes
}

/// Tokens that push parsers to their edges.
const NASTY: &[&str] = &[
    "nan",
    "inf",
    "-1",
    "0",
    "3",
    "4294967296",
    "18446744073709551616",
    "1e999",
    "",
    "x",
    "\n",
    "end_header",
    "element face 99999999999",
    "property list uchar int vertex_indices",
    "#",
    "/",
    "f",
    "v",
    "OFF",
    "2",
    "-0",
    "0.5",
];

/// Replaces whitespace-separated tokens of `base` by tokens of [`NASTY`].
fn mutate_tokens(base: &str, edits: &[(Index, Index)]) -> String {
    let mut tokens: Vec<&str> = base.split(' ').collect();
    for (at, with) in edits {
        let i = at.index(tokens.len());
        tokens[i] = NASTY[with.index(NASTY.len())];
    }
    tokens.join(" ")
}

// 256 cases each by default; set PROPTEST_CASES for a longer hunt.
proptest! {
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        load_all(&bytes);
    }

    #[test]
    fn mutated_files_never_panic(
        which in 0usize..4,
        edits in proptest::collection::vec(any::<(Index, u8, u8)>(), 1..10),
        cut in any::<Index>(),
    ) {
        let base = match which {
            0 => std::fs::read(data("cube.obj")).expect("read"),
            1 => std::fs::read(data("cube.off")).expect("read"),
            2 => std::fs::read(data("cube.ply")).expect("read"),
            _ => binary_cube(),
        };
        let mutated = mutate(&base, &edits);
        load_all(&mutated);
        load_all(&mutated[..cut.index(mutated.len() + 1)]);
    }

    #[test]
    fn mutated_tokens_never_panic(
        which in 0usize..3,
        edits in proptest::collection::vec(any::<(Index, Index)>(), 1..6),
    ) {
        let name = ["cube.obj", "cube.off", "cube.ply"][which];
        let base = std::fs::read_to_string(data(name)).expect("read");
        let spaced = base.replace('\n', " \n ");
        load_all(mutate_tokens(&spaced, &edits).as_bytes());
    }
}
