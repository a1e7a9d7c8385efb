// Binding numbers and the numbers GLSL and Rust share: the single source of truth, grouped by pass.
// build.rs turns each of these forms into a Rust constant of crate bounce_graph::bindings:
//   #define NAME <integer>          (decimal, or 0x hex; an optional u suffix)  →  pub const NAME: u32
//   const uint NAME = <integer>u;                                              →  pub const NAME: u32
//   const float NAME = <expression>;  (float literals, earlier names, + − × / and parentheses)  →  f32
// and fails the build on any other `#define NAME value` or `const` line, so nothing is left out silently.
// Structs shared with Rust live in types.glsl.
#ifndef BOUNCE_BINDINGS_GLSL
#define BOUNCE_BINDINGS_GLSL

// ---- Every pass ----------------------------------------------------------------------------------------
// Workgroup sizes: 2D passes run WG_2D × WG_2D groups over pixels or texels, 1D passes WG_1D.
#define WG_2D 8
#define WG_1D 64
#define MAX_LIGHTS 16
// The thesis's luminance (eq. 7.6): RGB weights of a contribution's scalar importance (common.glsl's
// luminance; ris's host-side estimate of the blocked transport).
const float LUMINANCE_R = 0.299;
const float LUMINANCE_G = 0.587;
const float LUMINANCE_B = 0.114;
// Specialisation constant ids. SPEC_TEXTURED: the scene has textures (false: albedo_at reads no
// texture, so an untextured scene runs the shader variant without texture fetches).
#define SPEC_TEXTURED 0
// SPEC_RIS_PICKS: K, the picks per reservoir of ris's initial stage (ris_initial.comp; RisPush::picks
// chooses the pipeline), so that a frame runs only its own picks' code: llvmpipe runs an `if` body under
// masks even when no lane takes it. The same reason for ris's other specialisations, which bind nothing
// of their own: SPEC_RIS_NEAR (the near window's candidates), SPEC_RIS_NEAR_LIGHTS (its windows: 1, or
// RIS_NEAR_LIGHTS in scenes of more lights) and SPEC_RIS_UNIFORM_SOURCE (the uniform source's shortcut).
#define SPEC_RIS_PICKS 1
#define SPEC_RIS_NEAR 2
#define SPEC_RIS_NEAR_LIGHTS 3
#define SPEC_RIS_UNIFORM_SOURCE 4

// ---- Scene data: every pass that reads the mesh (gbuffer, dprsm, direct, voxelize, ...) ---------------
#define B_FRAME 0
#define B_VERTICES 1
#define B_TRI_MATERIAL 2
#define B_MATERIALS 3
#define B_TEXTURES 4
#define B_TEXELS 5
#define B_LIGHTS 6

// ---- dprsm: the VPL map at each light (`--light-map`, shared/lightmap.glsl) ------------------------------
#define LIGHT_MAP_DPRSM 0
#define LIGHT_MAP_RSM 1
#define LIGHT_MAP_CUBE 2
// Written by dprsm.comp (one layer per light and face), read by every VPL consumer at B_VPL_POSITION..FLUX.
#define B_DPRSM_POSITION_OUT 68
#define B_DPRSM_NORMAL_OUT 69
#define B_DPRSM_FLUX_OUT 70
// The least cos α of a VPL's patch area A_v = Δω · d² / cos α (dprsm.comp): a texel that meets
// its surface at grazing incidence gets at most 20× the area it would facing the light.
const float VPL_MIN_COS = 0.05;
// The step of the VPLs' offset in their texels from one light-map layer to the next (the R2 sequence's,
// 1/g and 1/g², g the plastic number; shared/lightmap.glsl `texel_offset`, frame/keys.rs).
const float VPL_OFFSET_STEP_X = 0.7548777;
const float VPL_OFFSET_STEP_Y = 0.5698403;

// ---- direct: inputs and output (and the BVH) ----------------------------------------------------------------------
#define B_DIRECT_GPOSITION 7
#define B_DIRECT_GNORMAL 8
#define B_DIRECT_GALBEDO 9
#define B_DIRECT_OUT 10

