//! `FrameSettings::reads` against the images: for every method, visibility and ris source (and the
//! direct component, and a pinned VPL set), each setting is changed alone, and the image must change
//! exactly where `reads` says the frame reads it. A setting said unread must leave the image the same bit
//! for bit (`bounce render` tells the user it was ignored); a setting said read must move it.

use bounce_graph::frame::{
    Component, FaceMode, FrameSettings, LightMap, Method, MisWeights, Renderer, RisSource, Setting, Visibility,
    VplKernel,
};
use bounce_graph::scene::Scene;
use bounce_tests::TestGpu;

/// The frames the settings are read in: small, every product made afresh.
fn base() -> FrameSettings {
    FrameSettings {
        width: 8,
        height: 8,
        vpls: 4,
        dprsm_res: 16,
        voxels: 16,
        cdf_samples: 8,
        spp: 4,
        psm_res: 32,
        ris: bounce_graph::frame::RisSettings { candidates: 8, ..Default::default() },
        ..FrameSettings::default()
    }
}

/// `s` with `setting` changed to another valid value.
fn changed(s: &FrameSettings, setting: Setting) -> FrameSettings {
    let mut t = s.clone();
    match setting {
        Setting::Vpls => t.vpls += 1,
        Setting::Seed => t.seed += 1,
        Setting::DprsmRes => t.dprsm_res = 12,
        Setting::Voxels => t.voxels = 12,
        Setting::VplKernel => {
            t.vpl_kernel = if s.vpl_kernel == VplKernel::Patch { VplKernel::Point } else { VplKernel::Patch }
        }
        Setting::CdfSamples => t.cdf_samples = 5,
        Setting::Regions => t.regions = 9,
        Setting::GatherRays => t.gather_rays = 2,
        Setting::Defensive => t.defensive = 0.3,
        Setting::Face => {
            t.face = if s.face == FaceMode::Uniform { FaceMode::RussianRoulette } else { FaceMode::Uniform }
        }
        Setting::MisWeights => {
            t.mis_weights =
                if s.mis_weights == MisWeights::Thesis { MisWeights::Consistent } else { MisWeights::Thesis }
        }
        Setting::Spp => t.spp += 1,
        Setting::Visibility => {
            t.visibility = if s.visibility == Visibility::Exact { Visibility::Voxel } else { Visibility::Exact }
        }
        Setting::PsmRes => t.psm_res = 24,
        Setting::LightMap => t.light_map = LightMap::Cube,
        // As `--cdf-seed` sets them: the importance's seed and the VPL set's.
        Setting::CdfSeed => {
            let c = Some(s.cdf_seed.map_or(7, |c| c + 1));
            (t.cdf_seed, t.vpl_seed) = (c, c);
        }
        Setting::Source => {
            t.ris.source = if s.ris.source == RisSource::Global { RisSource::Uniform } else { RisSource::Global }
        }
        Setting::Candidates => t.ris.candidates = 5,
        Setting::Picks => t.ris.picks = 2,
        Setting::Denoise => t.denoise = !s.denoise,
    }
    t
}

/// The frames whose reads are checked.
fn bases() -> Vec<FrameSettings> {
    let b = base();
    let mut v = vec![
        FrameSettings { component: Component::Direct, method: Method::Ris, ..b.clone() },
        FrameSettings { component: Component::Direct, method: Method::Global, ..b.clone() },
        // An animation's VPL set, pinned to the seed's; `--cdf-seed`'s (both seeds).
        FrameSettings { method: Method::All, vpl_seed: Some(b.seed), ..b.clone() },
        FrameSettings { method: Method::Uniform, vpl_seed: Some(b.seed), ..b.clone() },
        FrameSettings { method: Method::All, cdf_seed: Some(3), vpl_seed: Some(3), ..b.clone() },
        FrameSettings { method: Method::Global, cdf_seed: Some(3), vpl_seed: Some(3), ..b.clone() },
    ];
    for method in Method::ALL {
        for visibility in [Visibility::Exact, Visibility::Voxel, Visibility::Psm] {
            v.push(FrameSettings { method, visibility, ..b.clone() });
        }
    }
    for source in [RisSource::Global, RisSource::Stratified, RisSource::Local, RisSource::Gbg] {
        let ris = bounce_graph::frame::RisSettings { source, ..b.ris };
        v.push(FrameSettings { method: Method::Ris, ris, ..b.clone() });
    }
    v
}

fn valid(gpu: &TestGpu, r: &Renderer, s: &FrameSettings) -> bool {
    s.validate(gpu).is_ok() && r.check(s).is_ok()
}

fn image(r: &mut Renderer, s: &FrameSettings) -> Vec<[f32; 4]> {
    r.clear_frame_cache();
    r.render(s).unwrap().radiance
}

#[test]
fn a_setting_is_read_exactly_where_changing_it_changes_the_image() {
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let mut wrong = vec![];
    let mut checked = 0;
    for s in bases() {
        if !valid(&gpu, &r, &s) {
            continue;
        }
        let before = image(&mut r, &s);
        assert_eq!(before, image(&mut r, &s), "{:?} {:?}: the same settings gave two images", s.method, s.visibility);
        for setting in Setting::ALL {
            let t = changed(&s, setting);
            if !valid(&gpu, &r, &t) {
                continue;
            }
            let moved = image(&mut r, &t) != before;
            checked += 1;
            if moved != s.reads(setting) {
                let what = if moved { "changed the image, said unread" } else { "left the image, said read" };
                wrong.push(format!(
                    "{:?} {:?} {:?} source {:?} vpl_seed {:?}: {setting:?} {what}",
                    s.component, s.method, s.visibility, s.ris.source, s.vpl_seed
                ));
            }
        }
    }
    eprintln!("{checked} settings checked");
    assert!(checked > 400, "only {checked} settings were checked");
    assert!(wrong.is_empty(), "{} wrong:\n{}", wrong.len(), wrong.join("\n"));
}
