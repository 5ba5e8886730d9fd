//! `iscene view`: the viewer (feature `viewer`), or a clear error in a build without it.

#[cfg(feature = "viewer")]
use std::path::PathBuf;

use iscene::error::IsceneError;
#[cfg(feature = "viewer")]
use iscene::pipeline::{ReconstructOptions, SegmentationChoice, reconstruct};

use crate::args::ViewArgs;

pub(crate) fn view(args: ViewArgs, interactive: bool) -> Result<(), IsceneError> {
    #[cfg(not(feature = "viewer"))]
    {
        let _ = (args, interactive);
        Err(IsceneError::Internal(
            "this iscene was built without the viewer: cargo run --release --features viewer -- view ..."
                .into(),
        ))
    }
    #[cfg(feature = "viewer")]
    {
        let ViewArgs {
            dir,
            screenshot,
            layer,
            frames,
            size,
            open,
            replay,
            shots,
            task,
            robot,
            live,
        } = args;
        let dir = if replay && !dir.join("report.json").is_file() {
            reconstruct_for_replay(&dir, interactive)?
        } else {
            dir
        };
        show(
            iscene::viewer::ViewOptions {
                dir,
                screenshot,
                layers: Vec::new(),
                frames,
                size,
                open,
                replay,
                shots,
                task,
                robot,
                live,
            },
            &layer,
        )
    }
}

#[cfg(feature = "viewer")]
#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
fn show(options: iscene::viewer::ViewOptions, layers: &[String]) -> Result<(), IsceneError> {
    use clap::ValueEnum;
    let layers = layers
        .iter()
        .map(|l| {
            iscene::viewer::Layer::from_str(l, true).map_err(|_| {
                IsceneError::Input(iscene::error::InputError::invalid(
                    &options.dir,
                    format!(
                        "--layer {l:?}: the layers are {}",
                        iscene::viewer::Layer::ALL.map(|l| l.name()).join(", ")
                    ),
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let screenshot = options.screenshot.clone();
    let timing = iscene::viewer::view(&iscene::viewer::ViewOptions { layers, ..options })?;
    if let (Some(path), Some(t)) = (screenshot, timing) {
        println!(
            "{} ({} frames after the first in {:.2} s: {:.1} frames/s)",
            path.display(),
            t.frames,
            t.seconds,
            t.frames_per_s()
        );
    }
    Ok(())
}

/// `view --replay` on a specification or sequence: reconstruct it first, into out/<name> as
/// `iscene reconstruct` does by default (the oracle segmentation where ground-truth labels
/// exist, geometry only otherwise).
#[cfg(feature = "viewer")]
fn reconstruct_for_replay(input: &std::path::Path, progress: bool) -> Result<PathBuf, IsceneError> {
    let stem = input
        .file_stem()
        .map_or("replay".into(), |s| s.to_string_lossy().into_owned());
    let out = PathBuf::from("out").join(stem);
    let labelled =
        input.extension().is_some_and(|e| e == "json") || input.join("labels.json").is_file();
    reconstruct(&ReconstructOptions {
        segmentation: if labelled {
            SegmentationChoice::Oracle
        } else {
            SegmentationChoice::None
        },
        progress,
        ..ReconstructOptions::new(input, &out)
    })?;
    eprintln!(
        "reconstructed {} into {}; replaying it",
        input.display(),
        out.display()
    );
    Ok(out)
}
