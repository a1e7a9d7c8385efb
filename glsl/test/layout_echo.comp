#version 460
// Test kernel: reads every shared struct at the offsets GLSL gives it and writes each scalar, in
// declaration order, to a flat word array. The test fills the input from the Rust mirror
// (crates/graph/src/shader_types.rs) with distinct values and expects the words in Rust's field order:
// any offset or padding disagreement shows up as a mismatch.
#include "../shared/types.glsl"

layout(local_size_x = 1) in;
layout(std430, set = 0, binding = 0) readonly buffer In {
    Vertex v;
    Material m;
    TextureInfo t;
    Light l;
    FrameUniforms f;
    // The push constant structs (push constant blocks are laid out as std430, like this buffer).
    GatherPush gp;
    PsmView pv;
    ImportancePush ip;
    CdfPush cp;
    VoxelizePush vp;
    ParaboloidPush pp;
    PresentPush pr;
    ReprojectPush rp;
    DenoisePush dp;
};
layout(std430, set = 0, binding = 1) writeonly buffer Out { uint words[]; };

uint k = 0u;
void put4(vec4 x) { for (int i = 0; i < 4; i++) words[k++] = floatBitsToUint(x[i]); }
void put4u(uvec4 x) { for (int i = 0; i < 4; i++) words[k++] = x[i]; }

void main() {
    put4(v.position_u);
    put4(v.normal_v);
    put4(m.kd_tex);
    put4u(uvec4(t.offset, t.width, t.height, t.pad));
    put4(l.position);
    put4(l.intensity);
    for (int c = 0; c < 4; c++) put4(f.view_proj[c]);
    put4(f.eye);
    put4(f.scene_min);
    put4(f.scene_max);
    put4u(f.size);
    put4u(f.maps);
    put4(f.shadow);
    put4(f.voxel_origin);
    put4u(f.voxel_dims);
    put4u(f.light_map);
    put4(f.vpl);
    for (int c = 0; c < 4; c++) put4(f.prev_view_proj[c]);
    put4(f.camera);
    put4u(uvec4(gp.mode, gp.samples, gp.seed, gp.first));
    put4u(uvec4(gp.last, gp.accumulate, gp.add_direct, floatBitsToUint(gp.clamp_d2)));
    put4u(uvec4(gp.sections, floatBitsToUint(gp.defensive), gp.face_mode, gp.cdf_len));
    put4u(uvec4(gp.rays, gp.end_balls, floatBitsToUint(gp.near_share), gp.near_radius));
    put4(pv.position_v);
    put4(pv.normal_p);
    put4u(uvec4(ip.mode, ip.samples, ip.seed, ip.regions));
    put4u(uvec4(floatBitsToUint(ip.min_d2), floatBitsToUint(ip.fixed_scale), ip.section, ip.first));
    put4u(uvec4(cp.stage, cp.row_length, cp.rows, cp.section));
    put4u(uvec4(vp.cells_per_invocation, vp.first_triangle, pp.map_res, pp.pad));
    words[k++] = floatBitsToUint(pp.offset.x);
    words[k++] = floatBitsToUint(pp.offset.y);
    put4u(uvec4(pr.stage, floatBitsToUint(pr.frames), pr.reset, pr.swap_rb));
    put4u(uvec4(floatBitsToUint(pr.exposure), pr.groups, pr.prior, pr.pad));
    put4u(uvec4(rp.history, floatBitsToUint(rp.plane), floatBitsToUint(rp.normal), rp.pad0));
    put4u(uvec4(dp.history, dp.step, dp.last, dp.add_direct));
    put4(vec4(dp.alpha, dp.sigma_l, dp.sigma_n, dp.sigma_z));
}
