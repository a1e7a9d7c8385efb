//! Which of a frame's settings its image depends on: [`FrameSettings::reads`]. `bounce render` says
//! which of the flags given on its command line the frame does not read (a `--mis-weights` beside
//! `--method gbg` changes nothing, and a user should not have to find that out by comparing images).
//! The integration tests hold the answer against the images themselves: for every method, visibility and
//! ris source, a setting is read exactly when changing it changes the image.

use super::settings::{Component, FrameSettings, Method, Visibility};

/// A frame setting that one command-line flag sets (`CdfSeed`: `--cdf-seed`, which sets `cdf_seed` and
/// `vpl_seed` alike).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Setting {
    /// `--vpls`.
    Vpls,
    /// `--seed`.
    Seed,
    /// `--dprsm-res`.
    DprsmRes,
    /// `--voxels`.
    Voxels,
    /// `--vpl-kernel`.
    VplKernel,
    /// `--cdf-samples`.
    CdfSamples,
    /// `--regions`.
    Regions,
    /// `--gather-rays`.
    GatherRays,
    /// `--defensive`.
    Defensive,
    /// `--face`.
    Face,
    /// `--mis-weights`.
    MisWeights,
    /// `--spp`.
    Spp,
    /// `--visibility`.
    Visibility,
    /// `--psm-res`.
    PsmRes,
    /// `--light-map`.
    LightMap,
    /// `--cdf-seed` (`cdf_seed` and `vpl_seed`).
    CdfSeed,
    /// `--source` (ris's).
    Source,
    /// `--candidates` (ris's).
    Candidates,
    /// `--picks` (ris's).
    Picks,
    /// `--denoise`.
    Denoise,
}

impl Setting {
    /// Every setting, in declaration order.
    pub const ALL: [Setting; 20] = [
        Setting::Vpls,
        Setting::Seed,
        Setting::DprsmRes,
        Setting::Voxels,
        Setting::VplKernel,
        Setting::CdfSamples,
        Setting::Regions,
        Setting::GatherRays,
        Setting::Defensive,
        Setting::Face,
        Setting::MisWeights,
        Setting::Spp,
        Setting::Visibility,
        Setting::PsmRes,
        Setting::LightMap,
        Setting::CdfSeed,
        Setting::Source,
        Setting::Candidates,
        Setting::Picks,
        Setting::Denoise,
    ];
}

impl FrameSettings {
    /// Whether this frame's image depends on `setting`: whether changing it alone can change the image.
    pub fn reads(&self, setting: Setting) -> bool {
        if self.component == Component::Direct {
            // Exact shadow rays to each light: no VPL, no sample.
            return false;
        }
        let method = self.method;
        // Every method but the path tracer gathers VPLs from the light maps.
        let vpls = method != Method::Reference;
        // The methods that draw VPLs from a distribution (ris: its candidates).
        let draws = vpls && method != Method::All;
        // The distribution they draw from: a CDF's (global, stratified, local, gbg; mis samples gbg's),
        // or the uniform one over the non-empty texels.
        let source = self.sampling_method();
        let cdf = draws && !matches!(source, Method::Uniform | Method::Realtime);
        match setting {
            Setting::Vpls => draws && method != Method::Realtime,
            // `all` is random only in where each VPL lies in its texel, which --cdf-seed pins.
            Setting::Seed => method != Method::All || self.vpl_seed.or(self.cdf_seed).is_none(),
            Setting::DprsmRes | Setting::VplKernel | Setting::LightMap | Setting::Visibility => vpls,
            // The CDFs' importance keeps its gather points one voxel cell away from a VPL (its 1/d²
            // bounded there), whatever the visibility.
            Setting::Voxels => vpls && (self.visibility == Visibility::Voxel || cdf),
            Setting::Defensive => cdf,
            // gbg's (and mis's) importance is gathered by cosine rays from every pixel.
            Setting::CdfSamples => cdf && matches!(source, Method::Global | Method::Stratified | Method::Local),
            Setting::Regions => cdf && source == Method::Local,
            Setting::GatherRays => cdf && matches!(source, Method::Gbg | Method::Mis),
            // The face choice is of a CDF's sections; the uniform draw is over every valid texel at once.
            Setting::Face => cdf,
            Setting::MisWeights => method == Method::Mis,
            Setting::Spp => method == Method::Reference,
            Setting::PsmRes => vpls && self.visibility == Visibility::Psm,
            // `--cdf-seed` sets both the importance's seed and the VPLs' places in their texels (`cdf_seed`
            // and `vpl_seed`): every VPL frame reads the latter.
            Setting::CdfSeed => vpls,
            Setting::Source | Setting::Candidates | Setting::Picks => method == Method::Ris,
            Setting::Denoise => method == Method::Realtime,
        }
    }
}
