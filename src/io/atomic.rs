//! Outputs that appear whole or not at all: files written beside their target and renamed, and
//! output folders staged beside their final name and renamed when complete.

use std::path::{Path, PathBuf};

use crate::error::IsceneError;
use crate::io::output_folder::{MARKER, OutputMarker, OutputTarget};

/// Writes `bytes` to `path` through a temporary file in the same folder.
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), IsceneError> {
    let tmp = sibling(path, "tmp");
    std::fs::write(&tmp, bytes)
        .map_err(|e| IsceneError::io(format!("writing {}", tmp.display()), e))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        IsceneError::io(
            format!("renaming {} to {}", tmp.display(), path.display()),
            e,
        )
    })
}

fn sibling(path: &Path, tag: &str) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{tag}-{}", std::process::id()))
}

/// Marks a staging folder as ours, so that a later run may remove it once its process is gone.
const STAGING_MARKER: &str = ".iscene-staging";

/// A folder being written. Everything goes into a hidden sibling of the final folder; `commit`
/// swaps it into place, replacing the earlier output only when [`OutputTarget`]'s rule still
/// allows. Dropped without `commit`, the staging folder is removed, so a failed run leaves no
/// output that looks complete; one a killed process left is removed by the next run in the same
/// folder.
pub struct StagedDir {
    staging: PathBuf,
    target: OutputTarget,
    committed: bool,
}

impl StagedDir {
    pub fn new(target: &OutputTarget) -> Result<Self, IsceneError> {
        let path = target.path();
        let parent = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        std::fs::create_dir_all(parent)
            .map_err(|e| IsceneError::io(format!("creating {}", parent.display()), e))?;
        clear_stale_staging(path);
        let staging = sibling(path, "partial");
        std::fs::create_dir_all(&staging)
            .map_err(|e| IsceneError::io(format!("creating {}", staging.display()), e))?;
        let staged = Self {
            staging,
            target: target.clone(),
            committed: false,
        };
        std::fs::write(staged.staging.join(STAGING_MARKER), b"")
            .map_err(|e| IsceneError::io(format!("writing {}", staged.staging.display()), e))?;
        Ok(staged)
    }

    /// Where to write the folder's content for now.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The folder's final name.
    pub fn target(&self) -> &Path {
        self.target.path()
    }

    /// Writes the output marker listing every file written, and puts the folder in place.
    pub fn commit(mut self) -> Result<PathBuf, IsceneError> {
        let target = self.target.path().to_path_buf();
        std::fs::remove_file(self.staging.join(STAGING_MARKER))
            .map_err(|e| IsceneError::io(format!("finishing {}", self.staging.display()), e))?;
        let marker = OutputMarker::of_folder(&self.staging, self.target.command())?;
        let json = serde_json::to_vec_pretty(&marker)
            .map_err(|e| IsceneError::Internal(format!("output marker: {e}")))?;
        std::fs::write(self.staging.join(MARKER), json)
            .map_err(|e| IsceneError::io(format!("writing {}", self.staging.display()), e))?;
        if target.symlink_metadata().is_ok() {
            // The folder may have changed while the work ran: check it again.
            self.target.check_replaceable()?;
            replace_folder(&self.staging, &target)?;
            // The staging name now holds the earlier output.
            std::fs::remove_dir_all(&self.staging).map_err(|e| {
                IsceneError::io(format!("removing the earlier {}", target.display()), e)
            })?;
        } else {
            std::fs::rename(&self.staging, &target).map_err(|e| {
                IsceneError::io(
                    format!(
                        "renaming {} to {}",
                        self.staging.display(),
                        target.display()
                    ),
                    e,
                )
            })?;
        }
        self.committed = true;
        Ok(target)
    }
}

/// Swaps the folders `new` and `old` in one step, where the file system can: a kill at any
/// moment leaves `old`'s name holding one complete output or the other.
#[cfg(target_os = "linux")]
fn replace_folder(new: &Path, old: &Path) -> Result<(), IsceneError> {
    use rustix::fs::{CWD, RenameFlags, renameat_with};
    match renameat_with(CWD, new, CWD, old, RenameFlags::EXCHANGE) {
        Ok(()) => Ok(()),
        Err(rustix::io::Errno::INVAL | rustix::io::Errno::NOSYS) => replace_in_two_steps(new, old),
        Err(e) => Err(IsceneError::io(
            format!("putting {} in place of {}", new.display(), old.display()),
            e.into(),
        )),
    }
}

#[cfg(not(target_os = "linux"))]
fn replace_folder(new: &Path, old: &Path) -> Result<(), IsceneError> {
    replace_in_two_steps(new, old)
}

/// The earlier folder is moved aside, the new one moved in and the earlier one moved to `new`'s
/// name; a run killed between the steps leaves the earlier output aside (`.NAME.old-PID`),
/// where the next run puts it back.
fn replace_in_two_steps(new: &Path, old: &Path) -> Result<(), IsceneError> {
    let aside = sibling(old, "old");
    let io = |what: &str, e| IsceneError::io(format!("{what} {}", old.display()), e);
    std::fs::rename(old, &aside).map_err(|e| io("moving aside", e))?;
    if let Err(e) = std::fs::rename(new, old) {
        let _ = std::fs::rename(&aside, old);
        return Err(io("replacing", e));
    }
    std::fs::rename(&aside, new).map_err(|e| io("moving away the earlier", e))
}

