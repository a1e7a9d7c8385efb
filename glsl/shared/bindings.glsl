// Binding indices and constants: the single source of truth. build.rs turns every `#define NAME <int>`
// in this file into `pub const NAME: u32` in Rust (crate bounce_graph::bindings).
#ifndef BOUNCE_BINDINGS_GLSL
#define BOUNCE_BINDINGS_GLSL

#define MAX_LIGHTS 16

// Scene data, shared by every pass that reads the mesh (gbuffer, dprsm, direct).
#define B_FRAME 0
#define B_VERTICES 1
#define B_TRI_MATERIAL 2
#define B_MATERIALS 3
#define B_TEXTURES 4
#define B_TEXELS 5
#define B_LIGHTS 6

// direct: inputs and output
#define B_DIRECT_GPOSITION 7
#define B_DIRECT_GNORMAL 8
#define B_DIRECT_GALBEDO 9
#define B_DIRECT_SHADOW 10
#define B_DIRECT_OUT 11

// voxelize / voxel march: the occupancy bits (bit c % 32 of word c / 32 for cell
// c = x + dims.x * (y + dims.y * z)).
#define B_VOXELS 12

// dprsm (reflective): nothing extra; gather: inputs and outputs
#define B_GATHER_GPOSITION 13
#define B_GATHER_GNORMAL 14
#define B_GATHER_GALBEDO 15
#define B_VPL_POSITION 16
#define B_VPL_NORMAL 17
#define B_VPL_FLUX 18
#define B_CDF 19
#define B_GATHER_OUT 20

// cdf_reduce: importance in, CDF out
#define B_IMPORTANCE 21
#define B_CDF_OUT 22
#define B_GATHER_DIRECT 23

// importance modes
#define IMP_UNIFORM 0
#define IMP_GLOBAL 1
#define IMP_STRATIFIED 2
#define IMP_LOCAL 3
#define IMP_GBG_SCATTER 4
#define IMP_GBG_RESOLVE 5
#define B_REF_SQ 28

// The BVH (crates/graph/src/bvh.rs, glsl/shared/bvh.glsl): node and triangle buffers, and the traversal's
// bounds (loop iterations per trace, stack depth).
#define B_BVH_NODES 26
#define B_BVH_TRIS 27
#define BVH_MAX_STEPS 16384
#define BVH_STACK_SIZE 64
#define B_GBG_SUM 24
#define B_GBG_COUNT 25

// psm (per-VPL paraboloid shadow maps, `--visibility psm`): the frame's shared VPL set and their maps.
#define B_PSM_VIEWS 29
#define B_PSM_DEPTH 30
#define FACE_RR 0
#define FACE_UNIFORM 1

#define GATHER_SAMPLE 0
#define GATHER_ALL 1
#define MIS_CONSISTENT 2
#define MIS_THESIS 3
#define CDF_ROWS 0
#define CDF_TOTALS 1

// The VPL map at each light (`--light-map`, shared/lightmap.glsl).
#define LIGHT_MAP_DPRSM 0
#define LIGHT_MAP_RSM 1
#define LIGHT_MAP_CUBE 2

// Specialisation constant ids. SPEC_TEXTURED: the scene has textures (false: albedo_at reads no
// texture, so an untextured scene runs the shader variant without texture fetches).
#define SPEC_TEXTURED 0

#define WG_2D 8
#define WG_1D 64

#endif
