//! PLY (Polygon File Format): `format ascii 1.0`, `binary_little_endian 1.0` and
//! `binary_big_endian 1.0`.
//!
//! The header may hold `comment` and `obj_info` lines and any elements in any order. Positions
//! are the `x`, `y`, `z` properties of element `vertex`, of any scalar type (`char`, `uchar`,
//! `short`, `ushort`, `int`, `uint`, `float`, `double` or the aliases `int8` .. `float64`),
//! among any other properties, which are ignored. Polygons are the list property
//! `vertex_indices` (or `vertex_index`) of element `face`, with integer count and index types;
//! other properties of `face` and all other elements (lists included) are skipped.
//!
//! ASCII bodies are read one element per line (as every writer writes them): a line with fewer
//! or more values than the header declares is an error naming it; blank lines are skipped, and
//! an integer-typed value must be written as an integer. Data after the last element is ignored.
//!
//! The header's lines end as its first does (LF, CRLF or CR alone) and may follow a UTF-8
//! byte-order mark; an ASCII body's lines may end with any of the three.
//!
//! Errors name the header line, the body line (ASCII) or the element, its index and the byte
//! offset where its record starts (binary): malformed header, missing `x`/`y`/`z`, missing `face`
//! element, truncated data, malformed or non-finite number, face with fewer than 3 vertices,
//! index out of range.
//!
//! A header that declares more records than the body holds is blamed on the element that ends
//! early, not on the records after it that would be misread in its place. ASCII: when the body
//! has fewer non-blank lines than declared records, the first line that is not a record of the
//! element being read is named, with how many of its declared records came before. Binary:
//! before anything is read, the body's size is checked against the smallest records the header
//! allows (lists empty, faces with 3 indices), naming the first element that cannot fit, its
//! byte offset and how many of its records fit; a declared count of billions is refused there,
//! with nothing allocated for it.
//!
//! A header that declares fewer records than the body holds shows where the next element's
//! first record fails to read (ASCII): when that line reads as a record of the element before,
//! the message says that the header declares so many of those but more follow, rather than
//! blaming the line as a malformed record of the next element.
//!
//! [`super::triangle_bound`] bounds the triangles from the header and the file's size alone
//! (exactly for a binary file of triangles).

use super::{fan, last_line, lines, strip_bom, Syntax};
use crate::mesh::Mesh;
use glam::DVec3;

/// Parses a PLY file (not yet validated as a mesh).
pub(crate) fn parse(bytes: &[u8]) -> Result<Mesh, Syntax> {
    let header = Header::parse(bytes)?;
    let plan = Plan::new(&header)?;
    match header.encoding {
        Encoding::Ascii => {
            let body = String::from_utf8_lossy(bytes.get(header.body..).unwrap_or_default());
            let data = lines(&body).filter(|line| !line.trim().is_empty()).count();
            let records = header.records();
            let mut reader = Ascii {
                lines: lines(&body).enumerate(),
                first: header.lines + 1,
                end: header.lines + last_line(&body),
                data: (data, records),
                line: 0,
                text: "",
                tokens: "".split_whitespace(),
                record: Record::default(),
            };
            read_body(&mut reader, &header, &plan, bytes.len())
        }
        Encoding::Binary { big_endian } => {
            check_size(&header, &plan, bytes.len())?;
            let mut reader = Binary {
                data: bytes,
                pos: header.body,
                big_endian,
                start: header.body,
                count: 0,
                record: Record::default(),
            };
            read_body(&mut reader, &header, &plan, bytes.len())
        }
    }
}

