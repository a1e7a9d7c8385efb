//! The scene's BVH on the GPU: [`GpuBvh`] uploads the tree that `bounce_scene::bvh` builds and flattens
//! ([`FlatBvh`]; its module doc is the layout's contract) as three texel buffers, once per scene,
//! read-only afterwards, so the graph does not track it.

use anyhow::{Context, Result};
use bounce_device::{Binding, DescriptorWrites, Gpu, TexelBuffer};
use bounce_scene::bvh::{Bvh, FlatBvh, B_BVH_NODES, B_BVH_THREADED, B_BVH_TRIS, STACK_SIZE};
#[allow(unused_imports)] // named by the docs
use bounce_scene::bvh::{GpuBvhNode, GpuBvhTri, GpuThreadRec, MAX_STEPS};
use bounce_scene::scene::Scene;

/// The BVH on the GPU: uploaded once, read-only afterwards.
pub struct GpuBvh {
    /// [`GpuBvhNode`]s as two `uvec4` texels each, binding [`B_BVH_NODES`].
    pub nodes: TexelBuffer,
    /// [`GpuBvhTri`]s in leaf order as three `uvec4` texels each, binding [`B_BVH_TRIS`].
    pub tris: TexelBuffer,
    /// [`GpuThreadRec`]s ([`FlatBvh::threaded`]) as three `uvec4` texels each, binding [`B_BVH_THREADED`].
    pub threaded: TexelBuffer,
    pub node_count: u32,
    /// Scene triangles that can be hit (zero-area ones excluded).
    pub triangle_count: u32,
    /// Levels below the root (≤ [`STACK_SIZE`]).
    pub height: u32,
    max_iterations: u32,
    max_iterations_occluded: u32,
}

impl GpuBvh {
    /// Builds the SAH tree of `scene`, flattens and uploads it.
    pub fn new(gpu: &Gpu, scene: &Scene) -> Result<GpuBvh> {
        let bvh = Bvh::new(scene);
        GpuBvh::upload(gpu, &FlatBvh::new(&bvh, &scene.vertices))
    }

    /// Uploads a flattened tree (for a tree the caller already has, or a custom height limit).
    pub fn upload(gpu: &Gpu, flat: &FlatBvh) -> Result<GpuBvh> {
        anyhow::ensure!(flat.height <= STACK_SIZE, "BVH of height {} exceeds the stack ({STACK_SIZE})", flat.height);
        let up = |name: &str, bytes: &[u8]| {
            TexelBuffer::with_data(gpu, name, bytes).with_context(|| format!("uploading the {name}"))
        };
        Ok(GpuBvh {
            nodes: up("bvh nodes", bytemuck::cast_slice(&flat.nodes))?,
            tris: up("bvh triangles", bytemuck::cast_slice(&flat.tris))?,
            threaded: up("bvh threaded records", bytemuck::cast_slice(&flat.threaded()))?,
            node_count: flat.nodes.len() as u32,
            triangle_count: flat.triangle_count,
            height: flat.height,
            max_iterations: flat.max_iterations_per_ray(),
            max_iterations_occluded: flat.max_iterations_occluded(),
        })
    }

    /// An honest upper bound of the loop iterations one `bvh_closest` / `bvh_occluded` / `bvh_trace`
    /// call takes: min([`MAX_STEPS`], nodes + triangles + 1). Budget llvmpipe's per-invocation limit
    /// with it (module doc).
    pub fn max_iterations_per_ray(&self) -> u32 {
        self.max_iterations
    }

    /// An honest upper bound of the loop iterations of one `bvh_occluded` / `bvh_occluded_lifted` /
    /// `bvh_any_hit` call ([`FlatBvh::max_iterations_occluded`]).
    pub fn max_iterations_occluded(&self) -> u32 {
        self.max_iterations_occluded
    }

    /// The three descriptor bindings, for pipeline layouts.
    pub fn bindings() -> [Binding; 3] {
        [
            Binding::uniform_texel_buffer(B_BVH_NODES),
            Binding::uniform_texel_buffer(B_BVH_TRIS),
            Binding::uniform_texel_buffer(B_BVH_THREADED),
        ]
    }

    /// `w` with the three buffers bound.
    pub fn writes(&self, w: DescriptorWrites) -> DescriptorWrites {
        w.uniform_texel_buffer(B_BVH_NODES, &self.nodes)
            .uniform_texel_buffer(B_BVH_TRIS, &self.tris)
            .uniform_texel_buffer(B_BVH_THREADED, &self.threaded)
    }
}
