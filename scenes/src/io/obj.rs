//! Wavefront OBJ, loaded by `tobj` after a line-by-line check of our own.
//!
//! Only geometry is read: `v x y z` (further values, a curve weight `w` or a colour, are ignored
//! as the specification says for polygons; `tobj` alone would divide by `w`) and
//! `f v1[/vt[/vn]] v2 ..` with 1-based or negative (relative to the vertices so far) position
//! indices; a positive index may refer to a vertex defined later in the file. Polygons are
//! fan-triangulated. Normals, texture coordinates, free-form geometry, points and lines (`p`,
//! `l`), materials (`mtllib` files are never opened) and groups (`o`, `g`, `usemtl`) are ignored,
//! so all groups form one mesh that shares their vertices. Vertices no face uses are dropped;
//! the others keep their order of first use. `#` starts a comment anywhere on a line.
//!
//! `tobj` reports errors without a line, so every `v` and `f` line is checked first, naming the
//! line: malformed or non-finite coordinates, a vertex with fewer than 3 values, a malformed,
//! zero or out-of-range position index, a face with fewer than 3 vertices. Only `v` and `f`
//! lines, reduced to positions and position indices, are handed to `tobj`.
//!
//! An OBJ declares no counts, so [`super::triangle_bound`] bounds its triangles by its size
//! alone (half its size: see `triangle_bound` here).

use super::{coordinate, lines, text, Syntax};
use crate::mesh::Mesh;
use glam::DVec3;

/// Parses an OBJ file (not yet validated as a mesh).
pub(crate) fn parse(bytes: &[u8]) -> Result<Mesh, Syntax> {
    let text = text(bytes);
    let total = lines(&text).filter(|line| words(line).next() == Some("v")).count();

    // The geometry, checked, for tobj; other lines become blank so that line numbers stay.
    let mut geometry = String::with_capacity(text.len());
    let mut defined = 0;
    for (i, line) in lines(&text).enumerate() {
        let line_no = i + 1;
        let mut words = words(line);
        match words.next() {
            Some("v") => {
                let xyz: Vec<&str> = words.take(3).collect();
                if xyz.len() < 3 {
                    return Err(Syntax::at(
                        line_no,
                        format!("vertex has {} coordinates, expected x y z", xyz.len()),
                    ));
                }
                for token in &xyz {
                    coordinate(token, line_no)?;
                }
                defined += 1;
                geometry.push_str("v ");
                geometry.push_str(&xyz.join(" "));
            }
            Some("f") => {
                geometry.push('f');
                let mut corners = 0;
                for word in words {
                    let position = position_index(word, line_no, defined, total)?;
                    geometry.push(' ');
                    geometry.push_str(position);
                    corners += 1;
                }
                if corners < 3 {
                    return Err(Syntax::at(
                        line_no,
                        format!("face has {corners} vertices; a face needs at least 3"),
                    ));
                }
            }
            _ => {}
        }
        geometry.push('\n');
    }

    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default() // one index per position (`single_index: false`)
    };
    // No `mtllib` line reaches tobj, so the material loader is never called.
    let (models, _) = tobj::load_obj_buf(&mut geometry.as_bytes(), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| Syntax::whole(format!("OBJ: {e}")))?;

    let mut mesh = Mesh::default();
    for model in &models {
        let base = u32::try_from(mesh.positions.len())
            .map_err(|_| Syntax::whole("more than 2^32 vertices"))?;
        let (positions, indices) = (&model.mesh.positions, &model.mesh.indices);
        if positions.len() % 3 != 0 || indices.len() % 3 != 0 {
            return Err(Syntax::whole("OBJ: tobj returned incomplete vertices or triangles"));
        }
        mesh.positions.extend(
            // tobj's feature `use_f64` makes these `f64`, parsed as written.
            positions.chunks_exact(3).map(|p| DVec3::new(p[0], p[1], p[2])),
        );
        for t in indices.chunks_exact(3) {
            let corner = |k: usize| {
                base.checked_add(t[k]).ok_or_else(|| Syntax::whole("more than 2^32 vertices"))
            };
            mesh.triangles.push([corner(0)?, corner(1)?, corner(2)?]);
        }
    }
    Ok(mesh)
}

