//! A value of an input that a validator refuses: where it is and what is wrong with it.

use std::fmt;

/// A refused value of an input (a specification, a manifest, a task, a model file): the key
/// that holds it (`objects[3].size`, `inputs[2]`, `line 14: <geom pos>`; empty when the input as
/// a whole is wrong) and the problem. The readers that know the file turn it into an
/// `InputError` naming the file, so every message reads `FILE: KEY: PROBLEM`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InvalidValue {
    pub key: String,
    pub problem: String,
}

impl InvalidValue {
    /// The value at `key` is wrong: `problem`.
    pub fn at(key: impl Into<String>, problem: impl Into<String>) -> Self {
        Self {
            key: key.into(),
            problem: problem.into(),
        }
    }

    /// The input as a whole is wrong (no single key holds the problem), or the caller knows the
    /// key and adds it with [`InvalidValue::under`].
    pub fn whole(problem: impl Into<String>) -> Self {
        Self::at("", problem)
    }

    /// The same problem seen from the value's container: its key becomes `outer.key` (a field of
    /// `outer`, `objects[3]` around `size`), or `outer` when it had none.
    pub fn under(self, outer: &str) -> Self {
        let key = match (outer.is_empty(), self.key.is_empty()) {
            (true, _) => self.key,
            (false, true) => outer.to_string(),
            (false, false) => format!("{outer}.{}", self.key),
        };
        Self { key, ..self }
    }
}

impl fmt::Display for InvalidValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.key.is_empty() {
            f.write_str(&self.problem)
        } else {
            write!(f, "{}: {}", self.key, self.problem)
        }
    }
}

impl std::error::Error for InvalidValue {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_nest_from_the_inside_out() {
        let e = InvalidValue::whole("0 frames is outside 1..10000");
        assert_eq!(e.to_string(), "0 frames is outside 1..10000");
        let e = e.under("frames").under("camera");
        assert_eq!(e.key, "camera.frames");
        assert_eq!(e.to_string(), "camera.frames: 0 frames is outside 1..10000");
        assert_eq!(InvalidValue::at("size", "x").under("").key, "size");
    }
}
