#version 460
// importance: one weight per DPRSM texel, the input of cdf_reduce. Mode 0 (uniform): 1 for every texel
// that holds a VPL, 0 for empty ones. Dispatch: res × res × (2 × lights).
#include "shared/scene.glsl"

layout(local_size_x = WG_2D, local_size_y = WG_2D) in;
layout(set = 0, binding = B_VPL_POSITION) uniform sampler2DArray vpl_position;
layout(std430, set = 0, binding = B_IMPORTANCE) writeonly buffer Importance { float importance[]; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    uint res = frame.size.w;
    if (id.x >= res || id.y >= res) return;
    uint v = (id.z * res + id.y) * res + id.x;
    importance[v] = texelFetch(vpl_position, ivec3(id), 0).w > 0.0 ? 1.0 : 0.0;
}
