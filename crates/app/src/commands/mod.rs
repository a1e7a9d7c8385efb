//! One module per command; each `run` takes the parsed arguments and the two output streams, and
//! returns an error for `crate::error` to report. What several commands do alike lives here.

pub mod bench;
pub mod compare;
pub mod info;
pub mod render;
pub mod view;

use crate::cli::FrameArgs;
use anyhow::Result;
use bounce_device::Gpu;
use bounce_graph::frame::{Component, FrameSettings, Method, Renderer, RisSource, Setting};
use bounce_graph::scene::Scene;
use std::io::Write;
use std::path::Path;

/// Loads the scene and prints its one-line summary on `err`. A scene that does not load is a
/// `SceneError`, which the exit-code policy counts as bad input.
fn load_scene(path: &Path, err: &mut dyn Write) -> Result<Scene> {
    let scene = Scene::load(path)?;
    writeln!(err, "{}", scene.summary())?;
    Ok(scene)
}

/// Each frame setting's flag, by clap's argument id (a test holds it against `Setting::ALL` and the
/// commands' arguments).
pub(crate) const SETTING_FLAGS: [(&str, Setting); 20] = [
    ("vpls", Setting::Vpls),
    ("seed", Setting::Seed),
    ("dprsm_res", Setting::DprsmRes),
    ("voxels", Setting::Voxels),
    ("vpl_kernel", Setting::VplKernel),
    ("cdf_samples", Setting::CdfSamples),
    ("regions", Setting::Regions),
    ("gather_rays", Setting::GatherRays),
    ("defensive", Setting::Defensive),
    ("face", Setting::Face),
    ("mis_weights", Setting::MisWeights),
    ("spp", Setting::Spp),
    ("visibility", Setting::Visibility),
    ("psm_res", Setting::PsmRes),
    ("light_map", Setting::LightMap),
    ("cdf_seed", Setting::CdfSeed),
    ("source", Setting::Source),
    ("candidates", Setting::Candidates),
    ("picks", Setting::Picks),
    ("denoise", Setting::Denoise),
];

/// The frame settings whose flags `m` (a command's matches) has from the command line, not from a default.
pub fn given_settings(m: &clap::ArgMatches) -> Vec<Setting> {
    let given =
        |id: &str| m.ids().any(|i| i == id) && m.value_source(id) == Some(clap::parser::ValueSource::CommandLine);
    SETTING_FLAGS.iter().filter(|(id, _)| given(id)).map(|&(_, s)| s).collect()
}

/// The flags given that the frame does not read ([`FrameSettings::reads`]: a user who sets one expects
/// it to act), said once as a warning on `err`, with the settings that decide it. Under a time limit
/// (`progressive`) realtime's frames are averaged raw, and `--denoise` is not read either.
fn warn_ignored_flags(given: &[Setting], s: &FrameSettings, progressive: bool, err: &mut dyn Write) -> Result<()> {
    let raw_mean = progressive && s.method == Method::Realtime;
    if raw_mean && given.contains(&Setting::Denoise) {
        writeln!(err, "warning: --time-limit averages realtime's raw frames and does not read --denoise")?;
    }
    let given: Vec<Setting> = given.iter().copied().filter(|g| !(raw_mean && *g == Setting::Denoise)).collect();
    let given = given.as_slice();
    let frame = if s.component == Component::Direct {
        "--component direct".to_string()
    } else {
        let source = match s.method {
            Method::Ris => format!(", --source {}", crate::cli::RIS_SOURCES.name_of(&s.ris.source)),
            _ => String::new(),
        };
        let visibility = crate::cli::VISIBILITIES.name_of(&s.visibility);
        format!("--method {}, --visibility {visibility}{source}", s.method.name())
    };
    warn_unread(given, std::slice::from_ref(s), &format!("this frame ({frame}) does not read"), err)
}

/// The flags given that none of `frames` reads, said as one warning on `err`: `{what} --a, --b`.
fn warn_unread(given: &[Setting], frames: &[FrameSettings], what: &str, err: &mut dyn Write) -> Result<()> {
    let ignored: Vec<String> = SETTING_FLAGS
        .iter()
        .filter(|(_, setting)| given.contains(setting) && !frames.iter().any(|s| s.reads(*setting)))
        .map(|(id, _)| format!("--{}", id.replace('_', "-")))
        .collect();
    if !ignored.is_empty() {
        writeln!(err, "warning: {what} {}", ignored.join(", "))?;
    }
    Ok(())
}