// ---- voxelize, and the voxel march of shared/voxel.glsl (crates/graph/src/cpu_voxel.rs mirrors it) -------
// The occupancy bits (bit c % 32 of word c / 32 for cell c = x + dims.x * (y + dims.y * z)).
#define B_VOXELS 12
// Conservative margin, in cells: a cell counts as touched when a triangle comes within VOXEL_EPS of its box
// (2^-13 ≈ 1.2e-4 cell, a power of two so that 0.5 + VOXEL_EPS is exact in both languages). It absorbs the
// rounding of the grid coordinates (~1e-7 cell), so a surface exactly on a cell face marks both cells.
const float VOXEL_EPS = 1.0 / 8192.0;
// The endpoint offset of the march, in cells (see shared/voxel.glsl).
const float VOXEL_OFFSET_CELLS = 2.0;
// Direction components smaller than this (grid units, 2^-30) count as parallel to that axis's planes.
const float VOXEL_MIN_DIR = 1.0 / 1073741824.0;
// An exit parameter that is never reached (an axis the segment does not move along).
const float VOXEL_NEVER = 3.0e38;

// ---- importance: its output is cdf_reduce's input -------------------------------------------------------
#define B_IMPORTANCE 21
// gbg's fixed-point sums and counts.
#define B_GBG_SUM 24
#define B_GBG_COUNT 25
// ImportancePush.mode
#define IMP_UNIFORM 0
#define IMP_GLOBAL 1
#define IMP_STRATIFIED 2
#define IMP_LOCAL 3
#define IMP_GBG_SCATTER 4
#define IMP_GBG_RESOLVE 5

// ---- cdf_reduce: importance in (B_IMPORTANCE), CDF out ----------------------------------------------------
#define B_CDF_OUT 22
// CdfPush.stage
#define CDF_ROWS 0
#define CDF_TOTALS 1
#define CDF_TOTAL 2
// Floats before a CDF section's prefixes: the total, the rows (uint bits), the row length (uint bits) and
// one unused (shared/cdf.glsl; crates/graph/src/cpu_cdf.rs).
const uint CDF_HEADER = 4u;

// ---- gather and mis (importance and psm bind the VPLs and the CDF at the same numbers) ------------------
#define B_GATHER_GPOSITION 13
#define B_GATHER_GNORMAL 14
#define B_GATHER_GALBEDO 15
#define B_VPL_POSITION 16
#define B_VPL_NORMAL 17
#define B_VPL_FLUX 18
#define B_CDF 19
#define B_GATHER_OUT 20
#define B_GATHER_DIRECT 23
// GatherPush.mode
#define GATHER_SAMPLE 0
#define GATHER_ALL 1
#define MIS_CONSISTENT 2
#define MIS_THESIS 3
// GatherPush.face_mode
#define FACE_RR 0
#define FACE_UNIFORM 1

// ---- The BVH (crates/scene/src/bvh/, crates/graph/src/gpu_bvh.rs, shared/bvh.glsl): reference and the exact-visibility variants -----
// Node and triangle buffers, and the traversal's bounds (loop iterations per trace, stack depth).
#define B_BVH_NODES 26
#define B_BVH_TRIS 27
// The same tree threaded for stackless any-hit traversal (bvh_any_hit): one record per node and per triangle.
#define B_BVH_THREADED 46
// Set in a threaded record's link for a triangle record (a box record's link is its subtree's end).
#define BVH_THREAD_TRI 0x80000000u
// Steps of the threaded walk per loop iteration (written out in bvh_any_hit; divides BVH_MAX_STEPS).
#define BVH_THREAD_UNROLL 8
#define BVH_MAX_STEPS 16384
// Rays per shadow-ray queue (shared/shadow_queue.glsl): its answers are the bits of one uint.
#define SHADOW_QUEUE 32u
#define BVH_STACK_SIZE 64
// bvh_tri of "no hit".
#define BVH_NO_TRI 0xFFFFFFFFu
// Relative end epsilon of bvh_occluded (the CPU reference uses the same value in f64: bounce_oracles::cpu_ref::SHADOW_EPS).
const float BVH_SHADOW_EPS = 1e-4;

// ---- end_balls (passes/end_balls.rs, shared/end_balls.glsl): each shadow-ray end's empty half-ball ------
// The pass reads the G-buffer (B_GATHER_G*) or the VPL images (B_VPL_*) and writes B_END_BALL_OUT; the
// exact gather reads the pixels' balls at B_END_BALL_PIXELS and the VPLs' at B_END_BALL_VPLS.
#define B_END_BALL_OUT 49
#define B_END_BALL_PIXELS 50
#define B_END_BALL_VPLS 51
// Records one ball's walk may read (shared/end_balls.glsl); a walk that has not finished by then gives no
// ball (radius 0), so this only bounds the pass's time and loop count, never an answer.
#define END_BALL_MAX_STEPS 4096
// The largest radius a ball is given, as a share of the scene diagonal (BENCHMARKS.md: larger ones cost the
// walk more records than they save the rays).
const float END_BALL_MAX_RADIUS = 0.03;

