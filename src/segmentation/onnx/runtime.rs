//! Loading ONNX Runtime at run time (ort's `load-dynamic`) with an error that says what was tried,
//! and opening model sessions. ort allows one environment per process: it lives in a `OnceLock`
//! that every session and every parallel test shares.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use ort::environment::Environment;
use ort::session::Session;

use crate::error::InputError;

/// The file name scripts/setup-ort.sh installs.
const LIBRARY_NAME: &str = "libonnxruntime.so.1.31.1";

static ENVIRONMENT: OnceLock<Result<Environment, LoadError>> = OnceLock::new();

/// Why ONNX Runtime did not load; kept for the process's life, as the environment would be.
#[derive(Debug, thiserror::Error)]
enum LoadError {
    #[error("{}: loaded but unusable: {problem}", path.display())]
    Unusable { path: PathBuf, problem: ort::Error },
    #[error(
        "ONNX Runtime could not be loaded; tried:\n{}\nrun scripts/setup-ort.sh, or set \
         ORT_DYLIB_PATH to a libonnxruntime.so of version 1.31 or newer",
        tried.join("\n")
    )]
    NotLoaded {
        /// Each library tried and why it failed, in words.
        tried: Vec<String>,
    },
}

/// The libraries to try: only `ORT_DYLIB_PATH` when it is set (a library asked for by name is
/// never silently replaced by another), else the checkout's `.ort/` baked in at build time
/// (`.cargo/config.toml`), the executable's folder, then the system's search path.
fn candidates() -> Vec<PathBuf> {
    if let Some(p) = std::env::var_os("ORT_DYLIB_PATH") {
        return vec![PathBuf::from(p)];
    }
    let mut paths = Vec::new();
    if let Some(p) = option_env!("ISCENE_DEFAULT_ORT_DYLIB") {
        paths.push(PathBuf::from(p));
    }
    if let Some(dir) = std::env::current_exe()
        .ok()
        .and_then(|e| e.parent().map(Path::to_path_buf))
    {
        paths.push(dir.join(LIBRARY_NAME));
    }
    paths.push(PathBuf::from(LIBRARY_NAME));
    paths
}

fn load() -> Result<Environment, LoadError> {
    let mut tried = Vec::new();
    for path in candidates() {
        // A bare name goes to the dynamic loader's search; a path must exist, which keeps
        // dlopen's less helpful message for the case it is about.
        if path.components().count() > 1 && !path.is_file() {
            tried.push(format!("  {}: no such file", path.display()));
            continue;
        }
        match ort::init_from(&path) {
            Ok(builder) => {
                return builder
                    .with_name("iscene")
                    .build()
                    .map_err(|problem| LoadError::Unusable { path, problem });
            }
            Err(e) => {
                let reason = std::error::Error::source(&e)
                    .map(|s| s.to_string())
                    .unwrap_or_else(|| e.to_string());
                tried.push(format!("  {}: {reason}", path.display()));
            }
        }
    }
    Err(LoadError::NotLoaded { tried })
}

/// The process's ONNX Runtime environment, loaded on first use.
pub fn environment() -> Result<&'static Environment, InputError> {
    ENVIRONMENT
        .get_or_init(load)
        .as_ref()
        .map_err(|reason| InputError::missing(LIBRARY_NAME, reason.to_string()))
}

/// Where the networks run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum OnnxDevice {
    /// ONNX Runtime's CPU provider, one intra-op thread per session (the default).
    #[default]
    Cpu,
    /// ONNX Runtime's CUDA provider on GPU 0. Needs a library built with it (the
    /// onnxruntime-gpu wheel's, with libonnxruntime_providers_cuda.so beside it) and CUDA's
    /// runtime libraries on the loader's path; without them the run stops, it never falls back
    /// to the CPU unasked.
    Cuda,
}

/// A session for the model at `path` on `device`. On the CPU one intra-op thread: frames run in
/// parallel instead, one session per worker.
pub fn open_session(path: &Path, device: OnnxDevice) -> Result<Session, InputError> {
    if !path.is_file() {
        return Err(InputError::missing(
            path,
            "ONNX model not found (the default models are in ../shared/data/models; choose others with --models DIR)",
        ));
    }
    let env = environment()?;
    let fail = |e: &dyn std::fmt::Display| {
        InputError::invalid(path, format!("not a usable ONNX model: {e}"))
    };
    let builder = Session::builder(env)
        .map_err(|e| fail(&e))?
        .with_intra_threads(1)
        .map_err(|e| fail(&e))?;
    let mut builder = match device {
        OnnxDevice::Cpu => builder,
        OnnxDevice::Cuda => builder
            .with_execution_providers([ort::ep::CUDA::default()
                // cuDNN's exhaustive search (ONNX Runtime's default) tries every convolution
                // algorithm on a session's first run, seconds for these two small networks:
                // on an H200, 100 frames of 7-Scenes mapped in 10.3-11.5 s with it and 6.9 s
                // with the heuristic, whose frames ran as fast (median 39.7 ms against 41.3).
                .with_conv_algorithm_search(ort::ep::cuda::ConvAlgorithmSearch::Heuristic)
                .build()
                .error_on_failure()])
            .map_err(|e| {
                InputError::invalid(
                    path,
                    format!(
                        "--onnx-device cuda: ONNX Runtime's CUDA provider did not start ({}); \
                         it needs the onnxruntime-gpu library (ORT_DYLIB_PATH, with \
                         libonnxruntime_providers_cuda.so beside it) and CUDA's libraries on \
                         LD_LIBRARY_PATH (docs/live.md)",
                        e.to_string().trim()
                    ),
                )
            })?,
    };
    builder.commit_from_file(path).map_err(|e| fail(&e))
}
