//! `iscene simulate`: run a task in a scene folder and print each step.

use iscene::error::IsceneError;

use crate::args::SimulateArgs;

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
pub(crate) fn simulate(args: SimulateArgs) -> Result<(), IsceneError> {
    let SimulateArgs {
        dir,
        task,
        out,
        force,
        robot,
    } = args;
    let summary = iscene::simulation::simulate(&iscene::simulation::SimulateOptions {
        dir,
        task,
        out,
        force,
        robot,
    })?;
    if let Some(plan) = &summary.plan {
        println!("plan ({} steps): {}", plan.len(), plan.join(" "));
    }
    for s in &summary.steps {
        let physics = s.physics.as_ref().map_or(String::new(), |p| {
            format!(", stable {:.2}", p.stable_fraction)
        });
        match &s.failed_precondition {
            None => println!(
                "{:>2} {:<36} {}{physics} ({:.0} ms: motion {:.0} ms, rest {:.0} ms)",
                s.step,
                s.action.label(),
                if s.part_way { "part of the way" } else { "ok" },
                s.wall_ms,
                s.motion_ms(),
                s.physics_ms
            ),
            Some(why) => println!("{:>2} {:<36} FAILED: {why}", s.step, s.action.label()),
        }
    }
    println!(
        "{} -> {}",
        if summary.success { "success" } else { "failed" },
        summary.output.display()
    );
    if !summary.success {
        std::process::exit(1);
    }
    Ok(())
}
