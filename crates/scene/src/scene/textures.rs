//! Textures: the `map_Kd` images of the materials, decoded into packed sRGB RGBA8 texels (r in the
//! low byte, row 0 = the image's top row), one copy per distinct file.
//!
//! Input: a `map_Kd` statement's file (resolved against its MTL file's directory); output:
//! [`Textures`], the [`TextureInfo`] records and the texel array of `glsl/shared/types.glsl`. Errors
//! are [`SceneError::Texture`], naming the file and the material.

use super::{one_line, SceneError};
use crate::layout::TextureInfo;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// The scene's textures so far: texture `k` is `infos[k]`, its texels
/// `texels[offset..offset + width * height]`.
#[derive(Default)]
pub(super) struct Textures {
    pub infos: Vec<TextureInfo>,
    pub texels: Vec<u32>,
    index: HashMap<PathBuf, usize>,
}

impl Textures {
    /// The index of the texture at `path`, decoding it on first use; `material` and `mtl_path` name
    /// the `map_Kd` that wants it in errors.
    pub fn get_or_load(&mut self, path: &Path, material: &str, mtl_path: &Path) -> Result<usize, SceneError> {
        if let Some(&i) = self.index.get(path) {
            return Ok(i);
        }
        let (w, h, data) = load_texture(path).map_err(|e| match e {
            SceneError::Texture { path, msg } => SceneError::Texture {
                path,
                msg: format!("{msg} (map_Kd of material `{material}` in {})", mtl_path.display()),
            },
            other => other,
        })?;
        let offset = u32::try_from(self.texels.len())
            .ok()
            .filter(|o| o.checked_add(w.saturating_mul(h)).is_some())
            .ok_or_else(|| SceneError::Texture {
                path: path.to_path_buf(),
                msg: "the scene's textures exceed 2^32 texels".to_string(),
            })?;
        self.infos.push(TextureInfo { offset, width: w, height: h, pad: 0 });
        self.texels.extend_from_slice(&data);
        self.index.insert(path.to_path_buf(), self.infos.len() - 1);
        Ok(self.infos.len() - 1)
    }
}

/// The texture file of a `map_Kd` statement: options such as `-bm 1` or `-s 1 1 1` precede the
/// file name, so the name is the last token. Backslashes (Windows exporters) become `/`.
pub(super) fn map_kd_file(spec: &str) -> Option<String> {
    spec.split_whitespace().last().map(|s| s.replace('\\', "/"))
}

/// Decodes an image file into packed sRGB RGBA8 texels (r in the low byte), row 0 = top.
fn load_texture(path: &Path) -> Result<(u32, u32, Vec<u32>), SceneError> {
    let terr = |msg: String| SceneError::Texture { path: path.to_path_buf(), msg };
    let reader = image::ImageReader::open(path)
        .map_err(|e| terr(format!("cannot open: {e}")))?
        .with_guessed_format()
        .map_err(|e| terr(format!("cannot read: {e}")))?;
    let img = reader.decode().map_err(|e| terr(format!("cannot decode: {}", one_line(&e.to_string()))))?;
    let rgba = img.to_rgba8();
    let (w, h) = rgba.dimensions();
    if w == 0 || h == 0 {
        return Err(terr("image is empty".to_string()));
    }
    let texels = rgba.pixels().map(|p| u32::from_le_bytes(p.0)).collect::<Vec<u32>>();
    Ok((w, h, texels))
}

#[cfg(test)]
mod tests {
    use super::super::test_files::*;
    use super::super::Scene;
    use crate::layout::TextureInfo;

    #[test]
    fn texture_round_trips_into_texels() {
        let dir = temp_dir("texture");
        // 3×2 RGBA image with distinct sRGB values; row 0 is the top row of the PNG.
        let px: [[u8; 4]; 6] =
            [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [10, 20, 30, 40], [128, 64, 32, 255], [1, 2, 3, 4]];
        let raw: Vec<u8> = px.iter().flatten().copied().collect();
        let img = image::RgbaImage::from_raw(3, 2, raw).expect("image");
        std::fs::create_dir_all(dir.join("tex")).expect("mkdir");
        img.save(dir.join("tex").join("ab.png")).expect("save png");
        write(
            &dir,
            "room.obj",
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0.25 0.75\nusemtl t\nf 1/1 2/2 3/3\nusemtl t2\nf 1/1 2/2 3/3\n",
        );
        write(&dir, "m.mtl", "newmtl t\nmap_Kd -bm 1 tex\\ab.png\nnewmtl t2\nKd 0.5 0.5 0.5\nmap_Kd tex/ab.png\n");
        let s = Scene::from_toml_str(EXAMPLE, &dir.join("scene.toml")).expect("loads");
        // Both materials share one texture.
        assert_eq!(s.textures.len(), 1);
        assert_eq!(s.textures[0], TextureInfo { offset: 0, width: 3, height: 2, pad: 0 });
        let want: Vec<u32> = px.iter().map(|p| u32::from_le_bytes(*p)).collect();
        assert_eq!(s.texels, want);
        assert_eq!(s.texels[0] & 0xff, 255, "r is the low byte");
        // map_Kd without Kd: Kd = 1.
        assert_eq!(s.materials[s.tri_material[0] as usize].kd_tex, [1.0, 1.0, 1.0, 0.0]);
        assert_eq!(s.materials[s.tri_material[1] as usize].kd_tex, [0.5, 0.5, 0.5, 0.0]);
        // Raw UVs are stored (no flip).
        assert_eq!(s.vertices[2].uv(), glam::Vec2::new(0.25, 0.75));
    }
}
