//! A semantic class as an id: `table`, `cup`, or any class an imported CAD database brings. Each
//! name is stored once per process and an id is a copyable reference to it, so entities carry
//! and compare classes without allocating; the set of names is the classes a run meets (tens),
//! never freed.

use std::collections::HashSet;
use std::fmt;
use std::hash::{Hash, Hasher};
use std::sync::{Mutex, OnceLock, PoisonError};

use serde::{Deserialize, Deserializer, Serialize, Serializer};

#[derive(Clone, Copy)]
pub struct ClassId(&'static str);

impl ClassId {
    /// The id of the class called `name`.
    pub fn new(name: &str) -> Self {
        static NAMES: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
        let mut names = NAMES
            .get_or_init(Default::default)
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if let Some(&known) = names.get(name) {
            return Self(known);
        }
        let leaked: &'static str = Box::leak(name.to_owned().into_boxed_str());
        names.insert(leaked);
        Self(leaked)
    }

    pub fn as_str(self) -> &'static str {
        self.0
    }
}

/// One name, one address: ids compare by address.
impl PartialEq for ClassId {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.0, other.0)
    }
}

impl Eq for ClassId {}

/// Hashed by the name, not the address, so that hash maps keyed by class iterate in the same
/// order in every run.
impl Hash for ClassId {
    fn hash<H: Hasher>(&self, state: &mut H) {
        self.0.hash(state);
    }
}

/// Ordered by name.
impl Ord for ClassId {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.cmp(other.0)
    }
}

impl PartialOrd for ClassId {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq<str> for ClassId {
    fn eq(&self, other: &str) -> bool {
        self.0 == other
    }
}

impl PartialEq<&str> for ClassId {
    fn eq(&self, other: &&str) -> bool {
        self.0 == *other
    }
}

impl std::ops::Deref for ClassId {
    type Target = str;
    fn deref(&self) -> &str {
        self.0
    }
}

impl AsRef<str> for ClassId {
    fn as_ref(&self) -> &str {
        self.0
    }
}

impl From<&str> for ClassId {
    fn from(name: &str) -> Self {
        Self::new(name)
    }
}

impl fmt::Debug for ClassId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.0, f)
    }
}

impl fmt::Display for ClassId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.0)
    }
}

impl Serialize for ClassId {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.serialize_str(self.0)
    }
}

impl<'de> Deserialize<'de> for ClassId {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let name = String::deserialize(deserializer)?;
        Ok(Self::new(&name))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_name_is_one_id_and_ids_read_as_their_names() {
        let a = ClassId::new("table");
        let b = ClassId::new(&String::from("table"));
        assert_eq!(a, b);
        assert!(std::ptr::eq(a.as_str(), b.as_str()));
        assert_ne!(a, ClassId::new("tables"));
        assert_eq!(a, "table");
        assert!(ClassId::new("cup") < a);
        assert_eq!(format!("{a} {a:?}"), "table \"table\"");
        let json = serde_json::to_string(&a).expect("serialises");
        assert_eq!(json, "\"table\"");
        let back: ClassId = serde_json::from_str(&json).expect("parses");
        assert_eq!(back, a);
    }
}
