//! The one rule for ids that become file names: every reader that takes an id from a file
//! (`contact_graph.json` nodes, a CAD database's `index.json`, a panoptic index, a scene
//! specification's objects) checks it once, where it is read, so that no id can name a path
//! outside the folder it is written into.

use std::path::{Component, Path, PathBuf};

/// The longest id that becomes a file name.
pub const MAX_ID_LEN: usize = 100;

/// Why an id cannot be a file name, or a file a folder refers to cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FileNameError {
    #[error("an empty id")]
    Empty,
    /// `start` is the id's first 20 characters.
    #[error("id {start:?}... is longer than {MAX_ID_LEN} characters")]
    TooLong { start: String },
    #[error(
        "id {0:?} is not a plain name (letters, digits, _, - and ., starting with a letter or \
         digit): ids become file names"
    )]
    NotPlain(String),
    #[error("{} lies outside the folder {} (only files inside it are read)", name.display(), root.display())]
    Outside { name: PathBuf, root: PathBuf },
    #[error("{} leads outside the folder {} through a link (only files inside it are read)", name.display(), root.display())]
    OutsideThroughLink { name: PathBuf, root: PathBuf },
}

/// Checks that `id` is a plain file-name stem: 1 to [`MAX_ID_LEN`] ASCII letters, digits, `_`,
/// `-` or `.`, starting with a letter or digit (so no `..`, no hidden files, no separators, no
/// quotes that would break the XML and JSON it is written into).
pub fn check_file_name(id: &str) -> Result<(), FileNameError> {
    let plain = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.');
    if id.is_empty() {
        return Err(FileNameError::Empty);
    }
    if id.len() > MAX_ID_LEN {
        return Err(FileNameError::TooLong {
            start: id.chars().take(20).collect(),
        });
    }
    if !id.starts_with(|c: char| c.is_ascii_alphanumeric()) || !id.chars().all(plain) {
        return Err(FileNameError::NotPlain(id.to_string()));
    }
    Ok(())
}

/// The file `name` that a file in the folder `root` refers to, resolved inside `root`'s folder
/// tree, or why not: an absolute path, a `..` that climbs out of `root`, or a symbolic link that
/// leads out are refused, so that an input can only make the program read its own files.
pub fn inside_folder(root: &Path, name: &Path) -> Result<PathBuf, FileNameError> {
    let outside = || FileNameError::Outside {
        name: name.to_path_buf(),
        root: root.to_path_buf(),
    };
    if name.is_absolute() {
        // Allowed only where it names a file inside the folder after all.
        return match (name.canonicalize(), root.canonicalize()) {
            (Ok(real), Ok(real_root)) if real.starts_with(&real_root) => Ok(real),
            _ => Err(outside()),
        };
    }
    let mut relative = PathBuf::new();
    for part in name.components() {
        match part {
            Component::Normal(p) => relative.push(p),
            Component::CurDir => {}
            Component::ParentDir if relative.pop() => {}
            Component::ParentDir | Component::RootDir | Component::Prefix(_) => {
                return Err(outside());
            }
        }
    }
    let path = root.join(&relative);
    if let (Ok(real), Ok(real_root)) = (path.canonicalize(), root.canonicalize())
        && !real.starts_with(&real_root)
    {
        return Err(FileNameError::OutsideThroughLink {
            name: name.to_path_buf(),
            root: root.to_path_buf(),
        });
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_inside_the_folder_resolve_and_others_do_not() {
        let root = Path::new("/data/model");
        assert_eq!(
            inside_folder(root, Path::new("./meshes/../meshes/a.stl")),
            Ok(root.join("meshes/a.stl"))
        );
        for bad in ["../x.stl", "a/../../x.stl", "/etc/passwd"] {
            assert!(inside_folder(root, Path::new(bad)).is_err(), "{bad}");
        }
    }

    #[test]
    fn plain_names_pass_and_paths_do_not() {
        for good in ["table_1", "mjcf_short_fridge", "wall_0", "chair-2.b", "7"] {
            assert!(check_file_name(good).is_ok(), "{good}");
        }
        for bad in [
            "",
            "../../../x",
            "a/b",
            "a\\b",
            ".hidden",
            "..",
            "-rf",
            "a\"b",
            "a b",
            "ü",
            &"x".repeat(MAX_ID_LEN + 1),
        ] {
            assert!(check_file_name(bad).is_err(), "{bad}");
        }
    }
}
