//! The paraboloid maps of a renderer rendered alone, read back (test-only entry points, kept out of the
//! renderer): a graph with just the `dprsm` or `dprsm_depth` pass, on the renderer's passes and frame
//! inputs.

use anyhow::Result;
use bounce_device::Image;
use bounce_graph::frame::{FrameSettings, Renderer};
use bounce_graph::graph::{Graph, Handle};

/// The direct light's paraboloid depth map: distance / far per texel, layer after layer.
pub fn render_dprsm(r: &Renderer, s: &FrameSettings) -> Result<Vec<f32>> {
    r.check(s)?;
    let uniforms = r.uniform_buffer(s)?;
    let f = r.frame_inputs(s, &uniforms);
    let mut g = Graph::new(&r.gpu);
    let shadow = r.passes.dprsm.add_depth(&mut g, f);
    g.export(&shadow.depth);
    let done = g.execute()?;
    Ok(bytemuck::pod_collect_to_vec(&done.read_image(&shadow.depth)?))
}

/// The reflective DPRSM: (position, normal, flux) RGBA32F per texel, layer after layer.
pub fn render_vpls(r: &Renderer, s: &FrameSettings) -> Result<[Vec<[f32; 4]>; 3]> {
    r.check(s)?;
    let uniforms = r.uniform_buffer(s)?;
    let f = r.frame_inputs(s, &uniforms);
    let mut g = Graph::new(&r.gpu);
    let v = r.passes.dprsm.add(&mut g, f);
    for h in [&v.position, &v.normal, &v.flux] {
        g.export(h);
    }
    let done = g.execute()?;
    let read = |h: &Handle<Image>| -> Result<Vec<[f32; 4]>> { Ok(bytemuck::pod_collect_to_vec(&done.read_image(h)?)) };
    Ok([read(&v.position)?, read(&v.normal)?, read(&v.flux)?])
}