/// An upper bound of the triangles [`parse`] makes of a file of `size` bytes that starts with
/// `header` (whole lines holding at least the header).
///
/// A face of `n` indices is `n - 2` triangles, and a binary file's header bounds `n` by its
/// list's count type (255 for `uchar`; an ASCII count is read as written). The size bounds the
/// sum of the `n`: every other element's records
/// take their least size (lists empty), and what is left holds the faces. Binary: a face takes
/// its other properties' least size, its count and `n` items of the item's size, so the bound
/// is exact for a file of triangles with fixed-size records. ASCII: every value takes at least
/// 2 bytes (a digit and a separator or line end; the file's last value may lack it), so the
/// bound is loose (12 times the count of a grid of 80 000 triangles with 6-decimal
/// coordinates).
pub(crate) fn triangle_bound(header: &[u8], size: u64) -> Result<u64, Syntax> {
    let header = Header::parse(header)?;
    let plan = Plan::new(&header)?;
    let faces = &header.elements[plan.face];
    let (count, item) = plan.index_types;
    let nf = faces.count as u128;
    let longest: u128 = match count {
        Scalar::I8 => i8::MAX as u128,
        Scalar::U8 => u8::MAX.into(),
        Scalar::I16 => i16::MAX as u128,
        Scalar::U16 => u16::MAX.into(),
        Scalar::I32 => i32::MAX as u128,
        // A list's count is of an integer type (the header is refused otherwise).
        Scalar::U32 | Scalar::F32 | Scalar::F64 => u32::MAX.into(),
    };
    // The least size of a record of `element`, in bytes, besides the face's indices; and the
    // size of an index.
    let binary = matches!(header.encoding, Encoding::Binary { .. });
    let least = |element: &Element| -> u128 {
        let value = |ty: Scalar| if binary { ty.size() as u128 } else { 2 };
        element
            .properties
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(ty) | Kind::List(ty, _) => value(ty),
            })
            .sum()
    };
    let index = if binary { item.size() as u128 } else { 2 };
    let others: u128 = header
        .elements
        .iter()
        .enumerate()
        .filter(|&(e, _)| e != plan.face)
        .map(|(_, element)| element.count as u128 * least(element))
        .sum();
    let room = (u128::from(size) + u128::from(!binary))
        .saturating_sub(header.body as u128)
        .saturating_sub(others)
        .saturating_sub(nf * least(faces));
    let by_size = (room / index).saturating_sub(2 * nf);
    // An ASCII count is read as written, whatever its type's range.
    let by_header = if binary { nf * longest.saturating_sub(2) } else { u128::MAX };
    Ok(u64::try_from(by_size.min(by_header)).unwrap_or(u64::MAX))
}

/// A scalar property type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

/// A property: a scalar, or a list with its count and item types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List(Scalar, Scalar),
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
    line: usize,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    line: usize,
    properties: Vec<Property>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

#[derive(Debug)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body: usize,
    /// Number of header lines (the last is `end_header`).
    lines: usize,
}

impl Header {
    fn parse(bytes: &[u8]) -> Result<Self, Syntax> {
        let (mut pos, mut line) = (bytes.len() - strip_bom(bytes).len(), 0);
        // Every header line ends as the first does: with LF (CRLF: the CR is white space) or
        // with a CR alone. The body of a binary file starts right after `end_header`'s end, so
        // the two cannot be mixed.
        let first_end = bytes[pos..].iter().position(|&b| b == b'\r' || b == b'\n');
        let end = match first_end.map(|n| (bytes[pos + n], bytes.get(pos + n + 1))) {
            Some((b'\r', next)) if next != Some(&b'\n') => b'\r',
            _ => b'\n',
        };
        let mut encoding = None;
        let mut elements: Vec<Element> = Vec::new();
        loop {
            let Some(rest) = bytes.get(pos..).filter(|rest| !rest.is_empty()) else {
                return Err(match line {
                    0 => Syntax::whole("empty file"),
                    _ => Syntax::at(line, "the header ends without `end_header`"),
                });
            };
            let (raw, next) = match rest.iter().position(|&b| b == end) {
                Some(n) => (&rest[..n], pos + n + 1),
                None => (rest, bytes.len()),
            };
            line += 1;
            pos = next;
            let text = std::str::from_utf8(raw)
                .map_err(|_| Syntax::at(line, "the header holds a line that is not text"))?;
            if line == 1 {
                if text.trim() != "ply" {
                    return Err(Syntax::at(1, "not a PLY file: the first line must be `ply`"));
                }
                continue;
            }
            let words: Vec<&str> = text.split_whitespace().collect();
            match words.as_slice() {
                [] | ["comment" | "obj_info", ..] => {}
                ["format", format, version] => {
                    if *version != "1.0" {
                        return Err(Syntax::at(
                            line,
                            format!("unsupported PLY version `{version}`"),
                        ));
                    }
                    encoding = Some(match *format {
                        "ascii" => Encoding::Ascii,
                        "binary_little_endian" => Encoding::Binary { big_endian: false },
                        "binary_big_endian" => Encoding::Binary { big_endian: true },
                        _ => {
                            return Err(Syntax::at(line, format!("unknown PLY format `{format}`")))
                        }
                    });
                }
                ["element", name, count] => {
                    let count = count.parse().map_err(|_| {
                        Syntax::at(line, format!("malformed element count `{count}`"))
                    })?;
                    elements.push(Element {
                        name: (*name).to_owned(),
                        count,
                        line,
                        properties: Vec::new(),
                    });
                }
                ["property", rest @ ..] => {
                    let element = elements
                        .last_mut()
                        .ok_or_else(|| Syntax::at(line, "`property` before any `element`"))?;
                    let scalar = |name: &str| {
                        Scalar::from_name(name).ok_or_else(|| {
                            Syntax::at(line, format!("unknown property type `{name}`"))
                        })
                    };
                    let (name, kind) = match rest {
                        ["list", count, item, name] => {
                            let count = scalar(count)?;
                            if !count.is_integer() {
                                return Err(Syntax::at(
                                    line,
                                    "a list's count type must be an integer type",
                                ));
                            }
                            (name, Kind::List(count, scalar(item)?))
                        }
                        [ty, name] if *ty != "list" => (name, Kind::Scalar(scalar(ty)?)),
                        _ => return Err(Syntax::at(line, "malformed `property` line")),
                    };
                    element.properties.push(Property { name: (*name).to_owned(), kind, line });
                }
                ["end_header"] => break,
                [keyword, ..] => {
                    return Err(Syntax::at(
                        line,
                        format!("malformed header line starting `{keyword}`"),
                    ))
                }
            }
        }
        let encoding =
            encoding.ok_or_else(|| Syntax::at(line, "the header has no `format` line"))?;
        Ok(Self { encoding, elements, body: pos, lines: line })
    }

