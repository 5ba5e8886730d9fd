//! `iscene render`, `generate` and `eval`: the commands about specifications and their truth.

use iscene::error::IsceneError;
use iscene::scene::generate::GenerateOptions;
use iscene::scene::{RenderOptions, SceneSpec, render_sequence};

use crate::args::{EvalArgs, GenerateArgs, RenderArgs};
use crate::print_json;

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
pub(crate) fn render(args: RenderArgs, interactive: bool) -> Result<(), IsceneError> {
    let RenderArgs {
        spec,
        out,
        frames,
        no_noise,
        force,
    } = args;
    let parsed = SceneSpec::load(&spec)?;
    let s = render_sequence(
        &parsed,
        &spec,
        &out,
        &RenderOptions {
            frames,
            no_noise,
            progress: interactive,
            force,
            fingerprint: None,
        },
    )?;
    println!(
        "rendered {} frames of {} ({} objects, {} triangles) into {} in {:.2} s ({:.1} frames/s)",
        s.frames,
        parsed.name,
        s.objects,
        s.triangles,
        s.dir.display(),
        s.seconds,
        s.frames as f64 / s.seconds.max(1e-9)
    );
    Ok(())
}

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
pub(crate) fn generate(args: GenerateArgs) -> Result<(), IsceneError> {
    let GenerateArgs {
        seed,
        out,
        style,
        cad,
        noise,
        frames,
    } = args;
    iscene::scene::spec::check_frame_count(frames)
        .map_err(|e| iscene::error::InputError::invalid("--frames", e))?;
    let options = GenerateOptions {
        seed,
        style,
        cad,
        noise,
        frames,
    };
    let generated = iscene::scene::generate::generate(&options, &out)?;
    iscene::scene::generate::write_generated(&out, &generated.json)?;
    println!(
        "wrote {}: {} objects, style {} (seed {seed})",
        out.display(),
        generated.objects,
        generated.style.name()
    );
    Ok(())
}

pub(crate) fn eval(args: EvalArgs) -> Result<(), IsceneError> {
    let report = iscene::eval::evaluate_reconstruction(&args.dir, &args.gt)?;
    print_json(&report)
}
