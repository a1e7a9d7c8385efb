//! Regenerates the committed reference images under `tests/references/` with the exact CPU reference
//! renderer (`bounce_oracles::cpu_ref`: BVH ray casting, exact visibility). Not run by the tests, which
//! fail when a reference is missing instead of writing it.
//!
//!     cargo run -p bounce-tests --bin make-references

use bounce::output::{write_exr, RgbImage};
use bounce_graph::scene::Scene;
use bounce_oracles::cpu_ref;

fn main() -> anyhow::Result<()> {
    let root = bounce_tests::workspace();
    let scene = Scene::load(&root.join("assets/cornell-box/scene.toml"))?;
    let (w, h) = (64, 64);
    let pixels = cpu_ref::render_direct(&scene, w, h);
    let path = root.join("tests/references/cornell-direct-64.exr");
    let meta = [
        ("generator", "cpu_ref::render_direct (exact ray-cast visibility)".to_string()),
        ("component", "direct".into()),
    ];
    write_exr(&path, &RgbImage { width: w, height: h, pixels }, &meta)?;
    println!("wrote {}", path.display());
    Ok(())
}