/// Removes the staging folders (`.NAME.partial-PID`) that processes now gone left beside
/// `target`, and puts back an earlier output (`.NAME.old-PID`) a killed replacement left aside.
/// Only folders that carry one of our markers are touched.
pub fn clear_stale_staging(target: &Path) {
    let parent = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.filter_map(Result::ok) {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some((stem, tag, pid)) = staging_name(&name) else {
            continue;
        };
        if process_is_running(pid) {
            continue;
        }
        let path = entry.path();
        let ours = path.join(STAGING_MARKER).is_file() || path.join(MARKER).is_file();
        if !ours || !path.is_dir() {
            continue;
        }
        let owner = parent.join(stem);
        if tag == "old" && owner == target && owner.symlink_metadata().is_err() {
            let _ = std::fs::rename(&path, &owner);
        } else {
            let _ = std::fs::remove_dir_all(&path);
        }
    }
}

/// `.NAME.TAG-PID` with TAG `partial` or `old`: (NAME, TAG, PID).
fn staging_name(name: &str) -> Option<(&str, &str, i32)> {
    let rest = name.strip_prefix('.')?;
    let (front, pid) = rest.rsplit_once('-')?;
    let (stem, tag) = front.rsplit_once('.')?;
    let pid = pid.parse().ok()?;
    (["partial", "old"].contains(&tag) && !stem.is_empty()).then_some((stem, tag, pid))
}

#[cfg(unix)]
fn process_is_running(pid: i32) -> bool {
    let Some(pid) = rustix::process::Pid::from_raw(pid) else {
        return false;
    };
    !matches!(
        rustix::process::test_kill_process(pid),
        Err(rustix::io::Errno::SRCH)
    )
}

#[cfg(not(unix))]
fn process_is_running(_pid: i32) -> bool {
    true
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: a leftover hidden folder is removed by the next run, and the error
            // that got us here matters more.
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::output_folder::OutputCommand;

    fn target(path: &Path) -> OutputTarget {
        OutputTarget::claim("--out", path, OutputCommand::Reconstruct, &[], false).expect("claim")
    }

    #[test]
    fn uncommitted_folder_leaves_nothing_and_committed_replaces_the_earlier_output() {
        let root = tempfile::tempdir().expect("tempdir");
        let out = root.path().join("out");
        {
            let staged = StagedDir::new(&target(&out)).expect("stage");
            std::fs::write(staged.path().join("a.txt"), "x").expect("write");
        }
        assert!(!out.exists());
        assert_eq!(std::fs::read_dir(root.path()).expect("list").count(), 0);
        let staged = StagedDir::new(&target(&out)).expect("stage");
        std::fs::write(staged.path().join("stale.txt"), "old").expect("write");
        staged.commit().expect("commit");
        assert!(out.join(MARKER).is_file());
        let staged = StagedDir::new(&target(&out)).expect("stage");
        std::fs::write(staged.path().join("a.txt"), "x").expect("write");
        staged.commit().expect("commit");
        assert!(out.join("a.txt").exists() && !out.join("stale.txt").exists());
        assert_eq!(std::fs::read_dir(root.path()).expect("list").count(), 1);
    }

    #[test]
    fn a_file_added_during_the_run_stops_the_replacement() {
        let root = tempfile::tempdir().expect("tempdir");
        let out = root.path().join("out");
        let staged = StagedDir::new(&target(&out)).expect("stage");
        staged.commit().expect("commit");
        let staged = StagedDir::new(&target(&out)).expect("stage");
        std::fs::write(out.join("mine.txt"), "mine").expect("write");
        let err = staged.commit().expect_err("must refuse");
        assert_eq!(err.exit_code(), 2);
        assert!(out.join("mine.txt").is_file());
        assert_eq!(std::fs::read_dir(root.path()).expect("list").count(), 1);
    }

    #[test]
    fn leftovers_of_dead_processes_are_cleared_and_an_output_left_aside_is_put_back() {
        let root = tempfile::tempdir().expect("tempdir");
        let out = root.path().join("out");
        StagedDir::new(&target(&out))
            .expect("stage")
            .commit()
            .expect("commit");
        // No process has pid i32::MAX (pid_max is at most 2^22).
        let dead = i32::MAX;
        let aside = root.path().join(format!(".out.old-{dead}"));
        std::fs::rename(&out, &aside).expect("mv");
        let partial = root.path().join(format!(".out.partial-{dead}"));
        std::fs::create_dir_all(&partial).expect("mkdir");
        std::fs::write(partial.join(STAGING_MARKER), "").expect("write");
        let foreign = root.path().join(format!(".notes.partial-{dead}"));
        std::fs::create_dir_all(&foreign).expect("mkdir");
        drop(StagedDir::new(&target(&out)).expect("stage"));
        assert!(out.join(MARKER).is_file(), "the earlier output is back");
        assert!(!partial.exists() && !aside.exists());
        assert!(foreign.exists(), "a folder without our marker is not ours");
    }
}
