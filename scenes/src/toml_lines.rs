//! Where a key of a scene file is written: the line a message names, so that an error found
//! after parsing (a value out of range, a missing model) points at the user's text as a parse
//! error does. The file is parsed again with `toml_edit`, which keeps every key's place.

use toml_edit::{ImDocument, TableLike};

/// The 1-based line of `key` (dotted, with `name[i]` for the `i`th table of an array of
/// tables or of an inline array of inline tables, e.g. `object[1].shape.plane.size`,
/// `animation.object[0].key[1].time`) in the TOML `text`: where its deepest part that
/// is written is (a key left to its default is placed at its table); `None` when the text does
/// not parse or nothing of the key is written.
pub(crate) fn line_of(text: &str, key: &str) -> Option<usize> {
    let document = ImDocument::parse(text).ok()?;
    let mut table: &dyn TableLike = document.as_table();
    let mut span = None;
    for segment in key.split('.') {
        let (name, index) = match segment.split_once('[') {
            Some((name, rest)) => (name, Some(rest.strip_suffix(']')?.parse::<usize>().ok()?)),
            None => (segment, None),
        };
        let Some((written, item)) = table.get_key_value(name) else { break };
        span = written.span().or_else(|| item.span()).or(span);
        let item_table: Option<&dyn TableLike> = match index {
            Some(i) => {
                if let Some(element) = item.as_array_of_tables().and_then(|a| a.get(i)) {
                    span = element.span().or(span);
                    Some(element)
                } else {
                    // An inline array of inline tables: `key = [{ time = 0.0 }, ...]`.
                    let Some(element) = item.as_array().and_then(|a| a.get(i)) else { break };
                    span = element.span().or(span);
                    element.as_inline_table().map(|t| t as &dyn TableLike)
                }
            }
            None => item.as_table_like(),
        };
        match item_table {
            Some(t) => table = t,
            None => break,
        }
    }
    let start = span?.start;
    Some(1 + text.as_bytes()[..start.min(text.len())].iter().filter(|&&b| b == b'\n').count())
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "name = \"s\"\n\
                        [camera.perspective]\n\
                        eye = [0.0, 1.0, 2.0]\n\
                        fov_y_deg = 45.0\n\
                        [[object]]\n\
                        shape.plane = { size = 4.0 }\n\
                        [[object]]\n\
                        name = \"m\"\n\
                        shape.file = { path = \"m.obj\" }\n\
                        material = { color = [1.0,\n\
                        \x20 0.0, 0.0], opacity = 2.0 }\n\
                        [[animation.object]]\n\
                        name = \"m\"\n\
                        key = [{ time = 0.0 },\n\
                        \x20 { time = 1.0, translate = [1.0, 0.0, 0.0] }]\n";

    #[test]
    fn keys_are_found_on_the_line_they_are_written() {
        for (key, line) in [
            ("name", Some(1)),
            ("camera.perspective.fov_y_deg", Some(4)),
            ("camera.perspective.eye", Some(3)),
            // A default is placed at its table.
            ("camera.perspective.near", Some(2)),
            ("object[0].shape.plane.size", Some(6)),
            ("object[1].shape.file.path", Some(9)),
            ("object[1].material.opacity", Some(11)),
            ("object[1].transform.fit_size", Some(7)),
            ("object[1]", Some(7)),
            ("resolution", None),
            ("animation.object[0].name", Some(13)),
            ("animation.object[0].key[1].translate", Some(15)),
            ("animation.object[0].key[1].rotate_deg", Some(15)),
            ("animation.object[0].key[0].time", Some(14)),
            ("animation.object[0].key[2].time", Some(14)),
        ] {
            assert_eq!(line_of(TEXT, key), line, "{key}");
        }
        assert_eq!(line_of("not = toml = here", "not"), None);
    }
}
