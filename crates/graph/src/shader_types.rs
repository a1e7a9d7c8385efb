//! `#[repr(C)]` + `bytemuck::Pod` mirrors of `glsl/shared/types.glsl`: the frame's uniforms and the
//! passes' push constants (the scene's own structs are `bounce_scene::layout`'s). Every type carries size
//! and offset asserts; the lavapipe `layout_echo` test checks that the GPU agrees.

use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

// The scene's structs (its vertices, materials, textures and lights) live with the scene.
pub use bounce_scene::layout::{Light, Material, TextureInfo, Vertex};

/// Per-frame constants (one uniform buffer for every pass).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub scene_min: [f32; 4],
    pub scene_max: [f32; 4],
    pub size: [u32; 4],
    /// x unused, y the VPL slots (faces × lights × dprsm_res²), z `--psm-res`, w `--vpls`.
    pub maps: [u32; 4],
    /// The per-VPL shadow maps' depth bias: x constant (world units), y slope (texels); zw unused.
    pub shadow: [f32; 4],
    pub voxel_origin: [f32; 4],
    pub voxel_dims: [u32; 4],
    /// The VPL map kind (`LIGHT_MAP_*`), faces per light, tan(fov/2) bits (perspective faces), unused.
    pub light_map: [u32; 4],
    /// x: the weight s of a VPL's patch area in its kernel 1/√(d⁴ + (s·A_v)²) (`--vpl-kernel`; 0: 1/d²),
    /// yzw unused.
    pub vpl: [f32; 4],
    /// Last frame's `view_proj` (this frame's on a first frame): where a surface point was on screen.
    pub prev_view_proj: [[f32; 4]; 4],
    /// x: 2 tan(fov_y / 2) / height, a pixel's angle (the denoiser's depth tolerance); yzw unused.
    pub camera: [f32; 4],
}
const _: () = assert!(size_of::<FrameUniforms>() == 304);
const _: () = assert!(offset_of!(FrameUniforms, prev_view_proj) == 224);
const _: () = assert!(offset_of!(FrameUniforms, vpl) == 208);
const _: () = assert!(offset_of!(FrameUniforms, voxel_origin) == 160);
const _: () = assert!(offset_of!(FrameUniforms, eye) == 64);
const _: () = assert!(offset_of!(FrameUniforms, size) == 112);
const _: () = assert!(offset_of!(FrameUniforms, maps) == 128);
const _: () = assert!(offset_of!(FrameUniforms, shadow) == 144);

/// gather push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherPush {
    pub mode: u32,
    pub samples: u32,
    pub seed: u32,
    pub first: u32,
    pub last: u32,
    pub accumulate: u32,
    pub add_direct: u32,
    pub clamp_d2: f32,
    pub sections: u32,
    pub defensive: f32,
    pub face_mode: u32,
    pub cdf_len: u32,
    pub rays: u32,
    /// 1: the exact gather's rays skip their ends' empty balls (set by the gather pass where they are bound).
    pub end_balls: u32,
    /// η: the share of a CDF method's draws from the pixel's near window (`glsl/shared/near_window.glsl`).
    pub near_share: f32,
    /// The near window's half-width, texels.
    pub near_radius: u32,
}
const _: () = assert!(size_of::<GatherPush>() == 64);

impl GatherPush {
    /// This push (items `first..last`, its whole range) for the dispatch of items `f..l` of it: only the
    /// range's first dispatch keeps `accumulate` and `add_direct`; the later ones add to what it stored.
    pub fn chunk(&self, f: u32, l: u32) -> GatherPush {
        let head = f == self.first;
        GatherPush {
            first: f,
            last: l,
            accumulate: if head { self.accumulate } else { 1 },
            add_direct: if head { self.add_direct } else { 0 },
            ..*self
        }
    }
}

/// ris push constants, after a [`GatherPush`] (`RisPush` in `glsl/shared/types.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RisPush {
    pub candidates: u32,
    pub reservoirs: u32,
    pub pass: u32,
    pub neighbors: u32,
    pub radius: f32,
    pub history_cap: f32,
    /// Candidates from a presampled pool of `pool_tiles` × `RIS_POOL_TILE` VPLs (0: drawn per pixel).
    pub pool_tiles: u32,
    /// δ_L: the target weighs a VPL by max(V̂, δ_L), V̂ the visibility learned from earlier frames' shadow
    /// rays (0: off).
    pub learned: f32,
    /// The learned visibility's screen tiles (pixels per side) and light-map cells (texels per side).
    pub vis_tile: u32,
    pub vis_cell: u32,
    /// Candidates of each reservoir from the near window (the last of its M; 0: none): light-map texels
    /// around where the pixel projects into a light's map.
    pub near_candidates: u32,
    /// The near window's half-width, texels (the window is 2r + 1 texels wide).
    pub near_radius: u32,
    /// 1: the shade adds the unshadowed control variate β (U_g − g(y) W) (passes/ris.rs; without reuse).
    pub control: u32,
    /// K: VPLs each reservoir's candidates keep, independently, each traced by its own shadow ray; the
    /// reservoirs (layers) are `reservoirs` / K candidate streams of K picks.
    pub picks: u32,
    pub pad: [u32; 2],
}
const _: () = assert!(size_of::<RisPush>() == 64);

