// The VPL map at each light (`--light-map`, thesis §6.3, Tables 6.3/6.4): which directions its faces
// cover, how a texel maps to a direction and back, and each texel's solid angle. Included by scene.glsl.
//   LIGHT_MAP_DPRSM: two paraboloid faces, ±z (the thesis's choice; the default). A texel (u, v) of the
//     unit disk looks along paraboloid_direction(u, v); Δω = 4 / (1 + u² + v²)² · (2/res)².
//   LIGHT_MAP_RSM: one perspective face of field of view 2·atan(t) (t = tan(fov/2), default fov 90°),
//     looking from the light at the centre of the scene's bounds: what lies outside is never a VPL.
//   LIGHT_MAP_CUBE: six perspective faces of 90° (t = 1) along ±x, ±y, ±z.
// A perspective texel (u, v) ∈ [−1, 1]² looks along normalize(u·t, v·t, 1) in its face's frame and
// subtends Δω = (2t/res)² / (1 + t²(u² + v²))^{3/2}.
// Face frames: local = (dot(d, X), dot(d, Y), dot(d, Z)) for the face's axes X, Y, Z (Z the view axis).
#ifndef BOUNCE_LIGHTMAP_GLSL
#define BOUNCE_LIGHTMAP_GLSL

uint lm_kind() { return frame.light_map.x; }
uint lm_faces() { return frame.light_map.y; }
float lm_tan() { return uintBitsToFloat(frame.light_map.z); }

// The frame's VPL slots: every light's faces (faces() in all), each res rows (face_rows()) of res texels;
// the shape of the importance arrays and of each CDF section (shared/cdf.glsl, CDF_SHAPE_FROM_FRAME).
uint face_rows() { return frame.size.w; }
uint faces() { return lm_faces() * frame.size.z; }
uint vpl_slots() { return faces() * face_rows() * face_rows(); }

// The axes (X, Y, Z) of face `face` of light `l`.
void lm_axes(uint l, uint face, out vec3 X, out vec3 Y, out vec3 Z) {
    uint kind = lm_kind();
    if (kind == LIGHT_MAP_DPRSM) {
        X = vec3(1.0, 0.0, 0.0);
        Y = vec3(0.0, 1.0, 0.0);
        Z = vec3(0.0, 0.0, face == 0u ? 1.0 : -1.0);  // as to_face: a mirror, not a rotation
        return;
    }
    if (kind == LIGHT_MAP_CUBE) {
        uint axis = face / 2u;
        float s = (face % 2u == 0u) ? 1.0 : -1.0;
        Z = vec3(0.0);
        Z[axis] = s;
    } else {
        vec3 centre = 0.5 * (frame.scene_min.xyz + frame.scene_max.xyz);
        vec3 d = centre - lights[l].position.xyz;
        // Down where the light sits at the centre, within 1e-6 of the scene's diagonal (relative, so the
        // same at every scale: an absolute threshold in world units turned the map between scales).
        float diagonal = frame.scene_min.w;
        Z = dot(d, d) > 1e-12 * diagonal * diagonal ? unit_direction(d) : vec3(0.0, -1.0, 0.0);
    }
    tangent_basis(Z, X, Y);
}

vec3 lm_to_local(vec3 d, uint l, uint face) {
    vec3 X, Y, Z;
    lm_axes(l, face, X, Y, Z);
    return vec3(dot(d, X), dot(d, Y), dot(d, Z));
}

vec3 lm_from_local(vec3 q, uint l, uint face) {
    vec3 X, Y, Z;
    lm_axes(l, face, X, Y, Z);
    return q.x * X + q.y * Y + q.z * Z;
}

// Map coordinates (u, v) of a local direction with z > 0 (perspective) or z >= 0 (paraboloid).
vec2 lm_project(vec3 local) {
    if (lm_kind() == LIGHT_MAP_DPRSM) return paraboloid_project(local);
    return local.xy / (local.z * lm_tan());
}

// The unit local direction of map coordinates (u, v).
vec3 lm_direction(vec2 uv) {
    if (lm_kind() == LIGHT_MAP_DPRSM) return paraboloid_direction(uv);
    return normalize(vec3(uv * lm_tan(), 1.0));
}

// Whether map coordinates (u, v) are inside the face (the paraboloid's disk; the perspective square).
bool lm_covers(vec2 uv) {
    return lm_kind() == LIGHT_MAP_DPRSM ? dot(uv, uv) <= 1.0 : all(lessThanEqual(abs(uv), vec2(1.0)));
}

// Where in its texel layer `layer`'s rays pass, in texels: `offset` (layer 0's, in [0, 1)²) moved on by
// the R2 sequence's step per layer and wrapped, so that each layer's offset is uniform in the texel when
// layer 0's is, and the layers of one light do not share it.
// (crates/graph/src/frame/keys.rs has the host's twin.)
vec2 texel_offset(vec2 offset, uint layer) {
    return fract(offset + float(layer) * vec2(VPL_OFFSET_STEP_X, VPL_OFFSET_STEP_Y));
}

// Solid angle of the texel centred at (u, v) of a res² face (with u, v anywhere in the texel: the
// Jacobian there times the texel's area in map coordinates).
float lm_d_omega(vec2 uv, float res) {
    float r2 = dot(uv, uv);
    if (lm_kind() == LIGHT_MAP_DPRSM) return 4.0 / ((1.0 + r2) * (1.0 + r2)) * (2.0 / res) * (2.0 / res);
    float t = lm_tan();
    float q = 1.0 + t * t * r2;
    return (2.0 * t / res) * (2.0 * t / res) / (q * sqrt(q));
}

// The face of light l whose map sees direction d (from the light), and its map coordinates; false when
// no face covers d (outside the RSM's field of view).
bool lm_locate(vec3 d, uint l, out uint face, out vec2 uv) {
    uint kind = lm_kind();
    if (kind == LIGHT_MAP_DPRSM) {
        face = d.z >= 0.0 ? 0u : 1u;
        uv = paraboloid_project(to_face(d, face));
        return true;
    }
    if (kind == LIGHT_MAP_CUBE) {
        vec3 a = abs(d);
        uint axis = a.x >= a.y && a.x >= a.z ? 0u : (a.y >= a.z ? 1u : 2u);
        face = 2u * axis + (d[axis] >= 0.0 ? 0u : 1u);
    } else {
        face = 0u;
    }
    vec3 local = lm_to_local(d, l, face);
    if (!(local.z > 0.0)) return false;
    uv = lm_project(local);
    return lm_covers(uv);
}

#endif