    /// Number of records the body must hold (elements without properties have no data).
    fn records(&self) -> usize {
        self.elements
            .iter()
            .filter(|e| !e.properties.is_empty())
            .fold(0, |n, e| n.saturating_add(e.count))
    }
}

/// Where the mesh is in the elements.
#[derive(Debug)]
struct Plan {
    vertex: usize,
    /// Indices of the `x`, `y`, `z` properties in the vertex element.
    xyz: [usize; 3],
    face: usize,
    /// Index of the vertex index list in the face element.
    indices: usize,
    /// The count and item types of that list.
    index_types: (Scalar, Scalar),
    vertex_count: usize,
}

impl Plan {
    fn new(header: &Header) -> Result<Self, Syntax> {
        let find = |name: &str| -> Result<usize, Syntax> {
            let mut found = header.elements.iter().enumerate().filter(|(_, e)| e.name == name);
            let (index, _) = found.next().ok_or_else(|| {
                Syntax::at(header.lines, format!("the header declares no `{name}` element"))
            })?;
            if let Some((_, again)) = found.next() {
                return Err(Syntax::at(again.line, format!("a second `{name}` element")));
            }
            Ok(index)
        };
        let (vertex, face) = (find("vertex")?, find("face")?);
        let vertices = &header.elements[vertex];
        if u32::try_from(vertices.count).is_err() {
            return Err(Syntax::at(vertices.line, "more than 2^32 vertices"));
        }
        let mut xyz = [0; 3];
        for (slot, axis) in xyz.iter_mut().zip(["x", "y", "z"]) {
            let (index, property) = vertices
                .properties
                .iter()
                .enumerate()
                .find(|(_, p)| p.name == axis)
                .ok_or_else(|| {
                    Syntax::at(vertices.line, format!("element `vertex` has no property `{axis}`"))
                })?;
            if !matches!(property.kind, Kind::Scalar(_)) {
                return Err(Syntax::at(property.line, format!("`{axis}` must be a scalar")));
            }
            *slot = index;
        }
        let faces = &header.elements[face];
        let (indices, property) = faces
            .properties
            .iter()
            .enumerate()
            .find(|(_, p)| p.name == "vertex_indices" || p.name == "vertex_index")
            .ok_or_else(|| {
                Syntax::at(faces.line, "element `face` has no property `vertex_indices`")
            })?;
        let index_types = match property.kind {
            Kind::List(count, item) if item.is_integer() => (count, item),
            _ => {
                return Err(Syntax::at(
                    property.line,
                    format!("`{}` must be a list of integers", property.name),
                ))
            }
        };
        Ok(Self { vertex, xyz, face, indices, index_types, vertex_count: vertices.count })
    }
}

/// The element record being read, for messages.
#[derive(Debug, Default)]
struct Record {
    element: String,
    index: usize,
}

