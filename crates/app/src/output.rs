//! Image files and what is computed on their pixels: linear float32 RGB EXR with metadata (written
//! and read), tone-mapped PNG, the Reinhard 2002 tone mapping, and FLIP (nv-flip) on a pair tone-mapped
//! alike. Every file is written to a temporary file next to the target and renamed into place, so a
//! failure never leaves a half-written output; an image's EXR and PNG are both written before either
//! is renamed ([`write_exr_and_png`]), and commands check where their outputs go
//! ([`check_destination`], [`check_folder`]) before their work.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// Linear RGB radiance, row-major, row 0 = top.
#[derive(Clone, Debug)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    pub fn from_rgba(width: u32, height: u32, rgba: &[[f32; 4]]) -> Self {
        RgbImage { width, height, pixels: rgba.iter().map(|p| [p[0], p[1], p[2]]).collect() }
    }
    pub fn non_finite_count(&self) -> usize {
        self.pixels.iter().filter(|p| p.iter().any(|c| !c.is_finite())).count()
    }
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// A file written under its temporary name and renamed over its path by [`Staged::commit`]. Dropped
/// uncommitted (a later output of the same command failed), it removes the temporary: a command that
/// writes several files stages them all first, so a failure leaves none of them half-written or alone.
#[must_use = "a staged file is removed unless committed"]
pub struct Staged {
    tmp: PathBuf,
    path: PathBuf,
    committed: bool,
}

impl Staged {
    pub fn commit(mut self) -> Result<()> {
        std::fs::rename(&self.tmp, &self.path).with_context(|| format!("renaming into {}", self.path.display()))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if !self.committed {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// The file a write to `path` replaces: the target of a symbolic link (the rename would replace the link
/// itself, leaving its target as it was), `path` otherwise.
fn resolved(path: &Path) -> PathBuf {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
        _ => path.to_path_buf(),
    }
}

/// Removes from `dir` the temporaries an interrupted run left of files named `prefix…` (`.NAME.PID.tmp`,
/// as [`stage`] names them: a killed animation leaves its staged frames hidden in its folder, under a
/// process id no later run has). Returns how many.
pub fn remove_stale_temporaries(dir: &Path, prefix: &str) -> Result<usize> {
    let mut removed = 0;
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let path = entry?.path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else { continue };
        let Some(rest) = name.strip_prefix('.').and_then(|n| n.strip_suffix(".tmp")) else { continue };
        let Some((file, pid)) = rest.rsplit_once('.') else { continue };
        if file.starts_with(prefix) && !pid.is_empty() && pid.bytes().all(|b| b.is_ascii_digit()) && path.is_file() {
            std::fs::remove_file(&path).with_context(|| format!("removing {}", path.display()))?;
            removed += 1;
        }
    }
    Ok(removed)
}

/// Whether two output paths name one file: lexically absolute (`./a.exr` and `a.exr`), links followed
/// (two names of one file would share one temporary, and the second commit find it gone).
pub fn same_destination(a: &Path, b: &Path) -> bool {
    std::path::absolute(resolved(a)).ok() == std::path::absolute(resolved(b)).ok()
}

/// Write with `write` to `path`'s temporary file (removed again on failure).
fn stage(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<Staged> {
    let path = resolved(path);
    let staged = Staged { tmp: temp_path(&path), path, committed: false };
    write(&staged.tmp)?;
    Ok(staged)
}

/// Whether a file of type `ext` (`exr`, `png`) can be written at `path`, asked before the work that
/// makes it: its name ends in `.ext` (the format follows the name), it is no directory and nothing but a
/// file (or a link to one: the link's target is written), and its directory exists and takes a file (a
/// temporary is created there and removed). The error names the path and the cause, for the caller to
/// report as bad input.
pub fn check_destination(path: &Path, ext: &str) -> Result<()> {
    if path.is_dir() || path.as_os_str().as_encoded_bytes().ends_with(b"/") {
        anyhow::bail!("cannot write {}: it is a directory", path.display());
    }
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case(ext)) {
        anyhow::bail!(
            "cannot write {}: the file is {}, so its name must end in .{ext}",
            path.display(),
            ext.to_uppercase()
        );
    }
    if std::fs::symlink_metadata(path).is_ok() {
        let target = std::fs::canonicalize(path).with_context(|| format!("cannot write {}", path.display()))?;
        if !target.is_file() {
            anyhow::bail!("cannot write {}: it exists and is not a regular file", path.display());
        }
        return check_destination_dir(&target);
    }
    check_destination_dir(path)
}

fn check_destination_dir(path: &Path) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        anyhow::bail!("cannot write {}: there is no directory {}", path.display(), dir.display());
    }
    // The temporary the write itself will use (a stale one from a crashed run of this pid is replaced).
    let tmp = temp_path(path);
    std::fs::File::create(&tmp).with_context(|| format!("cannot write {}", path.display()))?;
    std::fs::remove_file(&tmp).with_context(|| format!("removing {}", tmp.display()))?;
    Ok(())
}

