//! Test harness for the lavapipe integration tests: a validation-checked device per test, image
//! metrics, and evidence files written on failure.
//!
//! Every test makes its own [`TestGpu`] (validation layers on). Its messages are collected per device
//! (the messenger's user data, not a process global: tests run as threads of one process) and checked
//! when the test ends: any message fails the test.

pub mod maps;

use bounce::output::{self, RgbImage};
use bounce_device::{Gpu, GpuOptions};
use std::path::PathBuf;

/// A device with validation on; asserts on drop that the validation layers said nothing.
pub struct TestGpu {
    pub gpu: Gpu,
}

impl TestGpu {
    pub fn new() -> TestGpu {
        let gpu = Gpu::new(&GpuOptions { validation: true, ..GpuOptions::default() }).unwrap_or_else(|e| {
            panic!("cannot create a Vulkan device with validation (install mesa-vulkan-drivers and vulkan-validationlayers): {e}")
        });
        assert!(gpu.validation_enabled(), "validation layers requested but no debug messenger");
        eprintln!("device: {}", gpu.name);
        TestGpu { gpu }
    }
}

impl Default for TestGpu {
    fn default() -> Self {
        Self::new()
    }
}

impl std::ops::Deref for TestGpu {
    type Target = Gpu;
    fn deref(&self) -> &Gpu {
        &self.gpu
    }
}

impl Drop for TestGpu {
    fn drop(&mut self) {
        if std::thread::panicking() {
            return;
        }
        let msgs = self.gpu.validation().messages();
        assert!(msgs.is_empty(), "{} validation message(s):\n{}", msgs.len(), msgs.join("\n"));
    }
}

/// Runs a test kernel of `glsl/test/` (its SPIR-V from `bounce_graph::shaders`) that reads `inputs` at
/// `B_TEST_IN` and writes `out_len` values at `B_TEST_OUT`, one invocation per input in groups of
/// `WG_1D`, and returns what it wrote.
pub fn run_test_kernel<I: bytemuck::Pod, O: bytemuck::Pod>(
    gpu: &Gpu,
    name: &str,
    spirv: &[u8],
    inputs: &[I],
    out_len: usize,
) -> Vec<O> {
    use bounce_device::{sync::Access, vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites};
    use bounce_graph::bindings::{B_TEST_IN, B_TEST_OUT, WG_1D};
    let bindings = [Binding::storage_buffer(B_TEST_IN), Binding::storage_buffer(B_TEST_OUT)];
    let p = ComputePipeline::new(gpu, name, &bounce_graph::spirv(spirv), &bindings, 0, &[]).unwrap();
    let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let inb = Buffer::with_data(gpu, &format!("{name} in"), storage, bytemuck::cast_slice(inputs)).unwrap();
    let bytes = (std::mem::size_of::<O>() * out_len) as u64;
    let outb = Buffer::new(gpu, &BufferDesc::storage(format!("{name} out"), bytes)).unwrap();
    gpu.submit(|cmd| {
        let w = DescriptorWrites::new().storage_buffer(B_TEST_IN, &inb).storage_buffer(B_TEST_OUT, &outb);
        p.dispatch(cmd, &w, &[], [inputs.len() as u32, 1, 1], [WG_1D, 1, 1]);
    })
    .unwrap();
    bytemuck::pod_collect_to_vec(&outb.read_back(Access::ComputeWrite).unwrap())
}

/// The workspace root (tests run with the tests crate as working directory). Read at run time where cargo
/// runs the test: two checkouts sharing one build cache share this crate too, compiled in whichever built
/// it first, whose compile-time path names that checkout's scripts and assets.
pub fn workspace() -> PathBuf {
    let tests =
        std::env::var_os("CARGO_MANIFEST_DIR").map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")), PathBuf::from);
    tests.parent().unwrap().to_path_buf()
}

pub fn default_scene() -> PathBuf {
    workspace().join("assets/cornell-box/scene.toml")
}