impl Record {
    fn set(&mut self, element: &str, index: usize) {
        if self.element != element {
            element.clone_into(&mut self.element);
        }
        self.index = index;
    }
}

/// A PLY body, ASCII or binary, read one value at a time.
trait Body {
    /// Starts record `index` of `element`.
    fn begin(&mut self, element: &Element, index: usize) -> Result<(), Syntax>;
    /// Reads a value (integer types are exact in `f64`).
    fn read(&mut self, ty: Scalar) -> Result<f64, Syntax>;
    /// Skips `n` values of type `ty`.
    fn skip(&mut self, ty: Scalar, n: usize) -> Result<(), Syntax>;
    /// Ends the record.
    fn end(&mut self) -> Result<(), Syntax>;
    /// A complaint about the current record.
    fn error(&self, message: &str) -> Syntax;
    /// What to report when record `index` of element `e` fails with `error`: the error itself,
    /// unless the body shows that the header's counts are wrong.
    fn explain(&self, _header: &Header, _e: usize, _index: usize, error: Syntax) -> Syntax {
        error
    }
}

/// Refuses a binary body too short for the smallest records its header declares (every list
/// empty, but 3 indices per face), before anything is read: the message names the first element
/// that cannot fit, where it starts and how many of its records fit. Where an earlier element
/// has lists, its records may be longer: the start is then the earliest possible.
fn check_size(header: &Header, plan: &Plan, size: usize) -> Result<(), Syntax> {
    let (mut offset, mut exact) = (header.body, true);
    for (e, element) in header.elements.iter().enumerate() {
        let (mut least, mut fixed) = (0, true);
        for (p, property) in element.properties.iter().enumerate() {
            least += match property.kind {
                Kind::Scalar(ty) => ty.size(),
                Kind::List(count, item) => {
                    fixed = false;
                    let items = if (e, p) == (plan.face, plan.indices) { 3 } else { 0 };
                    count.size() + items * item.size()
                }
            };
        }
        let room = size.saturating_sub(offset);
        match element.count.checked_mul(least) {
            Some(need) if need <= room => {
                offset += need;
                exact &= fixed;
            }
            _ => {
                let (bytes, from) = match (fixed, exact) {
                    (true, true) => ("", ""),
                    (false, true) => ("at least ", ""),
                    (true, false) => ("", " at the earliest"),
                    (false, false) => ("at least ", " at the earliest"),
                };
                return Err(Syntax::whole(format!(
                    "the file ends early, in element `{}`: line {} declares {} records of \
                     {bytes}{least} bytes each from byte {offset}{from}, and the file ends at \
                     byte {size}, after at most {} of them",
                    element.name,
                    element.line,
                    element.count,
                    room / least,
                )));
            }
        }
    }
    Ok(())
}

/// The mesh as it is read.
#[derive(Debug, Default)]
struct Builder {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// The face being read.
    polygon: Vec<u32>,
}

/// Reads every element of `header` from `body` (`size` bytes in all).
fn read_body(
    body: &mut impl Body,
    header: &Header,
    plan: &Plan,
    size: usize,
) -> Result<Mesh, Syntax> {
    // Each vertex value takes a byte at least: a lying count cannot reserve more than that.
    let values = header.elements[plan.vertex].properties.len().max(1);
    let mut mesh = Builder {
        positions: Vec::with_capacity(plan.vertex_count.min(size / values)),
        ..Builder::default()
    };
    for (e, element) in header.elements.iter().enumerate() {
        if element.properties.is_empty() {
            continue; // records without data
        }
        for i in 0..element.count {
            body.begin(element, i)?;
            read_record(body, e, element, plan, &mut mesh)
                .map_err(|error| body.explain(header, e, i, error))?;
        }
    }
    Ok(Mesh { positions: mesh.positions, triangles: mesh.triangles })
}

