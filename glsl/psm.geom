#version 460
// psm's maps: bound the triangle's exact image on one VPL's paraboloid face and emit that box as a quad; the
// fragment shader (psm.frag) then intersects each texel's ray with the triangle. See crates/graph/src/passes/psm.rs.
#include "shared/scene.glsl"
#include "shared/map_depth.glsl"

layout(push_constant) uniform Push { ParaboloidPush pc; };

layout(triangles) in;
layout(triangle_strip, max_vertices = 4) out;

// The viewpoints: the frame's shared VPLs (psm.comp).
layout(std430, set = 0, binding = B_PSM_VIEWS) readonly buffer PsmViews { PsmView psm_views[]; };
#include "shared/psm.glsl"

layout(location = 0) in vec3 i_world[];
layout(location = 1) flat in uint i_instance[];

layout(location = 0) flat out vec3 o_a;
layout(location = 1) flat out vec3 o_b;
layout(location = 2) flat out vec3 o_c;

void include_uv(vec2 uv, inout vec2 lo, inout vec2 hi) {
    lo = min(lo, uv);
    hi = max(hi, uv);
}

// The light sees a segment a→b as a great-circle arc; its paraboloid image is a circular arc. Besides the
// end points, the arc's bounding box is set by the points where du/dφ = 0 (or dv/dφ = 0). With
// s(φ) = a cos φ + w sin φ and u = s.x / (1 + s.z), that condition reduces to
//   B cos φ − A sin φ = A E − B C   (A = a.x, B = w.x, C = a.z, E = w.z),
// solved in closed form below for each axis.
void include_arc(vec3 a, vec3 b, inout vec2 lo, inout vec2 hi) {
    float cos_t = clamp(dot(a, b), -1.0, 1.0);
    vec3 w = b - a * cos_t;
    float wl = length(w);
    if (wl < 1e-7) return;
    w /= wl;
    float theta = acos(cos_t);
    for (int axis = 0; axis < 2; axis++) {
        float A = a[axis], B = w[axis], C = a.z, E = w.z;
        float R = sqrt(A * A + B * B);
        if (R < 1e-12) continue;
        float rhs = (A * E - B * C) / R;
        if (abs(rhs) > 1.0) continue;
        float delta = atan(A, B);
        float base = acos(rhs);
        for (int k = 0; k < 2; k++) {
            float phi = mod((k == 0 ? base : -base) - delta, 2.0 * PI);
            if (phi <= theta) {
                vec3 s = a * cos(phi) + w * sin(phi);
                include_uv(s.xy / (1.0 + s.z), lo, hi);
            }
        }
    }
}

// The box's depth (shared/map_depth.glsl) is a lower bound on every depth the fragment shader writes for
// this triangle (which declares depth_greater): the depth test can then reject a hidden box's fragments
// before they run the texel ray, as it would a plain triangle's. Without it every texel of every box ran
// the fragment shader (the DPRSM passes were fill-bound).
void emit_box(vec3 p[3], uint inst, vec2 lo, vec2 hi) {
    vec2 corners[4] = vec2[4](vec2(lo.x, lo.y), vec2(hi.x, lo.y), vec2(lo.x, hi.y), vec2(hi.x, hi.y));
    float z = map_box_depth(p[0], p[1], p[2], frame.scene_max.w);
    for (int k = 0; k < 4; k++) {
        o_a = p[0];
        o_b = p[1];
        o_c = p[2];
        gl_Layer = int(inst);
        gl_Position = vec4(corners[k], z, 1.0);
        EmitVertex();
    }
    EndPrimitive();
}

void main() {
    uint inst = i_instance[0];
    vec3 p[3];
    PsmView view = psm_views[inst];
    if (!(view.normal_p.w > 0.0)) return;  // no VPL drawn: the map stays empty (never read)
    for (int k = 0; k < 3; k++) p[k] = psm_to_local(i_world[k] - view.position_v.xyz, view.normal_p.xyz);

    // Clip to this face's half-space z >= 0 (Sutherland–Hodgman against one plane: at most 4 vertices).
    vec3 poly[4];
    int n = 0;
    for (int k = 0; k < 3; k++) {
        vec3 a = p[k], b = p[(k + 1) % 3];
        if (a.z >= 0.0) poly[n++] = a;
        if ((a.z >= 0.0) != (b.z >= 0.0)) {
            vec3 m = mix(a, b, a.z / (a.z - b.z));
            m.z = 0.0;
            poly[n++] = m;
        }
    }
    if (n < 3) return;

    float far = frame.scene_max.w;
    vec2 lo = vec2(1e30), hi = vec2(-1e30);
    bool touches_light = false;
    for (int k = 0; k < n; k++) {
        if (length(poly[k]) < 1e-6 * far) touches_light = true;
    }
    if (touches_light) {
        // The light lies on the triangle: its image can fill the face. Take the whole face.
        lo = vec2(-1.0);
        hi = vec2(1.0);
    } else {
        for (int k = 0; k < n; k++) {
            vec3 a = normalize(poly[k]);
            vec3 b = normalize(poly[(k + 1) % n]);
            include_uv(a.xy / (1.0 + a.z), lo, hi);
            include_arc(a, b, lo, hi);
        }
        // Margin against rounding (the fragment test is exact anyway): half a texel.
        float margin = 1.0 / float(pc.map_res);
        lo = max(lo - margin, vec2(-1.0));
        hi = min(hi + margin, vec2(1.0));
    }
    if (any(greaterThan(lo, hi))) return;
    emit_box(p, inst, lo, hi);
}
