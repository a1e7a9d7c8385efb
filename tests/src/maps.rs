//! The paraboloid maps of a renderer rendered alone, read back (test-only entry points, kept out of the
//! renderer): a graph with just the `dprsm` pass (or the end balls), on the renderer's passes and frame
//! inputs.

use anyhow::Result;
use bounce_device::Image;
use bounce_graph::frame::{FrameSettings, Renderer};
use bounce_graph::graph::{Graph, Handle};

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

/// The end balls (`passes/end_balls.rs`) with the ends they belong to, RGBA32F per texel: per pixel the
/// G-buffer position, normal and ball; per VPL texel (layer after layer) the VPL position and ball.
pub struct EndBallMaps {
    pub g_position: Vec<[f32; 4]>,
    pub g_normal: Vec<[f32; 4]>,
    pub pixels: Vec<[f32; 4]>,
    pub vpl_position: Vec<[f32; 4]>,
    pub vpls: Vec<[f32; 4]>,
}

/// The G-buffer, the VPL maps and both end-ball passes, alone in a graph (settings with exact visibility,
/// the renderer's BVH).
pub fn render_end_balls(r: &Renderer, s: &FrameSettings) -> Result<EndBallMaps> {
    r.check(s)?;
    let uniforms = r.uniform_buffer(s)?;
    let f = r.frame_inputs(s, &uniforms);
    let mut g = Graph::new(&r.gpu);
    let gb = r.passes.gbuffer.add(&mut g, f);
    let v = r.passes.dprsm.add(&mut g, f);
    let pixels = r.passes.end_balls.add_pixels(&mut g, f, &gb)?;
    let vpls = r.passes.end_balls.add_vpls(&mut g, f, &v)?;
    for h in [&gb.position, &gb.normal, &pixels, &v.position, &vpls] {
        g.export(h);
    }
    let done = g.execute()?;
    let read = |h: &Handle<Image>| -> Result<Vec<[f32; 4]>> { Ok(bytemuck::pod_collect_to_vec(&done.read_image(h)?)) };
    Ok(EndBallMaps {
        g_position: read(&gb.position)?,
        g_normal: read(&gb.normal)?,
        pixels: read(&pixels)?,
        vpl_position: read(&v.position)?,
        vpls: read(&vpls)?,
    })
}
