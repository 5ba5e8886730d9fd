//! The status record of one input, `DIR/<name>/status.json`: running, done or failed, with the
//! error, the time and the peak memory. An input is done only when its record says so for the
//! same options and the same program version; everything else is run again.

use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

use super::manifest::BatchInput;
use crate::error::IsceneError;

pub const STATUS_FILE: &str = "status.json";

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum State {
    /// Started and not finished: still running, or its process was killed.
    Running,
    Done,
    Failed,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputStatus {
    pub name: String,
    pub state: State,
    /// Why it failed.
    pub error: Option<String>,
    /// The shard that ran it (`I/N`).
    pub shard: String,
    pub host: String,
    /// Seconds since the Unix epoch.
    pub started_at: f64,
    pub finished_at: Option<f64>,
    pub seconds: Option<f64>,
    /// The peak resident memory of the process that ran it, MB.
    pub peak_memory_mb: Option<f64>,
    /// Whether `eval.json` scores it against a truth.
    pub evaluated: bool,
    pub version: String,
    pub input: BatchInput,
}

impl InputStatus {
    pub fn started(input: &BatchInput, shard: &str) -> Self {
        Self {
            name: input.name.clone(),
            state: State::Running,
            error: None,
            shard: shard.into(),
            host: host_name(),
            started_at: now(),
            finished_at: None,
            seconds: None,
            peak_memory_mb: None,
            evaluated: false,
            version: env!("CARGO_PKG_VERSION").into(),
            input: input.clone(),
        }
    }

    /// The record once the input's process ended: done, or failed with `error`.
    pub fn finished(mut self, error: Option<String>, evaluated: bool) -> Self {
        let end = now();
        self.state = if error.is_some() {
            State::Failed
        } else {
            State::Done
        };
        self.error = error;
        self.finished_at = Some(end);
        self.seconds = Some(end - self.started_at);
        self.evaluated = evaluated;
        self
    }

    /// Whether this record marks `input` finished, so that a rerun skips it.
    pub fn finishes(&self, input: &BatchInput) -> bool {
        self.state == State::Done
            && &self.input == input
            && self.version == env!("CARGO_PKG_VERSION")
    }
}

pub fn status_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(name).join(STATUS_FILE)
}

/// The record of input `name` in the batch folder `dir`, if there is a readable one.
pub fn read_status(dir: &Path, name: &str) -> Option<InputStatus> {
    let text = std::fs::read_to_string(status_path(dir, name)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Writes the record whole or not at all (a rename), so a killed process never leaves half of one.
pub fn write_status(dir: &Path, status: &InputStatus) -> Result<(), IsceneError> {
    let path = status_path(dir, &status.name);
    let temporary = path.with_extension("json.partial");
    let text = serde_json::to_string_pretty(status)
        .map_err(|e| IsceneError::Internal(format!("status JSON: {e}")))?;
    std::fs::write(&temporary, text + "\n")
        .and_then(|()| std::fs::rename(&temporary, &path))
        .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))
}

pub fn now() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|_| "unknown".into())
}

/// The peak resident memory of this process so far (Linux `VmHWM`), MB.
pub fn peak_memory_mb() -> Option<f64> {
    crate::base::process::peak_resident_bytes().map(|b| b as f64 / (1024.0 * 1024.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::manifest::Manifest;

    fn input(seed: u64) -> BatchInput {
        let value = serde_json::json!({"inputs": [{"seed": seed, "frames": 10}]});
        Manifest::from_value(&value, Path::new("."))
            .expect("manifest")
            .inputs
            .remove(0)
    }

    #[test]
    fn only_a_done_record_of_the_same_options_finishes_an_input() {
        let running = InputStatus::started(&input(1), "0/1");
        assert!(!running.finishes(&input(1)));
        let done = running.clone().finished(None, true);
        assert!(done.finishes(&input(1)));
        assert!(!done.finishes(&input(2)));
        let failed = running.finished(Some("bad".into()), false);
        assert_eq!(failed.state, State::Failed);
        assert!(!failed.finishes(&input(1)));
    }

    #[test]
    fn a_record_is_written_whole_and_read_back() {
        let dir = tempfile::tempdir().expect("tempdir");
        let status = InputStatus::started(&input(3), "1/2").finished(None, true);
        std::fs::create_dir(dir.path().join("seed_3")).expect("mkdir");
        write_status(dir.path(), &status).expect("write");
        let read = read_status(dir.path(), "seed_3").expect("read");
        // Times are compared within a microsecond: JSON numbers need not round-trip exactly.
        assert!((read.started_at - status.started_at).abs() < 1e-6);
        assert!(read.finishes(&status.input));
        assert_eq!((read.state, read.shard), (State::Done, status.shard));
        assert!(read_status(dir.path(), "seed_4").is_none());
    }

    #[test]
    fn the_peak_memory_of_this_process_is_read() {
        assert!(peak_memory_mb().is_some_and(|mb| mb > 1.0));
    }
}
