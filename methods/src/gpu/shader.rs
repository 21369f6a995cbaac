//! One place where the kernels' WGSL is put together.
//!
//! WGSL has no imports, so a kernel's source is its shared files followed by its own. Each
//! file is a [`Part`] that names the parts it needs; [`compose`] writes a kernel's parts with
//! everything they need first, each file once, in a fixed order (depth first, in the order the
//! needs are listed), each after a `// <file>` line. The parts are `const`s beside the code
//! that binds their buffers (`COMMON` in [`super::common`], the receiver and counters in
//! [`super::sm`], ...). A small module of our own rather than naga_oil: the kernels need
//! ordering and de-duplication only, no conditional compilation or renaming.

/// A WGSL file and the files it needs before it.
#[derive(Debug)]
pub struct Part {
    /// The file's name, written before its text in the composed source.
    pub name: &'static str,
    /// The file's text.
    pub source: &'static str,
    /// The parts it uses, in the order they are written.
    pub needs: &'static [&'static Part],
}

impl Part {
    /// A part with no needs.
    pub const fn file(name: &'static str, source: &'static str) -> Self {
        Self { name, source, needs: &[] }
    }
}

/// The source of a kernel made of `parts`: each part after what it needs, each file once.
pub fn compose(parts: &[&Part]) -> String {
    fn visit(part: &Part, written: &mut Vec<&'static str>, out: &mut String) {
        if written.contains(&part.name) {
            return;
        }
        for need in part.needs {
            visit(need, written, out);
        }
        written.push(part.name);
        out.push_str("// ");
        out.push_str(part.name);
        out.push('\n');
        out.push_str(part.source);
        if !part.source.ends_with('\n') {
            out.push('\n');
        }
    }
    let mut written = Vec::new();
    let mut out = String::new();
    for part in parts {
        visit(part, &mut written, &mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{compose, Part};

    const A: Part = Part::file("a.wgsl", "const A: u32 = 1u;");
    const B: Part = Part { name: "b.wgsl", source: "const B: u32 = A;\n", needs: &[&A] };
    const C: Part = Part { name: "c.wgsl", source: "const C: u32 = A + B;\n", needs: &[&A, &B] };

    #[test]
    fn needs_come_first_and_each_file_once() {
        let s = compose(&[&C, &B]);
        assert_eq!(
            s,
            "// a.wgsl\nconst A: u32 = 1u;\n// b.wgsl\nconst B: u32 = A;\n\
             // c.wgsl\nconst C: u32 = A + B;\n"
        );
        naga::front::wgsl::parse_str(&s).expect("the composed source parses");
    }
}
