//! What a command may write over: the one rule for `--out` (and `--into`) of every command.
//!
//! Nothing the program did not write is ever deleted. An output folder carries a marker
//! ([`MARKER`]) naming the command that wrote it and every file it wrote, with its size and
//! modification time; a later run replaces the folder only when the marker is there and every
//! file in the folder is one of those, unchanged. The checks run before any work, so a bad
//! `--out` costs nothing, and again just before the finished output replaces the folder.

use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{InputError, IsceneError};

/// The marker file of an output folder.
pub const MARKER: &str = ".iscene-output.json";

/// The commands that write whole output folders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputCommand {
    Render,
    Reconstruct,
    Simulate,
}

impl OutputCommand {
    pub fn name(self) -> &'static str {
        match self {
            Self::Render => "render",
            Self::Reconstruct => "reconstruct",
            Self::Simulate => "simulate",
        }
    }
}

/// A file as it was written: enough to see that it is still the same file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileStamp {
    pub bytes: u64,
    /// Modification time, nanoseconds since the Unix epoch.
    pub modified_ns: u64,
}

impl FileStamp {
    fn of(meta: &std::fs::Metadata) -> Self {
        let modified_ns = meta
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
        Self {
            bytes: meta.len(),
            modified_ns,
        }
    }
}

/// The content of [`MARKER`].
#[derive(Debug, Serialize, Deserialize)]
pub struct OutputMarker {
    pub generator: String,
    pub command: OutputCommand,
    /// Every file the command wrote, by its path relative to the folder ('/'-separated).
    pub files: BTreeMap<String, FileStamp>,
}

impl OutputMarker {
    /// The marker of the folder `dir` as it is now: every file in it (but the marker) listed.
    pub fn of_folder(dir: &Path, command: OutputCommand) -> Result<Self, IsceneError> {
        let files = list_files(dir)
            .map_err(|e| IsceneError::io(format!("listing {}", dir.display()), e))?
            .into_iter()
            .filter(|(name, _)| name != MARKER)
            .collect();
        Ok(Self {
            generator: format!("iscene {}", env!("CARGO_PKG_VERSION")),
            command,
            files,
        })
    }

    /// The marker of `dir`, or `None` when it has none that parses.
    pub fn read(dir: &Path) -> Option<Self> {
        let text = std::fs::read_to_string(dir.join(MARKER)).ok()?;
        serde_json::from_str(&text).ok()
    }
}

/// Every file under `dir` (symbolic links included, not followed), by its '/'-separated path
/// relative to `dir`, with its stamp.
fn list_files(dir: &Path) -> std::io::Result<BTreeMap<String, FileStamp>> {
    let mut files = BTreeMap::new();
    let mut pending = vec![PathBuf::new()];
    while let Some(relative) = pending.pop() {
        for entry in std::fs::read_dir(dir.join(&relative))? {
            let entry = entry?;
            let meta = entry.path().symlink_metadata()?;
            let path = relative.join(entry.file_name());
            if meta.is_dir() {
                pending.push(path);
            } else {
                let name = path
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect::<Vec<_>>()
                    .join("/");
                files.insert(name, FileStamp::of(&meta));
            }
        }
    }
    Ok(files)
}

/// Why the output folder `path` may not be written, when it is one of `inputs`, holds one, or
/// lies inside an input folder.
pub fn input_clash(path: &Path, inputs: &[&Path]) -> Option<String> {
    let out = resolved(path);
    inputs.iter().find_map(|input| {
        let input_abs = resolved(input);
        if out == input_abs {
            Some(format!("is the input {}", input.display()))
        } else if input_abs.starts_with(&out) {
            Some(format!(
                "holds the input {}; writing there would delete it",
                input.display()
            ))
        } else if input.is_dir() && out.starts_with(&input_abs) {
            Some(format!("lies inside the input {}", input.display()))
        } else {
            None
        }
    })
}

/// An output folder a command has been allowed to write: checked against the rule, not yet
/// written.
#[derive(Clone, Debug)]
pub struct OutputTarget {
    path: PathBuf,
    command: OutputCommand,
    /// The flag that named it, for messages (`--out`).
    flag: &'static str,
    /// Replace an earlier output of another command too.
    force: bool,
}

