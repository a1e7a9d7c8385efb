// Structs shared between GLSL and Rust (crates/graph/src/shader_types.rs mirrors them with size and
// offset asserts; tests/layout_echo checks both sides agree on the GPU). std430, no vec3 members, no bool.
#ifndef BOUNCE_TYPES_GLSL
#define BOUNCE_TYPES_GLSL

// One vertex of the flat (non-indexed) triangle list: triangle t owns vertices 3t, 3t+1, 3t+2, so
// gl_PrimitiveID (and gl_VertexIndex / 3) is the triangle index everywhere.
struct Vertex {
    vec4 position_u; // xyz world position, w texture u
    vec4 normal_v;   // xyz shading normal (unit; the face normal when the OBJ has no vn), w texture v
};

// Per-material data; triangle t uses materials[tri_material[t]].
struct Material {
    vec4 kd_tex;     // rgb Kd (linear), w = texture index as float, or -1 for none
};

// A texture stored as packed sRGB RGBA8 texels (r in the low byte) in the texel buffer.
struct TextureInfo {
    uint offset;     // first texel in the texel buffer
    uint width;
    uint height;
    uint pad;
};

struct Light {
    vec4 position;   // xyz world position, w unused
    vec4 intensity;  // rgb radiant intensity (W/sr), w unused
};

// Per-frame constants, one uniform buffer for every pass.
struct FrameUniforms {
    mat4 view_proj;          // world -> Vulkan clip space of the camera
    vec4 eye;                // xyz camera position
    vec4 scene_min;          // xyz scene bounds (w: scene diagonal length)
    vec4 scene_max;          // xyz scene bounds (w: far distance used by the paraboloid maps)
    uvec4 size;              // x width, y height, z light count, w reflective DPRSM (VPL) resolution per face
    uvec4 maps;              // x unused, y the VPL slots (faces × lights × dprsm_res²), z --psm-res, w --vpls
    vec4 shadow;             // x constant bias (world units), y slope bias (texel units), z,w unused
    vec4 voxel_origin;       // xyz world position of the grid's minimum corner, w cell size (cubic cells)
    uvec4 voxel_dims;        // xyz cells per axis, w total cells
    uvec4 light_map;         // the VPL map of each light (shared/lightmap.glsl): x kind (LIGHT_MAP_*),
                             // y faces per light, z tan(fov/2) of a perspective face (float bits), w unused
    vec4 vpl;                // x: the weight s of a VPL's patch area in its kernel 1/√(d⁴ + (s·A_v)²)
                             // (shared/vpl.glsl; 0: point VPLs, 1/d²), yzw unused
    mat4 prev_view_proj;     // last frame's view_proj (this frame's on a first frame): reprojection
    vec4 camera;             // x: 2 tan(fov_y / 2) / height, a pixel's angle (radians, small-angle); yzw unused
};

// gather push constants.
struct GatherPush {
    uint mode;        // GATHER_SAMPLE: N VPLs drawn from the CDF; GATHER_ALL: every VPL in [first, last)
    uint samples;     // N (GATHER_SAMPLE)
    uint seed;
    uint first;       // GATHER_ALL: VPL index range of this dispatch; GATHER_SAMPLE: sample index range
    uint last;
    uint accumulate;  // 1: add to the output image (later tiles); 0: overwrite it
    uint add_direct;  // 1: add the direct image (the combined component)
    float clamp_d2;   // the squared distance below which 1/d² is clamped (0: no clamp)
    uint sections;    // method CDF sections after the validity section (1; `local`: the regions)
    float defensive;  // ε: the share of samples drawn uniformly among the VPLs (0 for `uniform`)
    uint face_mode;   // FACE_RR: faces in proportion to their importance; FACE_UNIFORM: equally
    uint cdf_len;     // floats per CDF section
    uint rays;        // mis: gathering rays per pixel (n_g)
    uint end_balls;   // 1: the exact gather's rays skip their ends' empty balls (B_END_BALL_PIXELS/_VPLS)
    float near_share; // η: the share of a CDF method's draws from the pixel's near window (0: none)
    uint near_radius; // the near window's half-width, texels (2r + 1 wide)
};

// ris push constants, after a GatherPush (`draw_vpl`'s sampling fields; first/last: the candidate range
// of ris's initial stage, the reservoir range of its shade stage).
struct RisPush {
    uint candidates;  // M: candidates streamed into each reservoir
    uint reservoirs;  // R: reservoirs (layers; shadow rays) per pixel, K per candidate stream
    uint pass;        // the spatial pass (its neighbours' hash)
    uint neighbors;   // k: neighbours per spatial pass
    float radius;     // spatial radius, pixels
    float history_cap;// the history's confidence is capped at history_cap · M
    uint pool_tiles;  // candidates from a presampled pool of pool_tiles × RIS_POOL_TILE VPLs (0: per pixel)
    float learned;    // δ_L: the target weighs a VPL by max(V̂, δ_L), V̂ learned from earlier frames (0: off)
    uint vis_tile;    // the learned visibility's screen tiles, pixels per side
    uint vis_cell;    // its light-map cells, texels per side
    uint near_candidates; // the last this many of the M candidates come from the near window (0: none)
    uint near_radius; // the near window's half-width, texels (2r + 1 wide)
    uint control;     // 1: the shade adds β (U_g − g(y) W), the unshadowed control variate (no reuse only)
    uint picks;       // K: VPLs each reservoir's candidates keep, independently (layers: R = streams · K)
    uint pad0;
    uint pad1;
};

