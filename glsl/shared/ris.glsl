// ris's part that every stage shares (each stage file, glsl/ris_<stage>.comp, includes it first):
// resampled importance sampling over the VPLs (Talbot et al. 2005), with spatial and temporal reuse
// (Bitterli et al. 2020; generalized RIS, Lin et al. 2022). crates/graph/src/passes/ris.rs states the
// estimator and why it is unbiased. The target is the unshadowed contribution's luminance at the pixel,
//   p̂_x(v) = luminance(albedo(x)/π · Φ_v · (cos θ_v / π) · cos θ_x · k(d²)) (k: the VPL kernel, shared/vpl.glsl),
// the source is the gather's mixture (draw_vpl, its exact probability p_v). The stages, in frame order:
// ris_presample (the candidate pool), ris_initial (candidates into reservoirs), ris_temporal (last
// frame's reservoirs), ris_spatial (the neighbours'), ris_shade (the shadow rays and the sum); each
// file's header states its dispatch. Here: the push constants, the bindings every stage reads (G-buffer,
// VPLs, importance and CDF), the reservoirs' layout and random numbers, the target and the learned
// visibility's cells.
#ifndef BOUNCE_RIS_GLSL
#define BOUNCE_RIS_GLSL
#include "scene.glsl"
#include "voxel.glsl"
#ifdef EXACT_VISIBILITY
#include "bvh.glsl"
#endif

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(push_constant) uniform Push {
    GatherPush pc;
    RisPush ris;
};

layout(set = 0, binding = B_GATHER_GPOSITION) uniform sampler2D g_position;
layout(set = 0, binding = B_GATHER_GNORMAL) uniform sampler2D g_normal;
layout(set = 0, binding = B_GATHER_GALBEDO) uniform sampler2D g_albedo;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(set = 0, binding = B_VPL_NORMAL) uniform sampler2DArray vpl_normal;
layout(set = 0, binding = B_VPL_FLUX) uniform sampler2DArray vpl_flux;
layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(set = 0, binding = B_CDF) uniform usamplerBuffer cdf_texels;

#define CDF_SHAPE_FROM_FRAME
#include "cdf.glsl"
#include "vpl.glsl"
#include "sampling.glsl"

// Where reservoir `layer` of pixel q lives (layer-major: one layer is one image of reservoirs).
uint res_index(ivec2 q, uint layer) {
    return layer * frame.size.x * frame.size.y + uint(q.y) * frame.size.x + uint(q.x);
}

// A uniform in [0, 1) that depends on (pixel, frame seed, stream, index) only: reservoir choices, apart
// from the candidates' own stratified numbers.
float ris_rand(ivec2 q, uint stream, uint i) {
    uint h = pcg_hash(uint(q.x) + 65536u * uint(q.y)) ^ pcg_hash(pc.seed ^ 0x2545F491u);
    h = pcg_hash(h ^ pcg_hash(stream * 0x9E3779B9u + i));
    return float(h >> 8) * (1.0 / 16777216.0);
}

// The target p̂ of pixel geometry (x, n, a) for VPL v: the unshadowed contribution's luminance (a target
// may be anything positive wherever the integrand is; the shade tests the frame's real visibility).
// Deterministic per pixel, so the spatial weights evaluate the same p̂ at each neighbour.
// Split as p̂ = luminance(a ⊙ Φ_v) · target_geometry: the candidates' loop needs the geometric factor for
// the control variate's U_g too.
float target_geometry(vec3 x, vec3 n, Vpl vpl) {
    return vpl_unshadowed_geometry(x, n, vpl, pc.clamp_d2);
}

float target_of(vec3 x, vec3 n, vec3 a, Vpl vpl) {
    return dot(vpl_luminance_albedo(a), vpl.flux) * target_geometry(x, n, vpl);
}

float target_at(vec3 x, vec3 n, vec3 a, uint v) {
    return target_of(x, n, a, vpl_fetch(v));
}

// The learned visibility's counts for pixel q and VPL v: (visible, traced) at vis_counts[i], [i + 1] with
// i = vis_tile_base(q) + 2 · vis_cell_of(v), for q's screen tile (vis_tile pixels per side) and v's
// light-map cell (vis_cell texels per side). Split so a loop over candidates divides only once per pixel
// for the tile (llvmpipe divides integers lane by lane); only the learned variant computes cells.
uint vis_side() {
    return (frame.size.w + ris.vis_cell - 1u) / ris.vis_cell;
}

// The cell of texel (tx, ty) of light-map layer `layer`.
uint vis_cell_at(uint layer, uint tx, uint ty) {
    uint side = vis_side();
    return (layer * side + udiv(ty, ris.vis_cell)) * side + udiv(tx, ris.vis_cell);
}

// The quotients (a layer, a row) are far below 2^21, so udiv is exact.
uint vis_cell_of(uint v) {
    uint res = frame.size.w, face = res * res;
    uint layer = udiv(v, face), r = v - layer * face, ty = udiv(r, res);
    return vis_cell_at(layer, r - ty * res, ty);
}

uint vis_tile_base(ivec2 q) {
    uint tiles_x = (frame.size.x + ris.vis_tile - 1u) / ris.vis_tile;
    uint tile = (uint(q.y) / ris.vis_tile) * tiles_x + uint(q.x) / ris.vis_tile;
    uint side = vis_side();
    return 2u * tile * (lm_faces() * frame.size.z * side * side);
}

#ifdef RIS_LEARNED_READ
// The reuse stages' view of the learned visibility (ris.learned > 0; a stand-in is bound when off):
// for pixel q's screen tile and VPL v, x = max(V̂, δ_L) with V̂ = (visible + 1) / (traced + 2), the
// target's factor (as the initial stage's), and y = visible / (traced + 1), the control's visibility
// guess s. From earlier frames' counts only (this frame's shade adds after the reuse stages read them).
layout(set = 0, binding = B_RIS_VIS) uniform usamplerBuffer vis_texels;

vec2 learned_at(ivec2 q, uint v) {
    if (!(ris.learned > 0.0)) return vec2(1.0);
    uint vi = vis_tile_base(q) + 2u * vis_cell_of(v);
    uint seen = texelFetch(vis_texels, int(vi)).r, traced = texelFetch(vis_texels, int(vi + 1u)).r;
    return vec2(max(float(seen + 1u) / float(traced + 2u), ris.learned), float(seen) / float(traced + 1u));
}
#endif

Reservoir empty_reservoir(float confidence) {
    return Reservoir(RIS_NONE, 0.0, confidence, 0.0);
}

#endif
