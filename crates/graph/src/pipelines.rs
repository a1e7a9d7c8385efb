//! Pipelines built when a frame first needs them. A pass holds its shaders as [`Lazy`] sets: the SPIR-V,
//! the layout's bindings and push-constant size, and one slot per combination of specialisation
//! constants it may ask for. Creating the renderer builds none of these (only the few pipelines every
//! frame runs: the G-buffer, the light maps, direct light, the CDF scan), so start-up pays only for what
//! the first frame runs (on lavapipe a pipeline costs its LLVM compilation: the 51 variants built up
//! front took most of a small render's 2 s), and a timed run builds its pipelines in its untimed first
//! frame (`Renderer::prepare`, `Renderer::warm_up`).

use anyhow::Result;
use bounce_device::{Binding, ComputePipeline, Gpu};
use std::sync::OnceLock;

/// A compute shader's pipelines, `N` specialisations of it, each built on first use.
pub struct Lazy<const N: usize> {
    gpu: Gpu,
    name: &'static str,
    spirv: &'static [u8],
    bindings: Vec<Binding>,
    push: u32,
    built: [OnceLock<ComputePipeline>; N],
}

impl<const N: usize> Lazy<N> {
    /// `name` (labels and messages), its SPIR-V, the bindings of its layout and its push-constant bytes.
    pub fn new(gpu: &Gpu, name: &'static str, spirv: &'static [u8], bindings: &[Binding], push: u32) -> Self {
        Lazy {
            gpu: gpu.clone(),
            name,
            spirv,
            bindings: bindings.to_vec(),
            push,
            built: std::array::from_fn(|_| OnceLock::new()),
        }
    }

    /// Specialisation `slot` (< N), with the constants `spec` (the caller's one mapping from slot to
    /// constants: a slot always gets the same), built on first use.
    pub fn get(&self, slot: usize, spec: &[(u32, u32)]) -> Result<&ComputePipeline> {
        let cell = &self.built[slot];
        if let Some(p) = cell.get() {
            return Ok(p);
        }
        let words = crate::spirv(self.spirv);
        let p = ComputePipeline::new(&self.gpu, self.name, &words, &self.bindings, self.push, spec)?;
        Ok(cell.get_or_init(|| p))
    }
}

impl Lazy<1> {
    /// The shader as it is (no specialisation constants).
    pub fn pipeline(&self) -> Result<&ComputePipeline> {
        self.get(0, &[])
    }
}
