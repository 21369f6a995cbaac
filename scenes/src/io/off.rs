//! OFF (Object File Format), ASCII.
//!
//! Accepted: an optional header keyword `OFF`, or a variant `[ST][C][N]OFF` (`COFF`, `NOFF`,
//! `CNOFF`, `STOFF`, ...) whose extra per-vertex values (normals, colours, texture coordinates)
//! are ignored; the counts `vertices faces [edges]` on the next line or on the header line
//! itself (`OFF 8 6 12`); then one vertex per line (`x y z`, further values ignored) and one face
//! per line (`n i0 .. in-1`, 0-based, further values such as a colour ignored). `#` starts a
//! comment; blank lines are skipped; lines after the last face are ignored. The edge count is
//! not checked (writers disagree on it).
//!
//! The format is defined as a stream of tokens, but every writer puts one vertex or face on a
//! line and only lines tell where an optional colour ends, so this reader is line-based.
//!
//! Rejected with the line named: a malformed or non-finite number, a wrong counts line, a vertex
//! with fewer than 3 values, a face with fewer than 3 vertices or fewer indices than it
//! announces, an index out of range, a file that ends early. `4OFF`, `nOFF` (other dimensions)
//! and `OFF BINARY` are not supported and say so.
//!
//! [`super::triangle_bound`] bounds the triangles from the counts and the file's size alone.

use super::{coordinate, fan, last_line, lines, text, Syntax};
use crate::mesh::Mesh;
use glam::DVec3;

/// Parses an OFF file (not yet validated as a mesh).
pub(crate) fn parse(bytes: &[u8]) -> Result<Mesh, Syntax> {
    let text = text(bytes);
    let end = last_line(&text);
    let mut lines = content_lines(&text);
    let eof = |what: String| Syntax::at(end.max(1), format!("unexpected end of file: {what}"));
    let Counts { vertices: nv, faces: nf } = counts(&text, &mut lines)?;

    // Capacities are bounded by the input size so that a lying count cannot exhaust memory.
    let mut positions = Vec::with_capacity(nv.min(bytes.len() / 6));
    for i in 0..nv {
        let (line, tokens) =
            lines.next().ok_or_else(|| eof(format!("read {i} of {nv} vertices")))?;
        let xyz: Vec<&str> = tokens.take(3).collect();
        if xyz.len() < 3 {
            return Err(Syntax::at(
                line,
                format!("vertex {i} has {} values, expected x y z", xyz.len()),
            ));
        }
        positions.push(DVec3::new(
            coordinate(xyz[0], line)?,
            coordinate(xyz[1], line)?,
            coordinate(xyz[2], line)?,
        ));
    }

    let mut triangles = Vec::with_capacity(nf.min(bytes.len() / 8));
    let mut polygon = Vec::new();
    for f in 0..nf {
        let (line, mut tokens) =
            lines.next().ok_or_else(|| eof(format!("read {f} of {nf} faces")))?;
        let n_token = tokens.next().unwrap_or("");
        let n: usize = n_token.parse().map_err(|_| {
            Syntax::at(line, format!("malformed vertex count `{n_token}` of face {f}"))
        })?;
        if n < 3 {
            return Err(Syntax::at(
                line,
                format!("face {f} has {n} vertices; a face needs at least 3"),
            ));
        }
        polygon.clear();
        for k in 0..n {
            let token = tokens.next().ok_or_else(|| {
                Syntax::at(line, format!("face {f} announces {n} vertices but lists {k}"))
            })?;
            let index: i64 = token
                .parse()
                .map_err(|_| Syntax::at(line, format!("malformed vertex index `{token}`")))?;
            match u32::try_from(index) {
                Ok(v) if (v as usize) < nv => polygon.push(v),
                _ => {
                    return Err(Syntax::at(
                        line,
                        format!("vertex index {index} out of range: the file has {nv} vertices"),
                    ))
                }
            }
        }
        fan(&polygon, &mut triangles);
    }
    Ok(Mesh { positions, triangles })
}

/// An upper bound of the triangles [`parse`] makes of a file of `size` bytes that starts with
/// `header` (whole lines holding at least the counts).
///
/// The counts give `nv` vertices and `nf` faces, but not how many vertices each face has (a
/// face of `n` is `n - 2` triangles), so the size bounds it: a vertex line holds 3 numbers,
/// at least 5 bytes with their separators, and a line end; a face line of `n` vertices holds
/// `n + 1` numbers, at least `2n + 1` bytes, and a line end (the file's last line may lack
/// its end). So `6 nv + Σ (2 n + 2) - 1 <= size`, and the triangles, `Σ n - 2 nf`, are at most
/// `(size + 1 - 6 nv - 6 nf) / 2`: 12 times the count of a common file (a grid of 80 000
/// triangles with 6-decimal coordinates).
pub(crate) fn triangle_bound(header: &[u8], size: u64) -> Result<u64, Syntax> {
    let text = text(header);
    let Counts { vertices, faces } = counts(&text, &mut content_lines(&text))?;
    let least = 6u128 * (vertices as u128 + faces as u128);
    let room = (u128::from(size) + 1).saturating_sub(least);
    Ok(u64::try_from(room / 2).unwrap_or(u64::MAX))
}

/// The numbers of vertices and faces an OFF file declares.
struct Counts {
    vertices: usize,
    faces: usize,
}

