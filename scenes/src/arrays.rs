//! Fixed-size arrays in scene files (`resolution`, points, directions, colours, per-axis
//! values), read so that a wrong number of values is an error.
//!
//! serde's arrays and glam's vectors take the first N values of a TOML array and leave the rest
//! unread, which the TOML parser does not check: `resolution = [160, 120, 7]` or a four-value
//! `eye` would pass unnoticed. The readers here take every value (the extra ones of any type)
//! and refuse any count but N. Fields use them with `#[serde(deserialize_with = ...)]`; the
//! parser's message then shows the line, the key and the array.

use glam::DVec3;
use serde::de::{Deserialize, Deserializer, Error, IgnoredAny, SeqAccess, Visitor};
use std::fmt;
use std::marker::PhantomData;

/// An array of exactly `N` values of type `T`.
pub(crate) fn exact<'de, D, T, const N: usize>(deserializer: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    deserializer.deserialize_seq(Exact::<T, N>(PhantomData))
}

/// A vector of exactly 3 values.
pub(crate) fn dvec3<'de, D: Deserializer<'de>>(deserializer: D) -> Result<DVec3, D::Error> {
    exact::<D, f64, 3>(deserializer).map(DVec3::from_array)
}

/// An optional vector of exactly 3 values (a field with `#[serde(default)]`: absent is `None`).
pub(crate) fn option_dvec3<'de, D: Deserializer<'de>>(
    deserializer: D,
) -> Result<Option<DVec3>, D::Error> {
    dvec3(deserializer).map(Some)
}

/// Reads an array of exactly `N` values.
struct Exact<T, const N: usize>(PhantomData<T>);

impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Exact<T, N> {
    type Value = [T; N];

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "an array of {N} values")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
        let mut values = Vec::with_capacity(N);
        while values.len() < N {
            match seq.next_element()? {
                Some(value) => values.push(value),
                None => return Err(A::Error::invalid_length(values.len(), &self)),
            }
        }
        let mut count = N;
        while seq.next_element::<IgnoredAny>()?.is_some() {
            count += 1;
        }
        if count != N {
            return Err(A::Error::invalid_length(count, &self));
        }
        <[T; N]>::try_from(values).map_err(|v| A::Error::invalid_length(v.len(), &self))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize)]
    struct Probe {
        #[serde(deserialize_with = "exact")]
        size: [u32; 2],
        #[serde(default, deserialize_with = "dvec3")]
        at: DVec3,
        #[serde(default, deserialize_with = "option_dvec3")]
        maybe: Option<DVec3>,
    }

    fn probe(text: &str) -> Result<Probe, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }

    #[test]
    fn the_right_count_reads() {
        let p = probe("size = [4, 3]\nat = [1.0, -2.0, 0.5]").expect("valid");
        assert_eq!((p.size, p.at), ([4, 3], DVec3::new(1.0, -2.0, 0.5)));
        assert_eq!(probe("size = [4, 3]").expect("default").at, DVec3::ZERO);
        assert_eq!(probe("size = [4, 3]").expect("absent").maybe, None);
        let p = probe("size = [4, 3]\nmaybe = [1, 2, 3]").expect("present");
        assert_eq!(p.maybe, Some(DVec3::new(1.0, 2.0, 3.0)));
        let e = probe("size = [4, 3]\nmaybe = [1, 2]").expect_err("two values");
        assert!(e.contains("line 2") && e.contains("invalid length 2"), "{e}");
    }

    #[test]
    fn any_other_count_is_refused_with_line_and_key() {
        for (text, line, found) in [
            ("size = [160, 120, 7]", "line 1", "invalid length 3"),
            ("size = [160]", "line 1", "invalid length 1"),
            ("size = [1, 2]\nat = [1.0, 2.0, 3.0, \"four\"]", "line 2", "invalid length 4"),
            ("size = [1, 2]\nat = [\n  1.0, 2.0, 3.0, [4],\n]", "line 2", "invalid length 4"),
            ("size = [1, 2]\nat = [1.0, 2.0]", "line 2", "invalid length 2"),
            ("size = [1, 2, 3.5]", "line 1", "invalid length 3"),
        ] {
            let e = probe(text).expect_err(text);
            let key = if line == "line 1" { "size = " } else { "at = " };
            assert!(e.contains(line) && e.contains(key) && e.contains(found), "{text}: {e}");
        }
        let e = probe("size = 5").expect_err("not an array");
        assert!(e.contains("expected an array of 2 values"), "{e}");
        let e = probe("size = [1, \"two\"]").expect_err("wrong type");
        assert!(e.contains("line 1") && e.contains("two"), "{e}");
    }
}