// One reservoir of ris (per pixel and layer). While its candidates stream in (over dispatches) `weight`
// is their Σ w; once they are in, the unbiased contribution weight W of `vpl`.
struct Reservoir {
    uint vpl;         // the kept VPL (RIS_NONE: none)
    float weight;     // Σ w while streaming; then W
    float confidence; // c: candidates behind the sample (M; sums over reuse; capped as history)
    float target;     // p̂(vpl) at the owning pixel while streaming (0: none)
};

// One VPL of the frame's shared set under `--visibility psm`, and the viewpoint of its shadow map.
struct PsmView {
    vec4 position_v;  // xyz: the VPL lifted off its surface (the map's centre); w: the VPL index (uint bits)
    vec4 normal_p;    // xyz: the VPL's normal (the map's hemisphere axis); w: its probability (0: no VPL)
};

// importance push constants.
struct ImportancePush {
    uint mode;        // IMP_UNIFORM, IMP_GLOBAL, IMP_STRATIFIED, IMP_LOCAL, IMP_GBG_SCATTER, IMP_GBG_RESOLVE
    uint samples;     // gather points per CDF (global/stratified/local) or rays per pixel (gbg)
    uint seed;
    uint regions;     // local: regions per side (regions = side²); gbg scatter: rays per dispatch
    float min_d2;     // importance only: 1/d² is clamped below this squared distance
    float fixed_scale;// gbg: fixed-point units per unit of contribution (u64 atomics: deterministic sums)
    uint section;     // the section written (IMP_LOCAL: first region's section; one dispatch z per region)
    uint first;       // gbg scatter: this dispatch's first ray (rays [first, min(first + regions, samples)))
};

// cdf_reduce push constants.
struct CdfPush {
    uint stage;       // CDF_ROWS: prefix per row; CDF_TOTALS: prefix over the row totals
    uint row_length;  // texels per row
    uint rows;        // rows in all (2 faces × lights × rows per face)
    uint section;     // which section: importance at section·rows·row_length, CDF at section·cdf_len
};


// voxelize push constants.
struct VoxelizePush {
    uint cells_per_invocation; // candidate cells one invocation tests at most: u32 max where the driver has
                               // no loop limit (one invocation per triangle), else a triangle's cells are
                               // split over gl_GlobalInvocationID.y (see voxelize.rs)
    uint first_triangle;       // the triangle of invocation x = 0 (large scenes take several dispatches)
};

// Push constants of the paraboloid maps' shaders (dprsm.comp; psm.vert/geom/frag).
struct ParaboloidPush {
    uint map_res;     // the map resolution per face
    uint pad;
    vec2 offset;      // the reflective map's texel ray offset in layer 0, in texels ([0, 1)²; ½: the centre)
};

// present push constants.
struct PresentPush {
    uint stage;       // PRESENT_ACCUMULATE, PRESENT_TOTAL or PRESENT_MAP
    float frames;     // frames in the running mean, this one included
    uint reset;       // 1: the sum restarts at this frame's radiance
    uint swap_rb;     // 1: write B, G, R (a BGRA swapchain)
    float exposure;   // multiplies Reinhard's scale a / L̄_w (1: the PNG writer's mapping)
    uint groups;      // workgroups of the per-pixel stages (the stats buffer's partials)
    uint prior;       // PRESENT_PRIOR_NONE, _KEEP or _USE: the last real-time frame's part
    uint pad;
};

// reproject push constants.
struct ReprojectPush {
    uint history;     // 1: last frame's surface is kept (B_PREV_*); 0: a first frame, nothing reprojects
    float plane;      // disocclusion: the most a point may lie off last frame's surface, in pixel footprints
    float normal;     // disocclusion: the least cosine between this frame's and last frame's normals
    uint pad0;
};

// denoise push constants.
struct DenoisePush {
    uint history;     // temporal: 1 when last frame's accumulation is kept (B_DENOISE_PREV_*)
    uint step;        // à-trous: the kernel's tap spacing, pixels (1, 2, 4, ...)
    uint last;        // à-trous: 1 in the last iteration (remodulate, add the direct light)
    uint add_direct;  // 1: the raw estimate holds the direct light (subtracted, filtered apart, added back)
    float alpha;      // the temporal blend's least weight of the new frame (illumination and variance)
    float sigma_l;    // edge stop: luminance, in standard deviations
    float sigma_n;    // edge stop: the normals' cosine exponent
    float sigma_z;    // edge stop: distance off the pixel's plane, in pixel footprints per pixel of offset
};

#endif