fn ascii(s: &str) -> String {
    s.chars().map(|c| if c.is_ascii() && !c.is_ascii_control() { c } else { '?' }).collect()
}

/// Write a text file (temporary file, then rename).
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    stage_text(path, text)?.commit()
}

/// [`write_text`], staged: a command's tables are in place once its plot is drawn too.
pub fn stage_text(path: &Path, text: &str) -> Result<Staged> {
    stage(path, |tmp| std::fs::write(tmp, text).with_context(|| format!("writing {}", path.display())))
}

/// Write linear float32 RGB with `metadata` as EXR string attributes (`bounce.<key>`).
pub fn write_exr(path: &Path, img: &RgbImage, metadata: &[(&str, String)]) -> Result<()> {
    stage_exr(path, img, metadata)?.commit()
}

/// [`write_exr`], staged: the file is in place once committed.
fn stage_exr(path: &Path, img: &RgbImage, metadata: &[(&str, String)]) -> Result<Staged> {
    use exr::prelude::*;
    let (w, h) = (img.width as usize, img.height as usize);
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = img.pixels[y * w + x];
        (p[0], p[1], p[2])
    });
    let layer = Layer::new((w, h), LayerAttributes::named("radiance"), Encoding::SMALL_LOSSLESS, channels);
    let mut image = Image::from_layer(layer);
    for (k, v) in metadata {
        let key = Text::new_or_none(ascii(&format!("bounce.{k}"))).context("EXR attribute name")?;
        let value = Text::new_or_none(ascii(v)).context("EXR attribute value")?;
        image.attributes.other.insert(key, AttributeValue::Text(value));
    }
    stage(path, |tmp| image.write().to_file(tmp).with_context(|| format!("writing {}", path.display())))
}

/// An image as its EXR (with `metadata`) and, when asked, its tone-mapped PNG: both written before
/// either is renamed into place, so a failure leaves neither.
pub fn write_exr_and_png(exr: &Path, png: Option<&Path>, img: &RgbImage, metadata: &[(&str, String)]) -> Result<()> {
    stage_image(exr, png, img, metadata)?.into_iter().try_for_each(Staged::commit)
}

/// [`write_exr_and_png`], staged: the files are in place once each is committed (an animation commits
/// its frames once all are written).
pub fn stage_image(exr: &Path, png: Option<&Path>, img: &RgbImage, metadata: &[(&str, String)]) -> Result<Vec<Staged>> {
    let mut staged = vec![stage_exr(exr, img, metadata)?];
    staged.extend(png.map(|p| stage_png(p, img)).transpose()?);
    Ok(staged)
}

/// The most pixels an EXR may have to be read: 16384² (Vulkan's common largest 2-D image).
const MAX_READ_PIXELS: usize = 16384 * 16384;

/// Read the first RGB(A) layer of an EXR as linear RGB, with its `bounce.*` string attributes.
pub fn read_exr(path: &Path) -> Result<(RgbImage, Vec<(String, String)>)> {
    use exr::prelude::*;
    // An OpenEXR file starts with its magic number; anything else is named for what it is not.
    let mut magic = Vec::with_capacity(4);
    let file = std::fs::File::open(path).with_context(|| format!("reading {}", path.display()))?;
    std::io::Read::read_to_end(&mut std::io::Read::take(file, 4), &mut magic)
        .with_context(|| format!("reading {}", path.display()))?;
    anyhow::ensure!(magic == [0x76, 0x2f, 0x31, 0x01], "reading {}: not an OpenEXR file", path.display());
    // The size the header claims, before any pixel memory is taken for it (a damaged or crafted header
    // asked for 43 GB, and the allocation aborted the process).
    let meta =
        exr::meta::MetaData::read_from_file(path, false).with_context(|| format!("reading {}", path.display()))?;
    for h in &meta.headers {
        let (w, h) = (h.layer_size.width(), h.layer_size.height());
        anyhow::ensure!(
            w.saturating_mul(h) <= MAX_READ_PIXELS,
            "reading {}: its header says {w}×{h} pixels, more than the 16384×16384 bounce reads",
            path.display()
        );
    }
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = [r, g, b];
        },
    )
    .with_context(|| format!("reading {}", path.display()))?;
    let size = image.layer_data.size;
    let mut meta = vec![];
    // Custom header attributes may come back as image or layer attributes; take both.
    for (k, v) in image.attributes.other.iter().chain(image.layer_data.attributes.other.iter()) {
        if let AttributeValue::Text(t) = v {
            meta.push((k.to_string(), t.to_string()));
        }
    }
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((RgbImage { width: size.width() as u32, height: size.height() as u32, pixels }, meta))
}

