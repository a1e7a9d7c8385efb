// End balls: the part of a shadow ray next to each of its ends that needs no walk (crates/graph/src/passes/
// end_balls.rs makes them, the exact gather uses them). Include after bvh.glsl and common.glsl.
//
// An end p (a G-buffer point, or a VPL) lies on a triangle whose plane has unit normal n, turned to the side
// its ray leaves from (the camera's side for a pixel, the light's for a VPL). Its ball is (n, r): every
// triangle that comes within r of p lies at most τ(p) above that plane, i.e. all its vertices v have
// n·(v − p) ≤ τ(p), with τ(p) = surface_lift(p)/16. A segment a → b with n·(a − p) > 2τ and n·(b − p) > 2τ
// lies more than 2τ above the plane all along (the height is linear along it), so inside the ball it meets no
// triangle: those there lie at or below τ, the others do not reach into the ball. The walk may then start
// where the segment leaves the ball (end_ball_exit) and still give the same answer. A shadow ray's ends are
// lifted off their surfaces by surface_lift (sampling.glsl), so both of its ends are that high above either
// end's plane unless the ray leaves at a grazing angle, and then the ball is simply not used.
//
// The margins: τ and 2τ are 1/16 and 1/8 of the lift (≥ 1e-5 of the scene diagonal), where f32 rounding of a
// height over a ball's radius (≤ END_BALL_MAX_RADIUS of the diagonal) is below 1e-8 of the diagonal; and a
// stored radius is the nearest such triangle's distance less one lift, so rounding in a distance or in the
// exit parameter never moves the walk's start past the true ball.
#ifndef BOUNCE_END_BALLS_GLSL
#define BOUNCE_END_BALLS_GLSL

// How far above an end's plane a triangle may lie and still be inside its ball (see the header).
float end_ball_tau(vec3 p) {
    return surface_lift(p, frame.scene_min.w) * (1.0 / 16.0);
}

// The parameter along a → b at which the segment leaves the ball (xyz: the plane's normal, w: the radius)
// around end p, or 0 where the ball does not apply: no ball, a or b not more than 2τ above the plane, or a
// outside the ball.
float end_ball_exit(vec3 a, vec3 b, vec3 p, vec4 ball) {
    float tau2 = 2.0 * end_ball_tau(p);
    if (!(ball.w > 0.0) || !(dot(ball.xyz, a - p) > tau2) || !(dot(ball.xyz, b - p) > tau2)) return 0.0;
    vec3 d = b - a, f = a - p;
    // |f + t·d|² = r²: qa t² + 2 qb t + qc = 0, the exit root (−qb + √(qb² − qa·qc)) / qa, written without
    // cancellation for either sign of qb.
    float qa = dot(d, d), qb = dot(f, d), qc = dot(f, f) - ball.w * ball.w;
    if (!(qc < 0.0) || !(qa > 0.0)) return 0.0;
    float s = sqrt(qb * qb - qa * qc);
    float t = qb <= 0.0 ? (s - qb) / qa : -qc / (qb + s);
    return clamp(t, 0.0, 1.0);
}

#ifdef END_BALLS_READ
// The balls as the shadow rays read them (the gather, ris's shade, mis): per G-buffer pixel and per VPL
// texel (passes/end_balls.rs), 0 where there is none. The includer's push constants `pc` (a GatherPush) say
// whether they are bound (pc.end_balls; stand-ins otherwise, never read).
layout(set = 0, binding = B_END_BALL_PIXELS) uniform sampler2D end_ball_pixels;
layout(set = 0, binding = B_END_BALL_VPLS) uniform sampler2DArray end_ball_vpls;

vec4 end_ball_of_vpl(uint v) {
    uint res = frame.size.w;
    return texelFetch(end_ball_vpls, ivec3(v % res, (v / res) % res, v / (res * res)), 0);
}

// Pixel px's ball, 0 when the balls are off.
vec4 end_ball_of_pixel(ivec2 px) {
    return pc.end_balls != 0u ? texelFetch(end_ball_pixels, px, 0) : vec4(0.0);
}

// The part of the shadow ray o → e to walk (a window for bvh_any_hit or shadow_queue_window): with the balls
// off, bvh_occluded_lifted's (BVH_LIFTED_EPS, 1 − BVH_LIFTED_EPS); with them on, that less x's ball (x_ball,
// x the surface point o was lifted from) and VPL v's (y its unlifted position, e lifted from it).
vec2 end_ball_window(vec3 o, vec3 e, vec3 x, vec4 x_ball, uint v, vec3 y) {
    vec2 w = vec2(BVH_LIFTED_EPS, 1.0 - BVH_LIFTED_EPS);
    if (pc.end_balls == 0u) return w;
    return vec2(max(w.x, end_ball_exit(o, e, x, x_ball)), min(w.y, 1.0 - end_ball_exit(e, o, y, end_ball_of_vpl(v))));
}
#endif

#ifdef END_BALLS_PASS
// Distance from p to triangle (a, b, c): its closest point by Voronoi regions (Ericson, Real-Time Collision
// Detection, 5.1.5).
float end_ball_tri_distance(vec3 p, vec3 a, vec3 b, vec3 c) {
    vec3 ab = b - a, ac = c - a, ap = p - a;
    float d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return distance(p, a);
    vec3 bp = p - b;
    float d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return distance(p, b);
    float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return distance(p, a + ab * (d1 / (d1 - d3)));
    vec3 cp = p - c;
    float d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return distance(p, c);
    float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return distance(p, a + ac * (d2 / (d2 - d6)));
    float va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
        return distance(p, b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    float denom = 1.0 / (va + vb + vc);
    return distance(p, a + ab * (vb * denom) + ac * (vc * denom));
}

// The radius of end p's ball for plane normal n (see the header), at most `rmax`: a walk of the threaded
// records (bvh.glsl) that enters a box only if it comes nearer than the nearest triangle found so far and
// reaches more than τ above the plane. 0 (no ball) if the walk has not finished after END_BALL_MAX_STEPS
// records.
float end_ball_radius(vec3 p, vec3 n, float rmax) {
    float tau = end_ball_tau(p);
    int end = bvh_thread_records();
    float best = rmax;
    int i = 0;
    for (uint k = 0u; k < uint(END_BALL_MAX_STEPS) && i < end; k++) {
        uvec4 a = texelFetch(bvh_threaded, 3 * i);
        vec3 lo = uintBitsToFloat(a.xyz);
        vec3 b = uintBitsToFloat(texelFetch(bvh_threaded, 3 * i + 1).xyz);
        if (a.w == BVH_THREAD_TRI) {
            vec3 c = uintBitsToFloat(texelFetch(bvh_threaded, 3 * i + 2).xyz);
            if (max(dot(n, lo - p), max(dot(n, b - p), dot(n, c - p))) > tau)
                best = min(best, end_ball_tri_distance(p, lo, b, c));
            i++;
        } else {
            // The box [lo, b]: its point nearest p, and its corner highest above the plane.
            vec3 q = clamp(p, lo, b) - p;
            vec3 top = mix(lo, b, greaterThan(n, vec3(0.0)));
            i = dot(q, q) < best * best && dot(n, top - p) > tau ? i + 1 : int(a.w);
        }
    }
    if (i < end) return 0.0;
    return max(best - surface_lift(p, frame.scene_min.w), 0.0);
}
#endif

#endif
