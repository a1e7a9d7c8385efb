#version 460
// cdf_reduce: importance per texel → a two-level CDF (per-row inclusive prefixes, then a prefix over the
// row totals). Stage CDF_ROWS: one invocation per row; CDF_TOTALS: one per face; CDF_TOTAL: one. See
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
    } else if (pc.stage == CDF_TOTALS) {
        // The prefix over row totals restarts at each face (every `len` rows): a face's rows are then
        // resolved against the face's own total, not against everything before it. One invocation a face
        // keeps each loop to `len` iterations (one invocation over all rows passed lavapipe's loop limit
        // with many lights' cube maps, which cut it silently: workarounds.rs).
        uint first = gl_GlobalInvocationID.x * len;
        if (first >= rows) return;
        float acc = 0.0;
        for (uint r = first; r < min(first + len, rows); r++) {
            acc += cdf[out_base + CDF_HEADER + r];
            cdf[out_base + CDF_HEADER + r] = acc;
        }
    } else {
        if (gl_GlobalInvocationID.x != 0u) return;
        // The total is the sum of the face totals (each face's last prefix), in face order (a last face may
        // be short: a CDF of fewer rows than a row's length).
        float total = 0.0;
        for (uint start = 0u; start < rows; start += len) total += cdf[out_base + CDF_HEADER + min(start + len, rows) - 1u];
        cdf[out_base] = total;
        cdf[out_base + 1u] = uintBitsToFloat(rows);
        cdf[out_base + 2u] = uintBitsToFloat(len);
        cdf[out_base + 3u] = 0.0;
    }
}