/// Reinhard et al. 2002, the global photographic operator (the thesis's tone mapping): scale by key
/// a = 0.18 over the log-average luminance, then L_d = L (1 + L/L_white²) / (1 + L) with L_white the
/// largest scaled luminance, applied to the luminance with colour ratios kept. Returns linear [0,1].
pub fn tonemap_reinhard(img: &RgbImage) -> Vec<[f32; 3]> {
    match reinhard_params(img) {
        Some((key, l_white)) => tonemap_reinhard_with(img, key, l_white),
        None => vec![[0.0; 3]; img.pixels.len()],
    }
}

fn lum(p: &[f32; 3]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// The operator's image-dependent parameters: the scale a / L̄_w and L_white (None for a black image).
fn reinhard_params(img: &RgbImage) -> Option<(f64, f64)> {
    let finite: Vec<f32> = img.pixels.iter().map(lum).filter(|l| l.is_finite() && *l >= 0.0).collect();
    if finite.is_empty() {
        return None;
    }
    let delta = 1e-6f64;
    let log_avg = (finite.iter().map(|&l| (delta + l as f64).ln()).sum::<f64>() / finite.len() as f64).exp();
    let key = 0.18 / log_avg;
    let l_white = finite.iter().fold(0.0f64, |m, &l| m.max(l as f64 * key)).max(1e-12);
    Some((key, l_white))
}

/// Reinhard's operator with given parameters (so two images can be mapped alike for comparison).
fn tonemap_reinhard_with(img: &RgbImage, key: f64, l_white: f64) -> Vec<[f32; 3]> {
    img.pixels
        .iter()
        .map(|p| {
            let lw = lum(p) as f64;
            if !(lw.is_finite() && lw > 0.0) {
                return [0.0; 3];
            }
            let l = lw * key;
            let ld = l * (1.0 + l / (l_white * l_white)) / (1.0 + l);
            let s = (ld / lw) as f32;
            [(p[0] * s).clamp(0.0, 1.0), (p[1] * s).clamp(0.0, 1.0), (p[2] * s).clamp(0.0, 1.0)]
        })
        .collect()
}

pub fn linear_to_srgb8(c: f32) -> u8 {
    let c = c.clamp(0.0, 1.0);
    let s = if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// sRGB 8-bit bytes of a tone-mapped image.
fn srgb8(mapped: &[[f32; 3]]) -> Vec<u8> {
    mapped.iter().flat_map(|p| p.map(linear_to_srgb8)).collect()
}

/// Mean FLIP (Andersson et al. 2020) of `test` against `reference`, both tone-mapped with the
/// reference's Reinhard parameters, and the error map as a magma heat map (sRGB8). A black reference maps
/// both with neutral parameters.
pub fn flip(test: &RgbImage, reference: &RgbImage) -> (f64, Vec<u8>) {
    let (key, l_white) = reinhard_params(reference).unwrap_or((1.0, 1.0));
    let r = nv_flip::FlipImageRgb8::with_data(
        reference.width,
        reference.height,
        &srgb8(&tonemap_reinhard_with(reference, key, l_white)),
    );
    let t =
        nv_flip::FlipImageRgb8::with_data(test.width, test.height, &srgb8(&tonemap_reinhard_with(test, key, l_white)));
    let err = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mean = nv_flip::FlipPool::from_image(&err).mean() as f64;
    (mean, err.apply_color_lut(&nv_flip::magma_lut()).to_vec())
}

/// Write sRGB8 RGB bytes as a PNG (temporary file, then rename).
pub fn write_png_bytes(path: &Path, width: u32, height: u32, bytes: Vec<u8>) -> Result<()> {
    stage_png_bytes(path, width, height, bytes)?.commit()
}

fn stage_png_bytes(path: &Path, width: u32, height: u32, bytes: Vec<u8>) -> Result<Staged> {
    let buf = image::RgbImage::from_raw(width, height, bytes).context("PNG buffer size")?;
    stage(path, |tmp| {
        buf.save_with_format(tmp, image::ImageFormat::Png).with_context(|| format!("writing {}", path.display()))
    })
}

/// Tone-map (Reinhard 2002) and write an sRGB PNG.
pub fn write_png(path: &Path, img: &RgbImage) -> Result<()> {
    stage_png(path, img)?.commit()
}

/// [`write_png`], staged: the file is in place once committed.
fn stage_png(path: &Path, img: &RgbImage) -> Result<Staged> {
    stage_png_bytes(path, img.width, img.height, srgb8(&tonemap_reinhard(img)))
}

/// Whether files can be written into the folder `path`, asked before the work: it is a folder that takes
/// a file, or it can be made (its nearest existing ancestor is a folder that takes one). A temporary file
/// is made and removed there to ask; no folder is created.
pub fn check_folder(path: &Path) -> Result<()> {
    let mut existing = path;
    if !path.exists() {
        let mut up = path.parent();
        existing = Path::new(".");
        while let Some(p) = up.filter(|p| !p.as_os_str().is_empty()) {
            if p.exists() {
                anyhow::ensure!(p.is_dir(), "cannot create {}: {} is not a directory", path.display(), p.display());
                existing = p;
                break;
            }
            up = p.parent();
        }
    }
    anyhow::ensure!(existing.is_dir(), "cannot write into {}: it is not a directory", path.display());
    let probe = existing.join(format!(".bounce-probe.{}.tmp", std::process::id()));
    std::fs::File::create(&probe).with_context(|| format!("cannot write into {}", path.display()))?;
    std::fs::remove_file(&probe).with_context(|| format!("removing {}", probe.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("bounce-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<_> =
            std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
        v.sort();
        v
    }

    /// A staged file is in place only once committed; dropped before, it leaves nothing (not even its
    /// temporary), so a command whose second output fails leaves neither.
    #[test]
    fn staged_files_appear_on_commit_and_vanish_when_dropped() {
        let d = scratch("staged");
        let img = RgbImage { width: 2, height: 1, pixels: vec![[0.5, 0.25, 1.0], [0.0, 0.0, 0.0]] };
        let exr = stage_exr(&d.join("a.exr"), &img, &[("k", "v".into())]).unwrap();
        let png = stage_png(&d.join("a.png"), &img).unwrap();
        assert!(!d.join("a.exr").exists() && !d.join("a.png").exists(), "visible before the commit: {:?}", names(&d));
        drop(png);
        exr.commit().unwrap();
        assert_eq!(names(&d), ["a.exr"]);
        let (back, meta) = read_exr(&d.join("a.exr")).unwrap();
        assert_eq!(back.pixels, img.pixels);
        assert!(meta.contains(&("bounce.k".into(), "v".into())), "{meta:?}");
        // A failing write removes its temporary too.
        let r = stage(&d.join("b.txt"), |tmp| {
            std::fs::write(tmp, "partial").unwrap();
            anyhow::bail!("the write failed")
        });
        assert!(r.is_err());
        assert_eq!(names(&d), ["a.exr"]);
        // The pair: a PNG that cannot be written leaves no EXR either.
        let e = write_exr_and_png(&d.join("c.exr"), Some(&d.join("no/c.png")), &img, &[]).unwrap_err();
        assert!(format!("{e:#}").contains("c.png"), "{e:#}");
        assert_eq!(names(&d), ["a.exr"]);
        write_exr_and_png(&d.join("c.exr"), Some(&d.join("c.png")), &img, &[]).unwrap();
        assert_eq!(names(&d), ["a.exr", "c.exr", "c.png"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_destination_is_checked_without_leaving_anything() {
        let d = scratch("destination");
        check_destination(&d.join("x.exr"), "exr").unwrap();
        check_destination(&d.join("x.PNG"), "png").unwrap();
        assert!(names(&d).is_empty(), "the probe stayed: {:?}", names(&d));
        let e = check_destination(&d, "exr").unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        let e = check_destination(&d.join("no/x.exr"), "exr").unwrap_err().to_string();
        assert!(e.contains("no directory"), "{e}");
        std::fs::write(d.join("file"), "").unwrap();
        let e = check_destination(&d.join("file/x.exr"), "exr").unwrap_err().to_string();
        assert!(e.contains("no directory"), "{e}");
        // The format follows the name; a name ending in a separator is a folder's.
        for (name, ext) in [("x.png", "exr"), ("x.exr", "png"), ("x", "exr"), ("scene.toml", "exr"), ("new/", "exr")] {
            let e = check_destination(&d.join(name), ext).unwrap_err().to_string();
            assert!(e.contains("must end in") || e.contains("is a directory"), "{name}: {e}");
        }
        check_folder(&d).unwrap();
        check_folder(&d.join("new/deeper")).unwrap();
        assert!(!d.join("new").exists(), "check_folder made a folder");
        assert!(names(&d) == ["file"], "the probe stayed: {:?}", names(&d));
        let e = check_folder(&d.join("file")).unwrap_err().to_string();
        assert!(e.contains("not a directory"), "{e}");
        let e = check_folder(&d.join("file/sub/deeper")).unwrap_err().to_string();
        assert!(e.contains("is not a directory"), "{e}");
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// An EXR whose header claims more pixels than can be read is refused before its pixels' memory is
    /// taken (a 60000² header aborted the process in the allocation).
    #[test]
    fn an_exr_claiming_a_huge_size_is_refused() {
        let d = scratch("huge");
        let img = RgbImage { width: 2, height: 2, pixels: vec![[1.0; 3]; 4] };
        write_exr(&d.join("small.exr"), &img, &[]).unwrap();
        let mut bytes = std::fs::read(d.join("small.exr")).unwrap();
        // The data and display windows (box2i: x_min, y_min, x_max, y_max) say 60000 × 60000.
        for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
            let at = bytes.windows(name.len()).position(|w| w == name).expect("the window attribute") + name.len() + 4;
            bytes[at + 8..at + 12].copy_from_slice(&59999i32.to_le_bytes());
            bytes[at + 12..at + 16].copy_from_slice(&59999i32.to_le_bytes());
        }
        std::fs::write(d.join("huge.exr"), &bytes).unwrap();
        let e = format!("{:#}", read_exr(&d.join("huge.exr")).unwrap_err());
        assert!(e.contains("60000×60000"), "{e}");
        assert_eq!(read_exr(&d.join("small.exr")).unwrap().0.pixels, img.pixels);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// An interrupted run's hidden temporaries are removed; a file of another name, or a temporary of
    /// another output, is not.
    #[test]
    fn stale_temporaries_are_removed_and_nothing_else() {
        let d = scratch("stale");
        for name in [
            ".frame_0003.exr.4242.tmp",
            ".frame_0003.png.17.tmp",
            ".frame_0001.exr.x.tmp",
            "frame_0001.exr",
            ".bench.csv.5.tmp",
        ] {
            std::fs::write(d.join(name), "").unwrap();
        }
        assert_eq!(remove_stale_temporaries(&d, "frame_").unwrap(), 2);
        assert_eq!(names(&d), [".bench.csv.5.tmp", ".frame_0001.exr.x.tmp", "frame_0001.exr"]);
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// A link is written through (its target replaced, the link kept); a FIFO or a device is refused
    /// before the work, not replaced by a file.
    #[test]
    fn a_link_is_written_through_and_a_special_file_refused() {
        let d = scratch("links");
        let img = RgbImage { width: 1, height: 1, pixels: vec![[1.0, 0.5, 0.25]] };
        std::fs::write(d.join("target.exr"), "old").unwrap();
        std::os::unix::fs::symlink(d.join("target.exr"), d.join("link.exr")).unwrap();
        check_destination(&d.join("link.exr"), "exr").unwrap();
        write_exr(&d.join("link.exr"), &img, &[]).unwrap();
        assert!(
            std::fs::symlink_metadata(d.join("link.exr")).unwrap().file_type().is_symlink(),
            "the link was replaced"
        );
        assert_eq!(read_exr(&d.join("target.exr")).unwrap().0.pixels, img.pixels);
        let status = std::process::Command::new("mkfifo").arg(d.join("fifo.exr")).status();
        if status.is_ok_and(|s| s.success()) {
            let e = check_destination(&d.join("fifo.exr"), "exr").unwrap_err().to_string();
            assert!(e.contains("not a regular file"), "{e}");
        }
        std::fs::remove_dir_all(&d).unwrap();
    }
}