/// Where failing tests leave their evidence.
pub fn evidence_dir() -> PathBuf {
    let base = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| workspace().join("target"));
    let d = base.join("test-output");
    let _ = std::fs::create_dir_all(&d);
    d
}

/// relMSE as the project defines it: mean over pixels and channels of (t − r)² / (r² + 0.01).
pub fn rel_mse(test: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    bounce::metrics::Metrics::of(test, reference).rel_mse
}

/// Mean over pixels and channels.
pub fn mean(img: &[[f32; 3]]) -> f64 {
    img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * img.len()).max(1) as f64
}

/// The mean of independent estimates and its standard error (sample standard deviation / √n), for the
/// unbiasedness tests' "within 4 standard errors".
pub fn mean_and_stderr(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    (m, (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / n.sqrt())
}

/// Write `<name>-actual.exr`, `<name>-reference.exr` and `<name>-diff.exr` (|actual − reference|) to
/// the evidence directory and return the paths, for the failure message.
pub fn write_evidence(name: &str, actual: &RgbImage, reference: &RgbImage) -> String {
    let dir = evidence_dir();
    let diff = RgbImage {
        width: actual.width,
        height: actual.height,
        pixels: actual
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, r)| [(a[0] - r[0]).abs(), (a[1] - r[1]).abs(), (a[2] - r[2]).abs()])
            .collect(),
    };
    let mut paths = vec![];
    for (suffix, img) in [("actual", actual), ("reference", reference), ("diff", &diff)] {
        let p = dir.join(format!("{name}-{suffix}.exr"));
        if output::write_exr(&p, img, &[]).is_ok() {
            paths.push(p.display().to_string());
        }
    }
    paths.join(", ")
}

/// xorshift64*: the tests' deterministic random numbers (no dependency).
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1), 24 bits.
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * self.f32()
    }
    /// Uniform in [0, n).
    pub fn below(&mut self, n: u32) -> u32 {
        (self.next_u64() % n as u64) as u32
    }
    /// Uniform in the box [lo, hi].
    pub fn vec(&mut self, lo: glam::Vec3, hi: glam::Vec3) -> glam::Vec3 {
        glam::Vec3::new(self.range(lo.x, hi.x), self.range(lo.y, hi.y), self.range(lo.z, hi.z))
    }
    /// A uniformly distributed unit vector (rejection from the cube).
    pub fn unit(&mut self) -> glam::Vec3 {
        loop {
            let v = self.vec(glam::Vec3::splat(-1.0), glam::Vec3::ONE);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
    /// A random point of a triangle (uniform by area).
    pub fn on_triangle(&mut self, t: &[glam::Vec3; 3]) -> glam::Vec3 {
        let (mut u, mut v) = (self.f32(), self.f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v
    }
}

/// The 12 triangles of the closed axis-aligned box of half-size `half` around `center` (the sealed
/// light and camera scenes), each face's two triangles wound alike.
pub fn closed_box(center: glam::Vec3, half: f32) -> Vec<[glam::Vec3; 3]> {
    let v = |x: f32, y: f32, z: f32| center + glam::Vec3::new(x, y, z) * half;
    let faces = [
        [v(-1., -1., -1.), v(1., -1., -1.), v(1., -1., 1.), v(-1., -1., 1.)],
        [v(-1., 1., -1.), v(-1., 1., 1.), v(1., 1., 1.), v(1., 1., -1.)],
        [v(-1., -1., -1.), v(-1., 1., -1.), v(1., 1., -1.), v(1., -1., -1.)],
        [v(-1., -1., 1.), v(1., -1., 1.), v(1., 1., 1.), v(-1., 1., 1.)],
        [v(-1., -1., -1.), v(-1., -1., 1.), v(-1., 1., 1.), v(-1., 1., -1.)],
        [v(1., -1., -1.), v(1., 1., -1.), v(1., 1., 1.), v(1., -1., 1.)],
    ];
    faces.iter().flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]]).collect()
}