// ---- reference: the exact one-bounce integrator --------------------------------------------------------
#define B_REF_SQ 28

// ---- psm (per-VPL paraboloid shadow maps, `--visibility psm`): the frame's shared VPL set and its maps ----
#define B_PSM_VIEWS 29
#define B_PSM_DEPTH 30

// ---- ris (resampled importance sampling over the VPLs, passes/ris.rs): reservoir buffers ---------------
// The stage's input reservoirs, its output, and last frame's final reservoirs.
#define B_RIS_IN 31
#define B_RIS_OUT 32
#define B_RIS_HISTORY 33
// The control variate (passes/ris.rs): per reservoir, the candidates' unshadowed estimate U_g (written by
// the initial stage, read by the shade); per pixel, (visible, traced) counts of its earlier shadow rays,
// the control's coefficient β, and the same counts of the candidate set in progress, not yet in β.
#define B_RIS_UNSHADOWED 34
#define B_RIS_CV 35
// RisPush.control: off; U_g over the reservoir's own candidates (the initial stage; no reuse); U_g over
// the last reuse stage's inputs (the last spatial pass: the generalized RIS form, passes/ris.rs).
#define RIS_CONTROL_OFF 0
#define RIS_CONTROL_CANDIDATES 1
#define RIS_CONTROL_REUSE 2
// Reservoir.vpl of an empty reservoir.
#define RIS_NONE 0xFFFFFFFFu
// ris's presampled candidate pool (--pool-tiles): written by ris.presample, read by ris.initial_pool as a
// uvec4 texel view, three texels per entry; VPLs per tile.
#define B_RIS_POOL 47
// ris's learned visibility (--learn-visibility): (visible, traced) shadow-ray counts per screen tile and
// light-map cell, added to by the shade, read by the next frames' initial stage.
#define B_RIS_VIS 48
#define RIS_POOL_TILE 1024
// Lights whose light maps get a near window (ris.comp, near_windows); the pool covers the others.
#define RIS_NEAR_LIGHTS 4
// Most neighbours of one spatial pass (its loops are bounded by it).
#define RIS_MAX_NEIGHBORS 8
// Most picks per reservoir's candidates (ris.picks; the initial stage keeps them in the components of a
// vec4, pick 0 in the reservoir itself).
#define RIS_MAX_PICKS 4
// The learned visibility's traced count at which a (tile, cell) stops counting (ris_shade.comp).
#define RIS_VIS_COUNT_MAX 0x40000000u
// The shade's shadow-ray counter: one uint, the rays the frame traced (added to by each subgroup).
#define B_RIS_RAYS 57
// ris's temporal stage: last frame's VPL maps (this frame's when no light moved), for the targets at last
// frame's surface that weigh the history (the target its sample was drawn for).
#define B_PREV_VPL_POSITION 65
#define B_PREV_VPL_NORMAL 66
#define B_PREV_VPL_FLUX 67

// ---- reproject (passes/reproject.rs): motion from the G-buffer, and the surface kept for the next frame --
// Written: where each pixel's point was last frame (B_MOTION: xy in pixels, its previous pixel ⌊xy⌋; z = 1
// where last frame saw the same surface there; w, a 4-bit mask of the four pixels around xy that did)
// and this frame's surface (B_SURFACE_POSITION_OUT: xyz, hit; B_SURFACE_OUT: the normal's float bits and
// the albedo as unorm8). Read by ris's temporal stage and the denoiser: B_MOTION and last frame's surface
// at B_PREV_POSITION and B_PREV_SURFACE.
#define B_MOTION 52
#define B_PREV_POSITION 53
#define B_PREV_SURFACE 54
#define B_SURFACE_POSITION_OUT 55
#define B_SURFACE_OUT 56