/// Reads the record just begun of `element` (the `e`-th) into `mesh`.
fn read_record(
    body: &mut impl Body,
    e: usize,
    element: &Element,
    plan: &Plan,
    mesh: &mut Builder,
) -> Result<(), Syntax> {
    let nv = plan.vertex_count;
    let mut xyz = [0.0; 3];
    for (p, property) in element.properties.iter().enumerate() {
        match property.kind {
            Kind::Scalar(ty) => {
                let value = body.read(ty)?;
                if e == plan.vertex {
                    if let Some(axis) = plan.xyz.iter().position(|&q| q == p) {
                        xyz[axis] = value;
                    }
                }
            }
            Kind::List(count, item) => {
                let n = body.read(count)?;
                if n < 0.0 {
                    return Err(body.error(&format!("negative list length {n}")));
                }
                // An integer below 2^63 (the count types are at most 32 bits): exact.
                let n = n as usize;
                if e != plan.face || p != plan.indices {
                    body.skip(item, n)?;
                    continue;
                }
                if n < 3 {
                    let message = format!("{n} vertices; a face needs at least 3");
                    return Err(body.error(&message));
                }
                mesh.polygon.clear();
                for _ in 0..n {
                    let v = body.read(item)?;
                    if v < 0.0 || v >= nv as f64 {
                        return Err(body.error(&format!(
                            "vertex index {v} out of range: the file has {nv} vertices"
                        )));
                    }
                    // In 0..nv, and nv < 2^32 (checked by the plan).
                    mesh.polygon.push(v as u32);
                }
                fan(&mesh.polygon, &mut mesh.triangles);
            }
        }
    }
    if e == plan.vertex {
        if !xyz.iter().all(|c| c.is_finite()) {
            return Err(body.error(&format!("non-finite coordinate {xyz:?}")));
        }
        mesh.positions.push(DVec3::from_array(xyz));
    }
    body.end()
}

/// An ASCII body: one record per line.
struct Ascii<'a> {
    lines: std::iter::Enumerate<super::Lines<'a>>,
    /// Line number of the body's first line.
    first: usize,
    /// Line number of the file's last line.
    end: usize,
    /// How many non-blank lines the body has, and how many records the header declares.
    data: (usize, usize),
    line: usize,
    /// The current line.
    text: &'a str,
    tokens: std::str::SplitWhitespace<'a>,
    record: Record,
}

impl Body for Ascii<'_> {
    fn begin(&mut self, element: &Element, index: usize) -> Result<(), Syntax> {
        self.record.set(&element.name, index);
        for (i, text) in self.lines.by_ref() {
            let tokens = text.split_whitespace();
            if tokens.clone().next().is_some() {
                self.line = self.first + i;
                self.text = text;
                self.tokens = tokens;
                return Ok(());
            }
        }
        Err(Syntax::at(
            self.end,
            format!(
                "unexpected end of file: element `{}` ends early, after {index} of the {} \
                 records that line {} declares",
                element.name, element.count, element.line
            ),
        ))
    }

    fn read(&mut self, ty: Scalar) -> Result<f64, Syntax> {
        let token = self
            .tokens
            .next()
            .ok_or_else(|| self.error("fewer values than the header declares"))?;
        ascii_value(token, ty).ok_or_else(|| self.error(&format!("malformed number `{token}`")))
    }

    fn skip(&mut self, ty: Scalar, n: usize) -> Result<(), Syntax> {
        for _ in 0..n {
            self.read(ty)?;
        }
        Ok(())
    }

    fn end(&mut self) -> Result<(), Syntax> {
        match self.tokens.next() {
            Some(extra) => Err(self.error(&format!(
                "more values than the header declares (`{extra}` is one too many)"
            ))),
            None => Ok(()),
        }
    }

    fn error(&self, message: &str) -> Syntax {
        Syntax::at(self.line, format!("{} {}: {message}", self.record.element, self.record.index))
    }

    /// In a body with fewer lines than records, the first line that is not a record of the
    /// element being read is where that element ends early. In a body with more, a line that
    /// fails as the first record of an element but reads as a record of the element before is
    /// one of that element's records beyond its declared count.
    fn explain(&self, header: &Header, e: usize, index: usize, error: Syntax) -> Syntax {
        let element = &header.elements[e];
        let (data, records) = self.data;
        let previous = header.elements[..e].iter().rev().find(|p| !p.properties.is_empty());
        let message = match previous {
            _ if data < records => format!(
                "element `{}` ends early, after {index} of the {} records that line {} \
                 declares: this line is not one ({})",
                element.name, element.count, element.line, error.message
            ),
            Some(previous) if data > records && index == 0 && fits(self.text, previous) => {
                format!(
                    "line {} declares {} `{}` records, but more follow: this line reads as one, \
                     not as `{}` 0 ({})",
                    previous.line, previous.count, previous.name, element.name, error.message
                )
            }
            _ => return error,
        };
        Syntax::at(
            self.line,
            format!(
                "{message}; the file has {data} lines of data for the header's {records} records"
            ),
        )
    }
}

