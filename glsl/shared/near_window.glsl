// The near window: a K × K window of light-map texels around where the pixel's point x projects into
// the map of each light, drawn uniformly: the VPLs next to x, whose kernel makes the integrand's tail
// (a concave edge's fireflies), are found there when the light sees x's surroundings. Light l's window
// opens only when the texel x projects to sees a point within the window's reach of x, r·√A (A its
// patch area): behind an occluder it would hold the occluder's lit side, which gives x nothing. A near
// draw first picks an open window with probability α_l ∝ luminance(I_l) / d_l², d_l the distance from
// light l to x (the radiosity of its VPLs next to x), then a texel of it. Every light's map has VPLs next
// to x, so every light's window is offered: with one window, a VPL of the other light's next to x was a
// rare draw with a huge weight (the clutter scene's fireflies). The first RIS_NEAR_LIGHTS lights get
// windows (NEAR_LIGHTS = RIS_NEAR_LIGHTS, a specialisation for scenes with more than one light; else
// one window, and a one-light scene pays nothing for the mixture); the other strategies cover the rest.
// All of it is fixed by x before any draw, so an estimate that mixes it in stays unbiased whichever
// windows open. Used by ris's initial stage (near candidates beside the pool) and by the CDF methods'
// sampling mixture (shared/sampling.glsl, the near share).
#ifndef BOUNCE_NEAR_WINDOW_GLSL
#define BOUNCE_NEAR_WINDOW_GLSL
layout(constant_id = SPEC_RIS_NEAR_LIGHTS) const uint NEAR_LIGHTS = 1u;

struct NearWindow {
    bool open;
    uint layer;  // the window's light-map layer (light · faces + face)
    ivec2 lo;    // its lowest texel
    float alpha; // the probability a near candidate picks this window (0: closed)
};

struct Near {
    NearWindow w[RIS_NEAR_LIGHTS]; // the first NEAR_LIGHTS are used (glslang sizes no copied array by a specialisation)
    uint n;     // windows computed (min(lights, NEAR_LIGHTS))
    bool open;  // any window open
    int size;   // K = min(2r + 1, res) texels a side
    float p;    // 1 / K²
};

NearWindow near_window_of(uint l, vec3 x, int size, uint radius) {
    NearWindow w;
    // Defined even where lm_locate finds no face (the window then stays closed).
    uint face = 0u;
    vec2 uv = vec2(0.0);
    int res = int(frame.size.w);
    vec3 d = x - lights[l].position.xyz;
    w.open = lm_locate(d, l, face, uv) && all(lessThan(abs(uv), vec2(2.0)));
    ivec2 c = clamp(ivec2(floor((uv * 0.5 + 0.5) * float(res))), ivec2(0), ivec2(res - 1));
    w.lo = clamp(c - ivec2(size / 2), ivec2(0), ivec2(res - size));
    w.layer = l * lm_faces() + face;
    vec4 seen = texelFetch(vpl_position, ivec3(c, int(w.layer)), 0);
    vec3 dx = seen.xyz - x;
    float reach2 = float(radius * radius) * seen.w;
    w.open = w.open && seen.w > 0.0 && dot(dx, dx) <= reach2;
    w.alpha = w.open ? luminance(lights[l].intensity.rgb) / max(dot(d, d), 1e-30) : 0.0;
    return w;
}

// Loops run to the constant NEAR_LIGHTS and branch on l < n inside, so that they unroll and every
// window is read at a constant index (llvmpipe keeps a dynamically indexed array in memory and reads
// it lane by lane, which halved the frame rate), and the branch, the same for every lane, skips the
// lights beyond the scene's (a select would evaluate them).
// The windows of x, `radius` texels to each side of x's texel.
Near near_windows(vec3 x, uint radius) {
    Near nw;
    int res = int(frame.size.w);
    nw.size = min(2 * int(radius) + 1, res);
    nw.p = 1.0 / float(nw.size * nw.size);
    nw.n = min(frame.size.z, uint(NEAR_LIGHTS));
    float total = 0.0;
    for (uint l = 0u; l < uint(NEAR_LIGHTS); l++) {
        nw.w[l] = NearWindow(false, 0u, ivec2(0), 0.0);
        if (l < nw.n) {
            nw.w[l] = near_window_of(l, x, nw.size, radius);
            total += nw.w[l].alpha;
        }
    }
    nw.open = total > 0.0;
    for (uint l = 0u; l < uint(NEAR_LIGHTS); l++) {
        if (l < nw.n) nw.w[l].alpha = nw.open ? nw.w[l].alpha / total : 0.0;
    }
    return nw;
}

// The texel of a near draw, a window by α (the uniform u_window) then a texel of it uniformly (u_texel),
// and its probability under the near strategy, α / K².
ivec3 near_texel(Near nw, float u_window, vec2 u_texel, out float p_near) {
    ivec2 lo = nw.w[0].lo;
    uint layer = nw.w[0].layer;
    float alpha = nw.w[0].alpha;
    if (NEAR_LIGHTS > 1u && nw.n > 1u) {
        // (The same for every lane.)
        float u = u_window, acc = 0.0;
        bool picked = false;
        for (uint j = 0u; j < uint(NEAR_LIGHTS); j++) {
            // The last open window takes what rounding leaves of u.
            if (j < nw.n && nw.w[j].alpha > 0.0 && !picked) {
                lo = nw.w[j].lo;
                layer = nw.w[j].layer;
                alpha = nw.w[j].alpha;
                acc += alpha;
                picked = u < acc;
            }
        }
    }
    p_near = alpha * nw.p;
    ivec2 o = min(ivec2(u_texel * float(nw.size)), ivec2(nw.size - 1));
    return ivec3(lo + o, int(layer));
}

// The near strategy's probability of VPL v: α of its light's window / K² inside that window, else 0.
// v's layer belongs to one light, so at most one window can hold it: find that window by its layer's
// index range and keep its corner and α (selects), then divide once and test once.
float near_prob(Near nw, uint v) {
    uint res = frame.size.w, face_texels = res * res;
    if (NEAR_LIGHTS == 1u || nw.n == 1u) {
        // One window (in the multi variants, a one-light scene: the same for every lane, so the loop
        // below is skipped).
        uint base = nw.w[0].layer * face_texels;
        if (!nw.w[0].open || v < base || v - base >= face_texels) return 0.0;
        uint r1 = v - base, ty1 = udiv(r1, res); // a row: far below udiv's exact range
        ivec2 o1 = ivec2(int(r1 - ty1 * res), int(ty1)) - nw.w[0].lo;
        return all(greaterThanEqual(o1, ivec2(0))) && all(lessThan(o1, ivec2(nw.size))) ? nw.w[0].alpha * nw.p : 0.0;
    }
    uint r = 0u;
    ivec2 lo = ivec2(0);
    float alpha = 0.0;
    for (uint j = 0u; j < uint(NEAR_LIGHTS); j++) {
        if (j < nw.n) {
            uint base = nw.w[j].layer * face_texels;
            bool mine = nw.w[j].open && v >= base && v - base < face_texels;
            r = mine ? v - base : r;
            lo = mine ? nw.w[j].lo : lo;
            alpha = mine ? nw.w[j].alpha : alpha;
        }
    }
    uint ty = udiv(r, res);
    ivec2 o = ivec2(int(r - ty * res), int(ty)) - lo;
    return alpha > 0.0 && all(greaterThanEqual(o, ivec2(0))) && all(lessThan(o, ivec2(nw.size))) ? alpha * nw.p : 0.0;
}
#endif
