//! The scene's `#[repr(C)]` + `bytemuck::Pod` structs, as the shaders read them (`glsl/shared/types.glsl`:
//! vertices, materials, textures, lights). Every type carries size and offset asserts; the lavapipe
//! `layout_echo` test checks that the GPU agrees.

use bytemuck::{Pod, Zeroable};
use std::mem::{offset_of, size_of};

/// One vertex of the flat triangle list (triangle `t` owns vertices `3t..3t+3`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Vertex {
    /// xyz world position, w texture u.
    pub position_u: [f32; 4],
    /// xyz unit shading normal, w texture v.
    pub normal_v: [f32; 4],
}
const _: () = assert!(size_of::<Vertex>() == 32);
const _: () = assert!(offset_of!(Vertex, normal_v) == 16);

impl Vertex {
    pub fn position(&self) -> glam::Vec3 {
        glam::Vec3::from_slice(&self.position_u[..3])
    }
    pub fn normal(&self) -> glam::Vec3 {
        glam::Vec3::from_slice(&self.normal_v[..3])
    }
    pub fn uv(&self) -> glam::Vec2 {
        glam::Vec2::new(self.position_u[3], self.normal_v[3])
    }
}

/// rgb Kd (linear) and the texture index as a float (-1: none).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    pub kd_tex: [f32; 4],
}
const _: () = assert!(size_of::<Material>() == 16);

impl Material {
    pub fn kd(&self) -> glam::Vec3 {
        glam::Vec3::from_slice(&self.kd_tex[..3])
    }
    pub fn texture(&self) -> Option<usize> {
        (self.kd_tex[3] >= 0.0).then_some(self.kd_tex[3] as usize)
    }
}

/// A texture's place in the packed sRGB RGBA8 texel buffer.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct TextureInfo {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub pad: u32,
}
const _: () = assert!(size_of::<TextureInfo>() == 16);

/// An isotropic point light.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    pub position: [f32; 4],
    pub intensity: [f32; 4],
}
const _: () = assert!(size_of::<Light>() == 32);