/// The lines of `text` that hold more than a comment: their 1-based numbers and tokens.
fn content_lines<'a>(
    text: &'a str,
) -> impl Iterator<Item = (usize, std::iter::Peekable<std::str::SplitWhitespace<'a>>)> {
    lines(text).enumerate().filter_map(|(i, line)| {
        let content = line.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace().peekable();
        tokens.peek()?;
        Some((i + 1, tokens))
    })
}

/// Reads the header keyword, if any, and the counts from the first content `lines` of `text`.
fn counts<'a>(
    text: &str,
    lines: &mut impl Iterator<Item = (usize, std::iter::Peekable<std::str::SplitWhitespace<'a>>)>,
) -> Result<Counts, Syntax> {
    let Some((header_line, mut tokens)) = lines.next() else {
        let what = if text.trim().is_empty() { "empty file" } else { "only comments" };
        return Err(Syntax::whole(format!("{what}: no OFF header or counts")));
    };
    // A header keyword is any first word that is not a number.
    let mut counts_line = header_line;
    let first = tokens.peek().copied().unwrap_or("");
    if first.parse::<f64>().is_err() {
        header(first, header_line)?;
        tokens.next();
        if tokens.peek() == Some(&"BINARY") {
            return Err(Syntax::at(header_line, "binary OFF is not supported"));
        }
        if tokens.peek().is_none() {
            (counts_line, tokens) = lines.next().ok_or_else(|| {
                Syntax::at(
                    last_line(text).max(1),
                    "unexpected end of file: no counts line after the header",
                )
            })?;
        }
    }
    let counts: Vec<&str> = tokens.collect();
    if !(2..=3).contains(&counts.len()) {
        return Err(Syntax::at(
            counts_line,
            format!("expected the counts `vertices faces edges`, found {} values", counts.len()),
        ));
    }
    let count = |token: &str| {
        token.parse::<usize>().map_err(|_| {
            Syntax::at(counts_line, format!("malformed count `{token}` (expected an integer ≥ 0)"))
        })
    };
    let (vertices, faces) = (count(counts[0])?, count(counts[1])?);
    if let Some(ne) = counts.get(2) {
        count(ne)?;
    }
    if u32::try_from(vertices).is_err() {
        return Err(Syntax::at(counts_line, format!("{vertices} vertices are more than 2^32")));
    }
    Ok(Counts { vertices, faces })
}

/// Checks the header keyword: `OFF` with optional prefixes `ST`, `C`, `N` in that order.
fn header(keyword: &str, line: usize) -> Result<(), Syntax> {
    let Some(prefix) = keyword.strip_suffix("OFF") else {
        return Err(Syntax::at(
            line,
            format!("expected an `OFF` header or the counts, found `{keyword}`"),
        ));
    };
    if prefix.contains('4') || prefix.contains('n') {
        return Err(Syntax::at(line, format!("`{keyword}`: only 3-dimensional OFF is supported")));
    }
    let rest = prefix.strip_prefix("ST").unwrap_or(prefix);
    let rest = rest.strip_prefix('C').unwrap_or(rest);
    let rest = rest.strip_prefix('N').unwrap_or(rest);
    if rest.is_empty() {
        Ok(())
    } else {
        Err(Syntax::at(line, format!("unknown OFF header `{keyword}`")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> Syntax {
        parse(text.as_bytes()).expect_err("malformed")
    }

    const TETRA: &str =
        "OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

    #[test]
    fn reads_a_tetrahedron() {
        let mesh = parse(TETRA.as_bytes()).expect("valid");
        assert_eq!(mesh.positions.len(), 4);
        assert_eq!(mesh.triangles, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
        assert_eq!(mesh.positions[3], DVec3::Z);
    }

    #[test]
    fn tolerates_variants_comments_and_merged_header() {
        let text = "# made by hand\nCOFF 3 1 0\n\n0 0 0 255 0 0 255  # red\n1 0 0 0 255 0 255\n\
                    0 1 0 0 0 255 255\n3 0 1 2 0.5 0.5 0.5\n";
        assert_eq!(parse(text.as_bytes()).expect("valid").triangles, vec![[0, 1, 2]]);
        let headerless = "3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        assert_eq!(parse(headerless.as_bytes()).expect("valid").triangles.len(), 1);
        let noff = "NOFF\n3 1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n";
        assert_eq!(parse(noff.as_bytes()).expect("valid").triangles.len(), 1);
    }

    #[test]
    fn fan_triangulates_polygons() {
        let text = "OFF\n5 1 0\n0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 1 0\n5 0 1 2 3 4\n";
        let mesh = parse(text.as_bytes()).expect("valid");
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn errors_name_the_line() {
        assert_eq!(err(""), Syntax::whole("empty file: no OFF header or counts"));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 x 0\n").line, Some(4));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n").line, Some(4));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0 0\n0 1 inf\n3 0 1 2\n").line, Some(5));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n").line, Some(4));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n").line, Some(6));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n").line, Some(6));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n").line, Some(6));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n").line, Some(6));
        assert_eq!(err("OFF\n3 1 0 7\n").line, Some(2));
        assert_eq!(err("OFF\n3 -1 0\n").line, Some(2));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0 0\n").line, Some(4));
        assert_eq!(err("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n\n# no faces\n").line, Some(7));
        assert_eq!(err("OFF\n").line, Some(1));
        assert_eq!(err("PLY\n3 1 0\n").line, Some(1));
        assert!(err("4OFF\n").message.contains("3-dimensional"));
        assert!(err("OFF BINARY\n").message.contains("binary"));
    }
}
