//! Outputs that appear whole or not at all: files written beside their target and renamed, and
//! output folders staged beside their final name and renamed when complete.

use std::path::{Path, PathBuf};

use crate::error::IsceneError;

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

/// A folder being written. Everything goes into a hidden sibling of the final folder; `commit`
/// moves it into place (replacing an older folder of that name). Dropped without `commit`, the
/// staging folder is removed, so a failed run leaves no output that looks complete.
pub struct StagedDir {
    staging: PathBuf,
    target: PathBuf,
    committed: bool,
}

impl StagedDir {
    pub fn new(target: &Path) -> Result<Self, IsceneError> {
        if let Some(parent) = target.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent)
                .map_err(|e| IsceneError::io(format!("creating {}", parent.display()), e))?;
        }
        let staging = sibling(target, "partial");
        if staging.exists() {
            std::fs::remove_dir_all(&staging)
                .map_err(|e| IsceneError::io(format!("clearing {}", staging.display()), e))?;
        }
        std::fs::create_dir_all(&staging)
            .map_err(|e| IsceneError::io(format!("creating {}", staging.display()), e))?;
        Ok(Self {
            staging,
            target: target.to_path_buf(),
            committed: false,
        })
    }

    /// Where to write the folder's content for now.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// The folder's final name.
    pub fn target(&self) -> &Path {
        &self.target
    }

    pub fn commit(mut self) -> Result<PathBuf, IsceneError> {
        if self.target.exists() {
            let old = sibling(&self.target, "old");
            std::fs::rename(&self.target, &old).map_err(|e| {
                IsceneError::io(format!("moving aside {}", self.target.display()), e)
            })?;
            std::fs::remove_dir_all(&old)
                .map_err(|e| IsceneError::io(format!("removing {}", old.display()), e))?;
        }
        std::fs::rename(&self.staging, &self.target).map_err(|e| {
            IsceneError::io(
                format!(
                    "renaming {} to {}",
                    self.staging.display(),
                    self.target.display()
                ),
                e,
            )
        })?;
        self.committed = true;
        Ok(self.target.clone())
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed {
            // Best effort: a leftover hidden folder is harmless, and the error that got us here matters more.
            let _ = std::fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uncommitted_folder_leaves_nothing_and_committed_replaces_the_old_one() {
        let root = tempfile::tempdir().expect("tempdir");
        let target = root.path().join("out");
        {
            let staged = StagedDir::new(&target).expect("stage");
            std::fs::write(staged.path().join("a.txt"), "x").expect("write");
        }
        assert!(!target.exists());
        assert_eq!(std::fs::read_dir(root.path()).expect("list").count(), 0);
        std::fs::create_dir_all(&target).expect("mkdir");
        std::fs::write(target.join("stale.txt"), "old").expect("write");
        let staged = StagedDir::new(&target).expect("stage");
        std::fs::write(staged.path().join("a.txt"), "x").expect("write");
        staged.commit().expect("commit");
        assert!(target.join("a.txt").exists() && !target.join("stale.txt").exists());
    }
}
