#version 460
// cdf_reduce: importance per texel → a two-level CDF (per-row inclusive prefixes, then a prefix over the
// row totals). Stage CDF_ROWS: one invocation per row; stage CDF_TOTALS: one invocation. See
// crates/graph/src/passes/cdf_reduce.rs for why two levels.
#include "shared/types.glsl"
#include "shared/bindings.glsl"

layout(local_size_x = WG_1D) in;
layout(push_constant) uniform Push { CdfPush pc; };
layout(std430, set = 0, binding = B_IMPORTANCE) readonly buffer Importance { float importance[]; };
layout(std430, set = 0, binding = B_CDF_OUT) buffer Cdf { float cdf[]; };

void main() {
    uint rows = pc.rows, len = pc.row_length;
    // Section s: importance at s·rows·len, its CDF at s·(header + rows + rows·len).
    uint in_base = pc.section * rows * len;
    uint out_base = pc.section * (CDF_HEADER + rows + rows * len);
    if (pc.stage == CDF_ROWS) {
        uint r = gl_GlobalInvocationID.x;
        if (r >= rows) return;
        float acc = 0.0;
        uint base = out_base + CDF_HEADER + rows + r * len;
        for (uint i = 0u; i < len; i++) {
            float x = importance[in_base + r * len + i];
            acc += (x > 0.0 && x < 1e30) ? x : 0.0;
            cdf[base + i] = acc;
        }
        cdf[out_base + CDF_HEADER + r] = acc; // the row total, turned into a prefix by CDF_TOTALS
    } else {
        if (gl_GlobalInvocationID.x != 0u) return;
        // The prefix over row totals restarts at each face (every `len` rows): a face's rows are then
        // resolved against the face's own total, not against everything before it. The total is the sum
        // of the face totals, in face order.
        float acc = 0.0, total = 0.0;
        for (uint r = 0u; r < rows; r++) {
            if (r % len == 0u) {
                total += acc;
                acc = 0.0;
            }
            acc += cdf[out_base + CDF_HEADER + r];
            cdf[out_base + CDF_HEADER + r] = acc;
        }
        total += acc;
        cdf[out_base] = total;
        cdf[out_base + 1u] = uintBitsToFloat(rows);
        cdf[out_base + 2u] = uintBitsToFloat(len);
        cdf[out_base + 3u] = 0.0;
    }
}