/// An upper bound of the triangles [`parse`] makes of a file of `size` bytes: half its size.
///
/// A face of `k` corners is `k - 2` triangles. Its line holds `f`, then `k` corners of at least
/// 2 bytes each (a separator and a digit), then a line end (but for the file's last line): at
/// least `2k + 2` bytes, of which the first triangle takes 8 (`f 1 2 3` and the end) and each
/// further one 2 more. So no file holds more than one triangle for every 2 bytes; a file of
/// `f 1 2 3` lines alone holds one for every 8, and a common file one for every 34 (a grid of
/// 80 000 triangles with 6-decimal coordinates), where the bound is 17 times the count.
pub(crate) fn triangle_bound(size: u64) -> u64 {
    size / 2
}

/// The words of `line` before any comment.
fn words(line: &str) -> std::str::SplitWhitespace<'_> {
    line.split('#').next().unwrap_or("").split_whitespace()
}

/// Checks one corner `v[/vt[/vn]]` of a face on line `line` (with `defined` vertices before it
/// and `total` in the file) and returns its position index as written.
fn position_index(word: &str, line: usize, defined: usize, total: usize) -> Result<&str, Syntax> {
    let malformed = || Syntax::at(line, format!("malformed face vertex `{word}`"));
    let mut parts = word.split('/');
    let position = parts.next().unwrap_or("");
    let others: Vec<&str> = parts.collect();
    if others.len() > 2 || others.iter().any(|p| !p.is_empty() && p.parse::<i64>().is_err()) {
        return Err(malformed());
    }
    let index: i64 = position.parse().map_err(|_| malformed())?;
    let in_range = match index {
        0 => return Err(Syntax::at(line, "vertex index 0: OBJ indices start at 1")),
        k if k > 0 => k.unsigned_abs() <= total as u64,
        k => k.unsigned_abs() <= defined as u64,
    };
    if !in_range {
        let message = if index > 0 {
            format!("vertex index {index} out of range: the file has {total} vertices")
        } else {
            format!("relative vertex index {index} out of range: {defined} vertices precede it")
        };
        return Err(Syntax::at(line, message));
    }
    Ok(position)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> Syntax {
        parse(text.as_bytes()).expect_err("malformed")
    }

    #[test]
    fn reads_faces_with_texcoords_normals_groups_and_relative_indices() {
        let text = "mtllib missing.mtl\no first\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\n\
                    v 0 1 0 0.5 0.5 0.5\nvt 0 0\nvn 0 0 1\nusemtl red\nf 1/1/1 2/1/1 3/1/1\n\
                    g second\nf -4//1 -2//1 -1//1\nl 1 2 3\np 4\n";
        let mesh = parse(text.as_bytes()).expect("valid");
        assert_eq!(mesh.triangles.len(), 2);
        // One mesh over both groups, sharing vertices; w ignored.
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.positions[2], DVec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn fan_triangulates_and_keeps_f64() {
        let text = "v 0.1 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n";
        let mesh = parse(text.as_bytes()).expect("valid");
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
        assert_eq!(mesh.positions[0].x, 0.1);
    }

    #[test]
    fn forward_references_are_allowed() {
        let mesh = parse(b"f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").expect("valid");
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn errors_name_the_line() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        for (tail, line) in [
            ("v 1 x 0\n", 4),
            ("v 1 nan 0\n", 4),
            ("v 1 0 -inf\n", 4),
            ("v 1 0 1e999\n", 4),
            ("v 1 0\n", 4),
            ("\nf 1 2 4\n", 5),
            ("f 1 2 -4\n", 4),
            ("f 1 2 0\n", 4),
            ("f 1 2\n", 4),
            ("f 1 2 3/x\n", 4),
            ("f 1 2 3/1/1/1\n", 4),
            ("f 1 2 three\n", 4),
        ] {
            let e = err(&format!("{base}{tail}"));
            assert_eq!(e.line, Some(line), "{tail:?}: {e:?}");
        }
        assert!(err("f 1 2 4\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").message.contains("3 vertices"));
    }
}