impl OutputTarget {
    /// Checks that `path` may take the output of `command`, before any work: it must not be
    /// the input or lie inside one of `inputs`, nor hold one; it must not be a file or a link;
    /// and an existing folder must be empty or an earlier output this command may replace
    /// ([`OutputTarget::check_replaceable`]).
    pub fn claim(
        flag: &'static str,
        path: &Path,
        command: OutputCommand,
        inputs: &[&Path],
        force: bool,
    ) -> Result<Self, IsceneError> {
        if path.as_os_str().is_empty() {
            return Err(InputError::invalid(flag, "is empty: name the output folder").into());
        }
        let target = Self {
            path: path.to_path_buf(),
            command,
            flag,
            force,
        };
        if let Some(why) = input_clash(path, inputs) {
            return Err(target.refuse(why));
        }
        // A run killed earlier in the same place left its staging folder, or an earlier output
        // moved aside: cleared (or put back) before the folder is judged.
        crate::io::atomic::clear_stale_staging(path);
        target.check_replaceable()?;
        Ok(target)
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    pub fn command(&self) -> OutputCommand {
        self.command
    }

    fn refuse(&self, why: impl std::fmt::Display) -> IsceneError {
        InputError::invalid(
            &self.path,
            format!("{} {why}; nothing was written", self.flag),
        )
        .into()
    }

    /// Whether the folder may be replaced now: absent, an empty folder, or an earlier output
    /// (by its marker) of this command (of any command with `force`) that holds only the files
    /// the marker lists, unchanged.
    pub fn check_replaceable(&self) -> Result<(), IsceneError> {
        let meta = match self.path.symlink_metadata() {
            Ok(meta) => meta,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => {
                return Err(InputError::invalid(&self.path, format!("cannot read: {e}")).into());
            }
        };
        if meta.file_type().is_symlink() {
            return Err(self.refuse("is a symbolic link: name the folder itself"));
        }
        if !meta.is_dir() {
            return Err(self.refuse("is an existing file, not a folder"));
        }
        let empty = std::fs::read_dir(&self.path)
            .map_err(|e| InputError::invalid(&self.path, format!("cannot list: {e}")))?
            .next()
            .is_none();
        if empty {
            return Ok(());
        }
        let Some(marker) = OutputMarker::read(&self.path) else {
            // Outputs of iscene before the marker existed look like this; they are not deleted
            // either, but the user is told what they are.
            let older = ["report.json", "trace.json", "gt/render.json"]
                .iter()
                .any(|f| self.path.join(f).is_file());
            return Err(self.refuse(format!(
                "is a folder iscene did not write (it has no {MARKER}), and it is not empty: \
                 choose a new or empty folder{}",
                if older {
                    " (if it is the output of an iscene older than the marker, delete it yourself)"
                } else {
                    ""
                }
            )));
        };
        if marker.command != self.command && !self.force {
            return Err(self.refuse(format!(
                "holds the output of `iscene {}`, not of `iscene {}`: pass --force to replace it",
                marker.command.name(),
                self.command.name()
            )));
        }
        let files = list_files(&self.path)
            .map_err(|e| InputError::invalid(&self.path, format!("cannot list: {e}")))?;
        for (name, stamp) in &files {
            if name == MARKER {
                continue;
            }
            match marker.files.get(name) {
                None => {
                    return Err(self.refuse(format!(
                        "holds {name}, which iscene did not write: move it away or choose another folder"
                    )));
                }
                Some(written) if written != stamp => {
                    return Err(self.refuse(format!(
                        "holds {name}, changed since iscene wrote it: move it away or choose another folder"
                    )));
                }
                Some(_) => {}
            }
        }
        Ok(())
    }
}

/// `path` made absolute with symbolic links resolved as far as it exists, and `.` and `..`
/// resolved in the part that does not exist yet.
pub fn resolved(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut existing = absolute.as_path();
    let mut rest = Vec::new();
    loop {
        if let Ok(real) = existing.canonicalize() {
            let mut out = real;
            for part in rest.iter().rev() {
                match part {
                    Component::ParentDir => {
                        out.pop();
                    }
                    Component::CurDir => {}
                    other => out.push(other.as_os_str()),
                }
            }
            return out;
        }
        match (existing.parent(), existing.components().next_back()) {
            (Some(parent), Some(last)) => {
                rest.push(last);
                existing = parent;
            }
            _ => return absolute,
        }
    }
}

/// The rule for a CAD database folder written into (`--into`): it adds to what the folder
/// holds, so the folder must be absent, empty, or a database iscene wrote (its `index.json`
/// names an iscene generator), and must neither be, hold nor lie inside the source `input`.
pub fn check_database_folder(into: &Path, input: Option<&Path>) -> Result<(), IsceneError> {
    let refuse = |why: String| -> IsceneError {
        InputError::invalid(into, format!("--into {why}; nothing was written")).into()
    };
    if let Some(input) = input {
        let (out, source) = (resolved(into), resolved(input));
        if out == source || source.starts_with(&out) || (input.is_dir() && out.starts_with(&source))
        {
            return Err(refuse(format!(
                "overlaps the models' source {}",
                input.display()
            )));
        }
    }
    let meta = match into.symlink_metadata() {
        Ok(meta) => meta,
        Err(_) => return Ok(()),
    };
    if meta.file_type().is_symlink() {
        return Err(refuse("is a symbolic link: name the folder itself".into()));
    }
    if !meta.is_dir() {
        return Err(refuse("is an existing file, not a folder".into()));
    }
    let empty = std::fs::read_dir(into)
        .map_err(|e| InputError::invalid(into, format!("cannot list: {e}")))?
        .next()
        .is_none();
    if empty {
        return Ok(());
    }
    let generator = std::fs::read_to_string(into.join("index.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v.get("generator")?.as_str().map(str::to_owned));
    match generator {
        Some(g) if g.starts_with("iscene") => Ok(()),
        _ => Err(refuse(
            "is a folder that is not a CAD database iscene wrote (no index.json of iscene's), \
             and it is not empty: choose a new or empty folder"
                .into(),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn claim(path: &Path, inputs: &[&Path]) -> Result<OutputTarget, IsceneError> {
        OutputTarget::claim("--out", path, OutputCommand::Reconstruct, inputs, false)
    }

    fn refused(result: Result<OutputTarget, IsceneError>, words: &str) {
        match result {
            Ok(_) => panic!("accepted; expected a refusal saying {words:?}"),
            Err(e) => {
                assert_eq!(e.exit_code(), 2, "{e}");
                assert!(e.to_string().contains(words), "{e} does not say {words:?}");
            }
        }
    }

    #[test]
    fn the_input_its_parents_and_its_inside_are_refused() {
        let root = tempfile::tempdir().expect("tempdir");
        let seq = root.path().join("data").join("seq");
        std::fs::create_dir_all(&seq).expect("mkdir");
        refused(claim(&seq, &[&seq]), "is the input");
        refused(claim(&root.path().join("data"), &[&seq]), "holds the input");
        refused(claim(&seq.join("out"), &[&seq]), "lies inside the input");
        refused(claim(&seq.join("..").join("seq"), &[&seq]), "is the input");
        assert!(claim(&root.path().join("data").join("out"), &[&seq]).is_ok());
    }

    #[test]
    fn files_links_and_folders_iscene_did_not_write_are_refused() {
        let root = tempfile::tempdir().expect("tempdir");
        let file = root.path().join("notes.txt");
        std::fs::write(&file, "mine").expect("write");
        refused(claim(&file, &[]), "is an existing file");
        let mine = root.path().join("mine");
        std::fs::create_dir_all(&mine).expect("mkdir");
        assert!(claim(&mine, &[]).is_ok(), "an empty folder is fine");
        std::fs::write(mine.join("a.txt"), "mine").expect("write");
        refused(claim(&mine, &[]), "did not write");
        #[cfg(unix)]
        {
            let link = root.path().join("link");
            std::os::unix::fs::symlink(&mine, &link).expect("symlink");
            refused(claim(&link, &[]), "symbolic link");
        }
    }

    #[test]
    fn an_earlier_output_is_replaceable_until_someone_adds_or_changes_a_file() {
        let root = tempfile::tempdir().expect("tempdir");
        let out = root.path().join("out");
        std::fs::create_dir_all(out.join("sub")).expect("mkdir");
        std::fs::write(out.join("report.json"), "{}").expect("write");
        std::fs::write(out.join("sub").join("m.obj"), "o").expect("write");
        let marker = OutputMarker::of_folder(&out, OutputCommand::Reconstruct).expect("marker");
        std::fs::write(
            out.join(MARKER),
            serde_json::to_string(&marker).expect("json"),
        )
        .expect("write");
        assert!(claim(&out, &[]).is_ok());
        refused(
            OutputTarget::claim("--out", &out, OutputCommand::Render, &[], false),
            "pass --force",
        );
        assert!(OutputTarget::claim("--out", &out, OutputCommand::Render, &[], true).is_ok());
        std::fs::write(out.join("sub").join("notes.md"), "mine").expect("write");
        refused(claim(&out, &[]), "sub/notes.md, which iscene did not write");
        refused(
            OutputTarget::claim("--out", &out, OutputCommand::Reconstruct, &[], true),
            "did not write",
        );
        std::fs::remove_file(out.join("sub").join("notes.md")).expect("rm");
        std::fs::write(out.join("report.json"), "{\"edited\": true}").expect("write");
        refused(claim(&out, &[]), "report.json, changed since");
    }

    #[test]
    fn a_database_folder_must_be_new_empty_or_iscenes() {
        let root = tempfile::tempdir().expect("tempdir");
        let db = root.path().join("db");
        assert!(check_database_folder(&db, None).is_ok());
        std::fs::create_dir_all(&db).expect("mkdir");
        std::fs::write(db.join("thesis.tex"), "mine").expect("write");
        assert!(check_database_folder(&db, None).is_err());
        std::fs::write(
            db.join("index.json"),
            r#"{"generator": "iscene cad import", "models": []}"#,
        )
        .expect("write");
        assert!(check_database_folder(&db, None).is_ok());
        let src = db.join("models");
        std::fs::create_dir_all(&src).expect("mkdir");
        assert!(check_database_folder(&db, Some(&src)).is_err());
        assert!(check_database_folder(&src.join("x"), Some(&src)).is_err());
    }
}
