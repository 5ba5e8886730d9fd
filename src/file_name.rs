//! The one rule for ids that become file names: every reader that takes an id from a file
//! (`contact_graph.json` nodes, a CAD database's `index.json`, a panoptic index, a scene
//! specification's objects) checks it once, where it is read, so that no id can name a path
//! outside the folder it is written into.

use std::path::{Component, Path, PathBuf};

/// The longest id that becomes a file name.
pub const MAX_ID_LEN: usize = 100;

/// Checks that `id` is a plain file-name stem: 1 to [`MAX_ID_LEN`] ASCII letters, digits, `_`,
/// `-` or `.`, starting with a letter or digit (so no `..`, no hidden files, no separators, no
/// quotes that would break the XML and JSON it is written into).
pub fn check_file_name(id: &str) -> Result<(), String> {
    let plain = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.');
    if id.is_empty() {
        return Err("an empty id".into());
    }
    if id.len() > MAX_ID_LEN {
        return Err(format!(
            "id {:?}... is longer than {MAX_ID_LEN} characters",
            id.chars().take(20).collect::<String>()
        ));
    }
    if !id.starts_with(|c: char| c.is_ascii_alphanumeric()) || !id.chars().all(plain) {
        return Err(format!(
            "id {id:?} is not a plain name (letters, digits, _, - and ., starting with a letter or \
             digit): ids become file names"
        ));
    }
    Ok(())
}

/// The file `name` that a file in the folder `root` refers to, resolved inside `root`'s folder
/// tree, or why not: an absolute path, a `..` that climbs out of `root`, or a symbolic link that
/// leads out are refused, so that an input can only make the program read its own files.
pub fn inside_folder(root: &Path, name: &Path) -> Result<PathBuf, String> {
    let outside = || {
        format!(
            "{} lies outside the folder {} (only files inside it are read)",
            name.display(),
            root.display()
        )
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
        return Err(format!(
            "{} leads outside the folder {} through a link (only files inside it are read)",
            name.display(),
            root.display()
        ));
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
