// `local`'s blend of screen regions at a pixel: the bilinear weights of the (up to) four regions of a
// side × side grid whose centres surround the pixel's centre. Pure geometry (no bindings), so the test
// kernel glsl/test/region_weights.comp checks it alone; shared/sampling.glsl's region_mixture drops the
// regions without weight and renormalises.
#ifndef BOUNCE_REGIONS_GLSL
#define BOUNCE_REGIONS_GLSL

// Entry j: region index (row-major, from 0) and weight; the weights are ≥ 0 and sum to 1. At the
// screen's edge (and with one region) both neighbours on an axis are the same region: the weight goes
// to one entry and the other gets 0.
void region_weights(vec2 px, vec2 size, uint side, out uvec4 region, out vec4 weight) {
    vec2 c = (px + 0.5) * float(side) / size - 0.5;
    vec2 f = clamp(floor(c), vec2(0.0), vec2(float(side - 1u)));
    vec2 t = clamp(c - f, vec2(0.0), vec2(1.0));
    uvec2 a = uvec2(f), b = min(a + 1u, uvec2(side - 1u));
    if (b.x == a.x) t.x = 0.0;
    if (b.y == a.y) t.y = 0.0;
    region = uvec4(a.y * side + a.x, a.y * side + b.x, b.y * side + a.x, b.y * side + b.x);
    weight = vec4((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
}

#endif
