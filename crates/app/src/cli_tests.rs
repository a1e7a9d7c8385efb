//! The command line's parsing (`crate::cli`), unit-tested.

use super::*;
use clap::CommandFactory;

fn parse(args: &[&str]) -> Command {
    Cli::try_parse_from(["bounce"].iter().chain(args)).expect("valid arguments").command
}

#[test]
fn the_schema_is_consistent() {
    Cli::command().debug_assert();
}

#[test]
fn every_choice_parses_to_its_graph_value() {
    for (name, value, _) in METHODS.0 {
        let Command::Render(a) = parse(&["render", "s.toml", "--method", name]) else { panic!() };
        assert_eq!(a.picture.method, Some(*value));
    }
    for (name, value, _) in VISIBILITIES.0 {
        let Command::Render(a) = parse(&["render", "s.toml", "--visibility", name]) else { panic!() };
        assert_eq!(a.frame.visibility, *value);
    }
    let Command::Render(a) = parse(&["render", "s.toml", "--light-map", "rsm:60"]) else { panic!() };
    assert_eq!(a.frame.settings(8, 8).light_map, LightMap::Rsm { fov_deg: 60.0 });
    let Command::Bench(a) = parse(&["bench", "s.toml", "--out", "o", "--methods", "gbg,mis"]) else { panic!() };
    assert_eq!(a.methods, [Method::Gbg, Method::Mis]);
    assert!(Cli::try_parse_from(["bounce", "render", "s.toml", "--face", "sideways"]).is_err());
}

#[test]
fn each_command_keeps_its_own_defaults() {
    let Command::Render(r) = parse(&["render", "s.toml"]) else { panic!() };
    assert_eq!((r.picture.vpls, r.frame.dprsm_res), (None, 512));
    let Command::View(v) = parse(&["view", "s.toml"]) else { panic!() };
    assert_eq!((v.picture.vpls, v.frame.dprsm_res), (Some(16), 256));
    let Command::Bench(b) = parse(&["bench", "s.toml", "--out", "o"]) else { panic!() };
    assert_eq!((b.width, b.height, b.frame.dprsm_res), (128, 128, 128));
}

/// Both schedules give the frames of an unchanged scene fresh seeds (so a static view's progressive
/// mean converges: `view_30_frames_under_xvfb_shows_the_scene` checks it against `all` with the
/// default, `coherent`); after each change `coherent` starts again from the base seed, `fresh` never.
#[test]
fn temporal_schedules() {
    for t in [Temporal::Coherent, Temporal::Fresh] {
        let seeds: Vec<u64> = (0..5).map(|k| t.seed(7, k, k)).collect();
        assert_eq!(seeds, [7, 8, 9, 10, 11], "{t:?}: an unchanged scene's frames");
    }
    let moving = |t: Temporal| (0..4).map(|k| t.seed(7, k, 0)).collect::<Vec<_>>();
    assert_eq!(moving(Temporal::Coherent), [7, 7, 7, 7]);
    assert_eq!(moving(Temporal::Fresh), [7, 8, 9, 10]);
}

/// The flags' defaults are the graph's defaults, so a command that sets nothing renders what
/// `FrameSettings::default()` describes (size and the per-command defaults aside).
#[test]
fn frame_flag_defaults_are_the_graph_defaults() {
    let Command::Render(r) = parse(&["render", "s.toml"]) else { panic!() };
    let (ours, graph) = (r.frame.settings(256, 256), FrameSettings::default());
    assert_eq!(format!("{ours:?}"), format!("{graph:?}"));
}

/// A scene's folder names its `scene.toml` in every command that takes one scene; a file, or a folder
/// without one, is taken as given (loading then fails with its own `error:` line).
#[test]
fn a_scene_folder_names_its_scene_toml() {
    let dir = std::env::temp_dir().join(format!("bounce-scene-folder-{}", std::process::id()));
    let bare = dir.join("bare");
    std::fs::create_dir_all(&bare).unwrap();
    std::fs::write(dir.join("scene.toml"), "").unwrap();
    let d = dir.to_str().unwrap();
    let Command::Render(r) = parse(&["render", d]) else { panic!() };
    assert_eq!(r.scene, dir.join("scene.toml"));
    let Command::View(v) = parse(&["view", d]) else { panic!() };
    assert_eq!(v.scene, dir.join("scene.toml"));
    let Command::Bench(b) = parse(&["bench", d, "--out", "o"]) else { panic!() };
    assert_eq!(b.scene, dir.join("scene.toml"));
    let Command::Render(r) = parse(&["render", bare.to_str().unwrap()]) else { panic!() };
    assert_eq!(r.scene, bare);
    let Command::Render(r) = parse(&["render", "s.toml"]) else { panic!() };
    assert_eq!(r.scene, PathBuf::from("s.toml"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every frame setting has a flag, and every flag's id is an argument of `render`, `bench` and `suite`
/// (a misspelt id would never be found given, and its warning never said).
#[test]
fn every_setting_has_a_flag_of_the_commands_that_warn() {
    use crate::commands::SETTING_FLAGS;
    use bounce_graph::frame::Setting;
    for s in Setting::ALL {
        assert_eq!(SETTING_FLAGS.iter().filter(|(_, f)| *f == s).count(), 1, "{s:?}");
    }
    let mut cmd = Cli::command();
    cmd.build();
    for name in ["render", "bench", "suite"] {
        let sub = cmd.find_subcommand(name).unwrap();
        let ids: Vec<&str> = sub.get_arguments().map(|a| a.get_id().as_str()).collect();
        for (id, _) in SETTING_FLAGS {
            // bench and suite sweep the seed themselves; render has every flag.
            if name != "render" && id == "seed" {
                continue;
            }
            assert!(ids.contains(&id), "`{name}` has no argument `{id}`");
        }
    }
}
