//! cdf_reduce: per-texel importance → a normalisable two-level CDF for inverse-transform sampling.
//!
//! Input: `importance` (`rows × row_length` floats; a row is one texel row of one DPRSM face, so
//! `rows = 2 · lights · res`). Output: `cdf`, floats laid out as `glsl/shared/cdf.glsl` reads them:
//! a `CDF_HEADER`-float header (total, rows, row length), the inclusive prefix over row totals (`rows` floats),
//! then each row's inclusive prefix (`rows × row_length` floats). Dispatch: ⌈rows/64⌉ groups for the
//! row prefixes (one invocation per row), then one invocation per face for the prefix over its row totals,
//! then one for the sum of the face totals, each dispatch serialized after the previous one
//! by the graph ([`crate::graph::PassContext::serialize`]).
//!
//! **Why two levels (and not one flat float32 prefix).** A flat prefix over 2 × 1024² texels adds
//! ~2·10⁶ terms into one float32 accumulator: late texels' masses fall below the accumulator's ulp and
//! the CDF stops resolving them. Here no sum has more than max(rows, row_length) ≤ 2048 terms per light
//! pair; the prefix over row totals restarts at each face (`row_length` rows), so a face is resolved
//! against its own total. The sampler draws face, row and texel with one uniform each, and the estimator divides
//! by the probability computed from the same float prefixes the search reads (`cdf_prob_rows` in
//! `glsl/shared/cdf.glsl`), exact up to the 24-bit resolution of each uniform against its own total. Negative, NaN and infinite weights count as 0. The
//! sampling side (binary search, u = 0, u → 1, runs of zero-weight texels) is in `glsl/shared/cdf.glsl`.

use crate::bindings::*;
use crate::graph::{Graph, Handle};
use crate::shader_types::CdfPush;
use crate::shaders;
use anyhow::Result;
use bounce_device::sync::Access;
use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites, Gpu};

pub struct CdfReduce {
    pipeline: ComputePipeline,
}

impl CdfReduce {
    pub fn new(gpu: &Gpu) -> Result<Self> {
        let bindings = [Binding::storage_buffer(B_IMPORTANCE), Binding::storage_buffer(B_CDF_OUT)];
        let pipeline = ComputePipeline::new(
            gpu,
            "cdf_reduce",
            &crate::spirv(shaders::CDF_REDUCE_COMP),
            &bindings,
            std::mem::size_of::<CdfPush>() as u32,
            &[],
        )?;
        Ok(CdfReduce { pipeline })
    }

    /// Floats per CDF section.
    pub fn section_len(rows: u32, row_length: u32) -> u64 {
        CDF_HEADER as u64 + rows as u64 + rows as u64 * row_length as u64
    }

    /// The CDF of every section of `importance` (`sections` arrays of `rows × row_length` weights, one
    /// after the other; section s's CDF starts at float s · [`CdfReduce::section_len`]).
    pub fn add<'a>(
        &'a self,
        g: &mut Graph<'a>,
        importance: &Handle<Buffer>,
        rows: u32,
        row_length: u32,
        sections: u32,
    ) -> Handle<Buffer> {
        let n = Self::section_len(rows, row_length) * sections as u64;
        // Written here as a storage buffer; the samplers read it through its texel view (Buffer::texel_view:
        // llvmpipe's per-lane storage reads made the binary searches the gather's largest cost).
        let mut desc = BufferDesc::storage("cdf", 4 * n);
        desc.usage |= vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let mut cdf = g.create_buffer(desc);
        let (imp, out) = (*importance, cdf);
        g.add_pass("cdf_reduce").read(&imp, Access::ComputeRead).overwrite(&mut cdf, Access::ComputeWrite).record(
            move |ctx| {
                let writes = DescriptorWrites::new()
                    .storage_buffer(B_IMPORTANCE, ctx.buffer(&imp))
                    .storage_buffer(B_CDF_OUT, ctx.buffer(&out));
                let push = |stage, section| CdfPush { stage, row_length, rows, section };
                // Sections write disjoint ranges of `cdf`, but each dispatch binds the whole buffer, so
                // the graph serializes them (synchronization validation sees whole-buffer writes).
                for section in 0..sections {
                    if section > 0 {
                        ctx.serialize(&out);
                    }
                    let p = push(CDF_ROWS, section);
                    self.pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&p), [rows, 1, 1], [WG_1D, 1, 1]);
                }
                for section in 0..sections {
                    // The faces' prefixes read the row totals the rows stage wrote; the total reads the
                    // faces' totals.
                    ctx.serialize(&out);
                    let p = push(CDF_TOTALS, section);
                    let faces = rows.div_ceil(row_length.max(1));
                    self.pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&p), [faces, 1, 1], [WG_1D, 1, 1]);
                    ctx.serialize(&out);
                    let p = push(CDF_TOTAL, section);
                    self.pipeline.dispatch(ctx.cmd, &writes, bytemuck::bytes_of(&p), [1, 1, 1], [WG_1D, 1, 1]);
                }
            },
        );
        cdf
    }
}