/// The value of an ASCII `token` of type `ty`: an integer type must be written as an integer.
fn ascii_value(token: &str, ty: Scalar) -> Option<f64> {
    if ty.is_integer() {
        token.parse::<i64>().map(|v| v as f64).ok()
    } else {
        token.parse::<f64>().ok()
    }
}

/// Whether the ASCII line `text` is a record of `element`: a value of each scalar property, and
/// of each list a count followed by as many items, each of its type, and nothing more.
fn fits(text: &str, element: &Element) -> bool {
    let mut tokens = text.split_whitespace();
    let mut value = |ty: Scalar| tokens.next().and_then(|t| ascii_value(t, ty));
    let values = element.properties.iter().all(|property| match property.kind {
        Kind::Scalar(ty) => value(ty).is_some(),
        Kind::List(count, item) => match value(count) {
            Some(n) if n >= 0.0 => (0..n as usize).all(|_| value(item).is_some()),
            _ => false,
        },
    });
    values && tokens.next().is_none()
}

/// A binary body.
struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
    /// Where the current record starts.
    start: usize,
    /// Number of records of the current element.
    count: usize,
    record: Record,
}

impl Binary<'_> {
    fn bytes<const N: usize>(&mut self) -> Result<[u8; N], Syntax> {
        let chunk = self.data.get(self.pos..self.pos.saturating_add(N));
        let chunk =
            chunk.and_then(|c| <[u8; N]>::try_from(c).ok()).ok_or_else(|| self.truncated())?;
        self.pos += N;
        Ok(chunk)
    }

    /// The file ends inside the current record.
    fn truncated(&self) -> Syntax {
        self.error(&format!(
            "truncated: the file ends at byte {}, inside record {} of the {} this element has",
            self.data.len(),
            self.record.index,
            self.count
        ))
    }
}

