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
use bounce_graph::frame::{FrameSettings, Method, Renderer, RisSource};
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

/// The flags given that `method` does not read (a user who sets one expects it to act), said once as a
/// warning on `err`: the sample count of a method that takes every VPL, a fixed budget or samples paths;
/// the path tracer's samples; ris's source, candidates and picks (realtime's are fixed).
fn warn_ignored_flags(vpls: Option<u32>, frame: &FrameArgs, method: Method, err: &mut dyn Write) -> Result<()> {
    let samples_vpls = !matches!(method, Method::All | Method::Reference | Method::Realtime);
    let ris = method == Method::Ris;
    let ignored: Vec<&str> = [
        ("--vpls", vpls.is_some() && !samples_vpls),
        ("--spp", frame.spp.is_some() && method != Method::Reference),
        ("--source", frame.source.is_some() && !ris),
        ("--candidates", frame.candidates.is_some() && !ris),
        ("--picks", frame.picks.is_some() && !ris),
    ]
    .into_iter()
    .filter_map(|(flag, ignored)| ignored.then_some(flag))
    .collect();
    if !ignored.is_empty() {
        writeln!(err, "warning: {} not read by --method {}", ignored.join(", "), method.name())?;
    }
    Ok(())
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
    let gathered = frame.source.is_none()
        && frame.defensive.is_none()
        && blocked.is_some_and(|b| b >= crate::cli::RIS_GATHERED_BLOCKED);
    if gathered {
        (settings.ris.source, settings.defensive) = (RisSource::Gbg, crate::cli::RIS_GATHERED_DEFENSIVE);
    }
    let share = blocked.map_or("nothing lit in view".into(), |b| format!("{:.0} %", 100.0 * b));
    let source = if gathered {
        format!(", from the gathered CDF (gbg, defensive {})", crate::cli::RIS_GATHERED_DEFENSIVE)
    } else {
        String::new()
    };
    Ok(format!(
        "ris per frame: {r} reservoirs × {m} candidates ({} from the near window){source}, {k} picks each; visibility blocks {share} of the view's unshadowed transport",
        n.min(m.saturating_sub(1))
    ))
}
