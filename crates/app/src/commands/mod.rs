//! One module per command; each `run` takes the parsed arguments and the two output streams, and
//! returns an error for `crate::error` to report. What several commands do alike lives here.

pub mod bench;
pub mod compare;
pub mod info;
pub mod render;
pub mod view;

use anyhow::Result;
use bounce_device::Gpu;
use bounce_graph::scene::Scene;
use std::io::Write;
use std::path::Path;

/// Loads the scene and prints its one-line summary on `err`. A scene that does not load is a
/// `SceneError`, which the exit-code policy counts as bad input.
fn load_scene(path: &Path, err: &mut dyn Write) -> Result<Scene> {
    let scene = Scene::load(path)?;
    writeln!(err, "{}", scene.summary())?;
    Ok(scene)
}

/// With `--validation`, fails if the layers reported anything during the command.
fn check_validation(gpu: &Gpu, validation: bool) -> Result<()> {
    if validation {
        let msgs = gpu.validation().messages();
        anyhow::ensure!(msgs.is_empty(), "{} validation message(s); first: {}", msgs.len(), msgs[0]);
    }
    Ok(())
}
