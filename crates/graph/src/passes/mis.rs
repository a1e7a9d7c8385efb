//! mis: multiple importance sampling of cosine gathering and gbg CDF sampling (thesis §7.4), with both
//! strategies' densities in one measure (solid angle), balance heuristic. The estimator, the one-measure
//! densities and the thesis's literal weights (`--mis-weights thesis`, for comparison) are stated in
//! `glsl/mis.comp`. Same inputs, outputs and dispatch as `gather` (its recording is reused); `first` /
//! `last` count the n_c CDF samples and then the n_g rays, so the loop-limit split covers both.
//!
//! The gathering strategy picks VPL v with probability q_g(ω_v) · Ω_v only up to the voxel march (the
//! hit is known to a cell) and the patch model A_v = Δω d_l² / cos α_v; where those are off, the MIS
//! estimate is not exactly unbiased with respect to `all` (measured in BENCHMARKS.md and the tests).

use super::gather::Gather;
use crate::shaders;
use anyhow::Result;
use bounce_device::Gpu;

/// The `mis` pass: the gather's recording with `glsl/mis.comp`.
pub fn create(gpu: &Gpu) -> Result<Gather> {
    Gather::with_shaders(gpu, "mis", shaders::MIS_COMP, shaders::MIS_EXACT_COMP)
}