/// ris's push constant block: the gather's sampling fields, then ris's own.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RisPushBlock {
    pub gather: GatherPush,
    pub ris: RisPush,
}
// 128 bytes: the least maxPushConstantsSize a Vulkan device may have.
const _: () = assert!(size_of::<RisPushBlock>() == 128);
const _: () = assert!(offset_of!(RisPushBlock, ris) == 64);

/// One reservoir of ris (`Reservoir` in `glsl/shared/types.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Reservoir {
    pub vpl: u32,
    /// Σ w while streaming; then the unbiased contribution weight W.
    pub weight: f32,
    pub confidence: f32,
    pub target: f32,
}
const _: () = assert!(size_of::<Reservoir>() == 16);

/// One VPL of the frame's shared set under `--visibility psm` and its shadow map's viewpoint
/// (`PsmView` in `glsl/shared/types.glsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PsmView {
    /// xyz: the VPL lifted off its surface; w: the VPL index (u32 bits).
    pub position_v: [f32; 4],
    /// xyz: the VPL's normal (the map's axis); w: its probability (0: no VPL).
    pub normal_p: [f32; 4],
}
const _: () = assert!(size_of::<PsmView>() == 32);

/// importance push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ImportancePush {
    pub mode: u32,
    pub samples: u32,
    pub seed: u32,
    pub regions: u32,
    pub min_d2: f32,
    pub fixed_scale: f32,
    pub section: u32,
    pub first: u32,
}
const _: () = assert!(size_of::<ImportancePush>() == 32);

/// cdf_reduce push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct CdfPush {
    pub stage: u32,
    pub row_length: u32,
    pub rows: u32,
    pub section: u32,
}
const _: () = assert!(size_of::<CdfPush>() == 16);

/// voxelize push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct VoxelizePush {
    /// Candidate cells one invocation tests at most (`u32::MAX`: no loop limit, one invocation per triangle).
    pub cells_per_invocation: u32,
    /// The triangle of invocation x = 0 of this dispatch.
    pub first_triangle: u32,
}
const _: () = assert!(size_of::<VoxelizePush>() == 8);
const _: () = assert!(offset_of!(VoxelizePush, first_triangle) == 4);

/// Push constants of the paraboloid maps' shaders (dprsm's and psm's).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ParaboloidPush {
    /// The map resolution per face.
    pub map_res: u32,
    pub pad: u32,
    /// Where in its texel each reflective-map texel's ray passes, in texels ([0, 1)², ½ the centre), for
    /// layer 0; layer k adds k times the R2 sequence's step, wrapped (`dprsm.comp`).
    pub offset: [f32; 2],
}
const _: () = assert!(size_of::<ParaboloidPush>() == 16);
const _: () = assert!(offset_of!(ParaboloidPush, pad) == 4);
const _: () = assert!(offset_of!(ParaboloidPush, offset) == 8);

/// present push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PresentPush {
    /// `PRESENT_ACCUMULATE`, `PRESENT_TOTAL` or `PRESENT_MAP`.
    pub stage: u32,
    /// Frames in the running mean, this one included.
    pub frames: f32,
    /// 1: the sum restarts at this frame's radiance.
    pub reset: u32,
    /// 1: write B, G, R (a BGRA swapchain).
    pub swap_rb: u32,
    /// Multiplies Reinhard's scale a / L̄_w (1: the PNG writer's mapping).
    pub exposure: f32,
    /// Workgroups of the per-pixel stages.
    pub groups: u32,
    /// `PRESENT_PRIOR_NONE`, `_KEEP` or `_USE`: the last real-time frame's part.
    pub prior: u32,
    pub pad: u32,
}
const _: () = assert!(size_of::<PresentPush>() == 32);
const _: () = assert!(offset_of!(PresentPush, exposure) == 16);

/// reproject push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ReprojectPush {
    /// 1: last frame's surface is kept; 0: a first frame, nothing reprojects.
    pub history: u32,
    /// Disocclusion: the most a point may lie off last frame's surface, in pixel footprints.
    pub plane: f32,
    /// Disocclusion: the least cosine between this frame's and last frame's normals.
    pub normal: f32,
    pub pad: u32,
}
const _: () = assert!(size_of::<ReprojectPush>() == 16);

/// denoise push constants.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DenoisePush {
    /// Temporal stage: 1 when last frame's accumulation is kept.
    pub history: u32,
    /// The à-trous kernel's tap spacing, pixels.
    pub step: u32,
    /// 1 in the last à-trous iteration (remodulate, add the direct light).
    pub last: u32,
    /// 1: the raw estimate holds the direct light.
    pub add_direct: u32,
    /// The temporal blend's least weight of the new frame.
    pub alpha: f32,
    /// Edge stops: luminance (standard deviations), normals (cosine exponent), plane distance (pixel
    /// footprints per pixel of offset).
    pub sigma_l: f32,
    pub sigma_n: f32,
    pub sigma_z: f32,
}
const _: () = assert!(size_of::<DenoisePush>() == 32);