/// Under `bench` and `suite`, the flags given that no method of `methods` reads on `base` (with
/// `per_view`, ris's per-view budget at equal time, ris also from the gathered source, which it takes
/// where visibility blocks most of a view unless --source is given).
fn warn_unread_by_methods(
    given: &[Setting],
    base: &FrameSettings,
    methods: &[Method],
    per_view: bool,
    err: &mut dyn Write,
) -> Result<()> {
    let mut frames: Vec<FrameSettings> =
        methods.iter().map(|&method| FrameSettings { method, ..base.clone() }).collect();
    if per_view && methods.contains(&Method::Ris) && !given.contains(&Setting::Source) {
        let ris = bounce_graph::frame::RisSettings { source: RisSource::Gbg, ..base.ris };
        frames.push(FrameSettings { method: Method::Ris, ris, ..base.clone() });
    }
    let names: Vec<&str> = methods.iter().map(|m| m.name()).collect();
    warn_unread(given, &frames, &format!("no method of --methods {} reads", names.join(",")), err)
}

/// With `--validation`, fails if the layers reported anything during the command.
fn check_validation(gpu: &Gpu, validation: bool) -> Result<()> {
    if validation {
        let msgs = gpu.validation().messages();
        anyhow::ensure!(msgs.is_empty(), "{} validation message(s); first: {}", msgs.len(), msgs[0]);
    }
    Ok(())
}

/// ris's reservoirs, candidates, picks and source per progressive frame under a time budget when
/// `--vpls` is not given (`render --time-limit`, and `suite` and `bench` at equal time, so that they
/// measure ris as `render` runs it): chosen per view by the share of the unshadowed transport that visibility
/// blocks ([`crate::cli::RIS_FRAME_BLOCKED`], [`crate::cli::RIS_FRAME_OPEN`],
/// [`crate::cli::RIS_GATHERED_BLOCKED`]); --candidates, --near-candidates, --picks, --source and
/// --defensive stand where given. Returns the line that says what was chosen.
fn ris_frame_budget(frame: &FrameArgs, renderer: &mut Renderer, settings: &mut FrameSettings) -> Result<String> {
    let blocked = renderer.blocked_share(settings.width, settings.height)?;
    let (r, m, n, k) = if frame.candidates.is_none() && !frame.near_candidates_given() {
        if blocked.is_some_and(|b| b < bounce_graph::passes::ris::AUTO_LEARN_BLOCKED) {
            crate::cli::RIS_FRAME_OPEN
        } else {
            crate::cli::RIS_FRAME_BLOCKED
        }
    } else {
        let k = crate::cli::RIS_FRAME_BLOCKED.3;
        (crate::cli::RIS_FRAME_BLOCKED.0, settings.ris.candidates, settings.ris.near_candidates, k)
    };
    // An explicit --picks stands.
    let k = frame.picks.unwrap_or(k);
    (settings.vpls, settings.ris.candidates, settings.ris.near_candidates, settings.ris.picks) = (r, m, n, k);
    // A given --defensive is the gathered source's share; it does not decide the source.
    let gathered = frame.source.is_none() && blocked.is_some_and(|b| b >= crate::cli::RIS_GATHERED_BLOCKED);
    if gathered {
        settings.ris.source = RisSource::Gbg;
        settings.defensive = frame.defensive.unwrap_or(crate::cli::RIS_GATHERED_DEFENSIVE);
    }
    let share = blocked.map_or("nothing lit in view".into(), |b| format!("{:.0} %", 100.0 * b));
    let source = match gathered {
        true => format!(", from the gathered CDF (gbg, defensive {})", settings.defensive),
        false => String::new(),
    };
    Ok(format!(
        "ris per frame: {r} reservoirs × {m} candidates ({} from the near window){source}, {k} picks each; visibility blocks {share} of the view's unshadowed transport",
        n.min(m.saturating_sub(1))
    ))
}
