//! `iscene cad generate` and `iscene cad import`: the CAD database.

use iscene::cad::import::body_tree::ImportScale;
use iscene::cad::import::{ModelFormat, import_model_files};
use iscene::error::IsceneError;

use crate::args::{CadCommand, ImportFormat};

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
pub(crate) fn cad(command: CadCommand) -> Result<(), IsceneError> {
    match command {
        CadCommand::Generate { into } => {
            iscene::io::output_folder::check_database_folder(&into, None)?;
            let n = iscene::cad::db::export::write_library(&into)?;
            println!(
                "wrote {n} parametric models (glb + json) and index.json into {}",
                into.display()
            );
        }
        CadCommand::Import {
            format,
            path,
            into,
            scale,
        } => {
            iscene::io::output_folder::check_database_folder(&into, Some(&path))?;
            let summary = match format {
                ImportFormat::Sh3d if scale.is_some() => {
                    return Err(iscene::error::InputError::invalid(
                            &path,
                            "--scale is for mjcf and urdf models: Sweet Home 3D catalogues give real sizes",
                        )
                        .into());
                }
                ImportFormat::Sh3d => iscene::cad::import::import_sh3d(&path, &into)?,
                ImportFormat::Mjcf => {
                    let scale = scale.unwrap_or(ImportScale::Class);
                    import_model_files(&path, &into, ModelFormat::Mjcf, scale)?
                }
                ImportFormat::Urdf => {
                    let scale = scale.unwrap_or(ImportScale::Factor(1.0));
                    import_model_files(&path, &into, ModelFormat::Urdf, scale)?
                }
            };
            println!("{summary}");
        }
    }
    Ok(())
}