// ---- denoise (passes/denoise.rs): temporal accumulation, variance, à-trous (SVGF) ------------------------
// Each stage reads B_DENOISE_IN (temporal: the raw estimate, the direct light at B_GATHER_DIRECT, last
// frame's accumulation at B_DENOISE_PREV_*; variance: the accumulated illumination, its accumulated
// variance at B_DENOISE_VARIANCE; à-trous: the last stage's output) and writes B_DENOISE_OUT (temporal:
// the accumulation at B_DENOISE_COLOR_OUT and B_DENOISE_VARIANCE_OUT).
#define B_DENOISE_IN 58
#define B_DENOISE_PREV_COLOR 59
#define B_DENOISE_PREV_VARIANCE 60
#define B_DENOISE_COLOR_OUT 61
#define B_DENOISE_VARIANCE_OUT 62
#define B_DENOISE_VARIANCE 63
#define B_DENOISE_OUT 64
// À-trous iterations (tap spacings 1, 2, 4, 8, 16: SVGF's five).
#define DENOISE_ITERATIONS 5
// The à-trous iterations that gather (a lone hit removed; each fits a plane to its taps, a local linear
// regression, so a ramp cut by a plane's edge keeps its slope); the later ones exchange (light moved,
// never lost). Measured over the generated suite under motion (BENCHMARKS.md, "Real time under motion"),
// against two gathering by weighted means (SVGF's) then three exchanging: with 2 / 3 / 4 / 5 fitting
// gathers the denoised relMSE 0.94× / 0.90× / 0.88× / 0.88× (worst run 1.98× / 1.27× / 1.12× / 1.12×),
// the flicker 1.03× / 0.97× / 0.94× / 0.94×, the lowest image mean (a corner light's) 0.68 → 0.83 /
// 0.78 / 0.75 / 0.73; with 4, the 54 runs held out 0.91× / 0.94×, 0.74 → 0.79.
#define DENOISE_GATHER_ITERATIONS 4
// The gathers' ridge λ on the plane's slope, in units of the taps' weight sum: 0.05 / 0.1 / 0.2 gave
// 0.89× / 0.88× / 0.89× the denoised relMSE (worst run 1.16× / 1.12× / 1.07×), 0.97× / 0.94× / 0.93× the
// flicker and 0.78 / 0.75 / 0.70 of a corner light (the same runs).
const float DENOISE_RIDGE = 0.1;
// The temporal stage clamps the history into this many standard deviations around the mean of this
// frame's 5 × 5 neighbourhood (per channel), so that lighting that changed is not dragged along.
// Measured (BENCHMARKS.md, "Real time under motion"): 2 and 3 both halved the denoised error on Sibenik
// under a moving light; 3 had the better worst case.
const float DENOISE_CLAMP_SIGMAS = 3.0;
// The temporal stage's gradient test: a 5 × 5 mean's change beyond this many standard deviations of its
// noise counts as a change of the lighting, and the history gives way by its share. Measured
// (BENCHMARKS.md, "Real time under motion"): 3 cut the generated suite's denoised error by 28 % for 6 %
// more flicker, 2 by 34 % for 19 % (means over 3 × 3: more flicker, over 7 × 7: more error), and 3
// halved both on Sibenik under a moving light.
const float DENOISE_GRADIENT_SIGMAS = 3.0;

// ---- present: the viewer's running mean, tone mapping and sRGB encoding (passes/present.rs) -------------
#define B_PRESENT_RADIANCE 40
#define B_PRESENT_SUM 41
#define B_PRESENT_OUT 42
#define B_PRESENT_STATS 43
#define B_PRESENT_PRIOR 44
#define B_PRESENT_MOMENTS 45
#define B_PRESENT_MEAN 46
// PresentPush.stage
#define PRESENT_ACCUMULATE 0
#define PRESENT_WEIGHT 1
#define PRESENT_TOTAL 2
#define PRESENT_MAP 3
// PresentPush.prior: none; keep this frame (a real-time one) as the prior; the mean carries the prior.
#define PRESENT_PRIOR_NONE 0
#define PRESENT_PRIOR_KEEP 1
#define PRESENT_PRIOR_USE 2
// The prior's weight in a still view's mean after a move (present.comp's prior_weight; passes/present.rs
// says how they were chosen): frames' worth at the first frame, at most, and the frames it fades over.
const float STOP_PRIOR_FIRST = 1.0;
const float STOP_PRIOR_MAX = 16.0;
const float STOP_PRIOR_FADE = 32.0;
// Reinhard 2002: the key value a, and the δ of the log-average luminance (crates/app/src/output.rs).
const float REINHARD_KEY = 0.18;
const float REINHARD_DELTA = 0.000001;

// ---- Test kernels (glsl/test/): their input and output buffers. Test pipelines bind nothing else at
// these numbers, so they may repeat B_REF_SQ's and B_PSM_VIEWS's. --------------------------------------------
#define B_TEST_IN 28
#define B_TEST_OUT 29

#endif