impl Body for Binary<'_> {
    fn begin(&mut self, element: &Element, index: usize) -> Result<(), Syntax> {
        self.record.set(&element.name, index);
        self.start = self.pos;
        self.count = element.count;
        Ok(())
    }

    fn read(&mut self, ty: Scalar) -> Result<f64, Syntax> {
        macro_rules! number {
            ($t:ty) => {{
                let bytes = self.bytes::<{ std::mem::size_of::<$t>() }>()?;
                let value = if self.big_endian {
                    <$t>::from_be_bytes(bytes)
                } else {
                    <$t>::from_le_bytes(bytes)
                };
                f64::from(value)
            }};
        }
        Ok(match ty {
            Scalar::I8 => number!(i8),
            Scalar::U8 => number!(u8),
            Scalar::I16 => number!(i16),
            Scalar::U16 => number!(u16),
            Scalar::I32 => number!(i32),
            Scalar::U32 => number!(u32),
            Scalar::F32 => number!(f32),
            Scalar::F64 => number!(f64),
        })
    }

    fn skip(&mut self, ty: Scalar, n: usize) -> Result<(), Syntax> {
        let end = n.checked_mul(ty.size()).and_then(|len| self.pos.checked_add(len));
        match end {
            Some(end) if end <= self.data.len() => {
                self.pos = end;
                Ok(())
            }
            _ => Err(self.truncated()),
        }
    }

    fn end(&mut self) -> Result<(), Syntax> {
        Ok(())
    }

    fn error(&self, message: &str) -> Syntax {
        Syntax::whole(format!(
            "{} {} (record at byte {}): {message}",
            self.record.element, self.record.index, self.start
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "ply\nformat ascii 1.0\ncomment hand-made\nelement vertex 3\n\
                        property float x\nproperty float y\nproperty float z\n\
                        element face 1\nproperty list uchar int vertex_indices\nend_header\n";

    fn err(text: &str) -> Syntax {
        parse(text.as_bytes()).expect_err("malformed")
    }

    #[test]
    fn reads_ascii_with_extra_properties_and_elements() {
        let text = "ply\nformat ascii 1.0\nobj_info x\nelement material 1\n\
                    property list uchar float rgb\nelement vertex 4\nproperty uchar red\n\
                    property double z\nproperty int16 y\nproperty float32 x\nelement face 1\n\
                    property list uint8 uint vertex_index\nproperty uchar flags\nelement edge 1\n\
                    property int a\nproperty int b\nend_header\n\
                    3 0.5 0.5 0.5\n1 0 0 0.5\n2 0 1 1.5\n\n3 1 1 2.5\n4 0 0 0\n4 0 1 2 3 7\n0 1\n";
        let mesh = parse(text.as_bytes()).expect("valid");
        assert_eq!(mesh.positions[0], DVec3::new(0.5, 0.0, 0.0));
        assert_eq!(mesh.positions[2], DVec3::new(2.5, 1.0, 1.0));
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn reads_binary_both_endians() {
        let header = |format: &str| {
            format!(
                "ply\r\nformat {format} 1.0\r\nelement vertex 3\r\nproperty double x\r\n\
                 property float y\r\nproperty short z\r\nelement face 1\r\n\
                 property list uchar uint vertex_indices\r\nend_header\r\n"
            )
        };
        for big in [false, true] {
            let mut bytes =
                header(if big { "binary_big_endian" } else { "binary_little_endian" }).into_bytes();
            for (x, y, z) in [(0.5f64, 0.0f32, 0i16), (1.0, 0.0, 0), (0.0, 1.0, -2)] {
                if big {
                    bytes.extend(
                        x.to_be_bytes().into_iter().chain(y.to_be_bytes()).chain(z.to_be_bytes()),
                    );
                } else {
                    bytes.extend(
                        x.to_le_bytes().into_iter().chain(y.to_le_bytes()).chain(z.to_le_bytes()),
                    );
                }
            }
            bytes.push(3);
            for i in [0u32, 1, 2] {
                bytes.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
            }
            let mesh = parse(&bytes).expect("valid");
            assert_eq!(mesh.positions[2], DVec3::new(0.0, 1.0, -2.0), "big endian: {big}");
            assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
            let e = parse(&bytes[..bytes.len() - 1]).expect_err("truncated");
            assert!(
                e.line.is_none()
                    && e.message.contains("element `face`")
                    && e.message.contains(&format!(
                        "ends at byte {}, after at most 0 of them",
                        bytes.len() - 1
                    )),
                "{e:?}"
            );
        }
    }

    #[test]
    fn more_vertices_than_declared_are_named_as_such() {
        // 3 vertices declared, 4 present: the fourth is where the face should be.
        let text = format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n");
        let e = err(&text);
        assert_eq!(e.line, Some(14), "{e:?}");
        assert_eq!(
            e.message,
            "line 4 declares 3 `vertex` records, but more follow: this line reads as one, not as \
             `face` 0 (face 0: 1 vertices; a face needs at least 3); the file has 5 lines of \
             data for the header's 4 records"
        );
        // A face line that is no vertex either is blamed as a face.
        let e = err(&format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 x\n3 0 1 2\n"));
        assert_eq!(e.message, "face 0: malformed number `x`");
    }

    #[test]
    fn errors_name_the_line() {
        let body = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        assert_eq!(parse(format!("{HEAD}{body}").as_bytes()).expect("valid").triangles.len(), 1);
        for (text, line) in [
            (format!("{HEAD}0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"), 12),
            (format!("{HEAD}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"), 12),
            (format!("{HEAD}0 0 0\n1 0 0\n0 1 inf\n3 0 1 2\n"), 13),
            (format!("{HEAD}0 0 0\n1 0\n0 1 0\n3 0 1 2\n"), 12),
            (format!("{HEAD}0 0 0\n1 0 0 0\n0 1 0\n3 0 1 2\n"), 12),
            (format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), 14),
            (format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 -1\n"), 14),
            (format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n2 0 1\n"), 14),
            (format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n"), 14),
            (format!("{HEAD}0 0 0\n1 0 0\n0 1 0\n"), 13),
            (HEAD.replace("property float z\n", ""), 4),
            (HEAD.replace("element face 1\nproperty list uchar int vertex_indices\n", ""), 8),
            (HEAD.replace("list uchar int vertex_indices", "int vertex_indices"), 9),
            (HEAD.replace("list uchar int", "list float int"), 9),
            (HEAD.replace("float y", "real y"), 6),
            (HEAD.replace("ascii", "binary"), 2),
            (HEAD.replace("end_header\n", ""), 9),
            ("PLY\n".to_owned(), 1),
        ] {
            let e = err(&text);
            assert_eq!(e.line, Some(line), "{text:?}: {e:?}");
        }
        assert_eq!(err(""), Syntax::whole("empty file"));
    }
}
