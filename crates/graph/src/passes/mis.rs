//! mis: multiple importance sampling of cosine gathering and gbg CDF sampling (thesis §7.4), with both
//! strategies' densities in one measure (solid angle), balance heuristic. The estimator, the one-measure
//! densities and the thesis's literal weights (`--mis-weights thesis`, for comparison) are stated in
//! `glsl/mis.comp`. Same inputs, outputs and dispatch as `gather` (its recording is reused); `first` /
//! `last` count the n_c CDF samples and then the n_g rays, so the loop-limit split covers both.
//!
//! Sample space: pairs (VPL v, point y of its patch Q_v⁺(x)): the texel's footprint on v's tangent
//! plane, cut to the part in front of the pixel's tangent plane, of area A_v⁺ (`glsl/shared/patch.glsl`),
//! with F(v, y) = c(v) / A_v⁺, so that Σ_v ∫ F dA = Σ_v c(v) exactly. The CDF strategy draws v by P_v and
//! y uniformly in Q_v⁺; a gathering ray names the texel its first hit projects into and y where it meets
//! that VPL's plane. Both densities are exact (a CDF sample re-runs the gathering ray map towards its
//! y), so the balance-heuristic estimate c(v) / (n_c P_v + n_g A_v⁺ p_g) is unbiased with respect to
//! `all` for either visibility; the tests `every_method_converges_to_all_at_the_monte_carlo_rate`,
//! `mis_is_unbiased_with_either_visibility_and_the_thesis_weights_are_not` and
//! `mis_is_unbiased_where_patches_reach_behind_a_junction` check it, and
//! `mis_front_part_is_the_clipped_square_and_its_points_are_uniform` checks Q_v⁺ against the exactly
//! clipped square.

use super::gather::Gather;
use crate::shaders;
use anyhow::Result;
use bounce_device::Gpu;

/// The `mis` pass: the gather's recording with `glsl/mis.comp`.
pub fn create(gpu: &Gpu) -> Result<Gather> {
    use shaders::*;
    Gather::with_shaders(gpu, "mis", [MIS_COMP, MIS_EXACT_COMP, MIS_PSM_COMP])
}
