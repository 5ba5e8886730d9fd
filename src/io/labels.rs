//! `labels.json` of the sequence format: which class and entity each instance id of the label
//! images is.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// `labels.json` of the sequence format.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Labels {
    pub instances: BTreeMap<String, LabelEntry>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LabelEntry {
    pub class: String,
    pub entity: String,
}

impl Labels {
    /// Instance id -> entry, with numeric keys.
    pub fn by_instance(&self) -> BTreeMap<u16, &LabelEntry> {
        self.instances
            .iter()
            .filter_map(|(k, v)| k.parse().ok().map(|id| (id, v)))
            .collect()
    }
}
