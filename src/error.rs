//! Errors that cross module boundaries: bad input (exit code 2) versus internal failure (exit code 1).

use std::path::{Path, PathBuf};

/// Everything a reader or validator can reject. Each error names the file and the problem.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The file or folder is not there.
    #[error("{path}: missing ({what})")]
    Missing { path: PathBuf, what: String },
    /// The file is there but its content is wrong.
    #[error("{path}: {problem}")]
    Invalid { path: PathBuf, problem: String },
}

impl InputError {
    pub fn invalid(path: impl AsRef<Path>, problem: impl std::fmt::Display) -> Self {
        Self::Invalid {
            path: path.as_ref().to_path_buf(),
            problem: problem.to_string(),
        }
    }

    pub fn missing(path: impl AsRef<Path>, what: impl Into<String>) -> Self {
        Self::Missing {
            path: path.as_ref().to_path_buf(),
            what: what.into(),
        }
    }

    /// Wraps an I/O error on `path` as bad input: a file we were told to read is unreadable.
    pub fn io(path: impl AsRef<Path>, err: &std::io::Error) -> Self {
        if err.kind() == std::io::ErrorKind::NotFound {
            Self::missing(path, "file not found")
        } else {
            Self::invalid(path, format!("cannot read: {err}"))
        }
    }

    pub fn path(&self) -> &Path {
        match self {
            Self::Missing { path, .. } | Self::Invalid { path, .. } => path,
        }
    }
}

/// Errors of the library's top-level operations.
#[derive(Debug, thiserror::Error)]
pub enum IsceneError {
    #[error(transparent)]
    Input(#[from] InputError),
    /// Writing outputs or another failure that is not the user's input's fault.
    #[error("{context}: {source}")]
    Io {
        context: String,
        source: std::io::Error,
    },
    #[error("internal error: {0}")]
    Internal(String),
}

impl IsceneError {
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        Self::Io {
            context: context.into(),
            source,
        }
    }

    /// The process exit code of DESIGN.md: 2 for bad input, 1 for internal failure.
    pub fn exit_code(&self) -> i32 {
        match self {
            Self::Input(_) => 2,
            Self::Io { .. } | Self::Internal(_) => 1,
        }
    }
}

pub type Result<T, E = IsceneError> = std::result::Result<T, E>;
