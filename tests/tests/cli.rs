//! The `bounce` command line, run in-process through `bounce::run` (the binary's `main` is only that
//! call): exit codes, one-line errors naming the file, no output file on failure, the timings table,
//! and the EXR's metadata.

use bounce::output::read_exr;
use std::path::{Path, PathBuf};

struct Run {
    code: i32,
    stdout: String,
    stderr: String,
}

fn bounce(args: &[&str]) -> Run {
    let mut argv = vec!["bounce".into()];
    argv.extend(args.iter().map(|a| a.into()));
    let (mut out, mut err) = (vec![], vec![]);
    let code = bounce::run(argv, &mut out, &mut err);
    Run { code, stdout: String::from_utf8_lossy(&out).into(), stderr: String::from_utf8_lossy(&err).into() }
}

fn scratch(name: &str) -> PathBuf {
    let d = bounce_tests::evidence_dir().join(format!("cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn error_lines(r: &Run) -> Vec<&str> {
    r.stderr.lines().filter(|l| l.starts_with("error")).collect()
}

#[test]
fn render_writes_exr_png_and_timings() {
    let d = scratch("render");
    let exr = d.join("img.exr");
    let png = d.join("img.png");
    let scene = bounce_tests::default_scene();
    let r = bounce(&[
        "render",
        scene.to_str().unwrap(),
        "--out",
        exr.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "24",
        "--component",
        "direct",
        "--validation",
        "--timings",
    ]);
    assert_eq!(r.code, 0, "stderr: {}", r.stderr);
    for pass in ["gbuffer", "direct", "total"] {
        assert!(r.stdout.lines().any(|l| l.starts_with(pass)), "timings table lacks {pass}:\n{}", r.stdout);
    }
    // The direct light traces its shadow rays: no light map is rendered for it.
    let drawn = |l: &str| l.starts_with("dprsm") && !l.ends_with("skipped");
    assert!(!r.stdout.lines().any(drawn), "a light map for direct light:\n{}", r.stdout);
    let (img, meta) = read_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (32, 24));
    assert!(img.pixels.iter().any(|p| p[0] > 0.0), "black image");
    let get = |k: &str| meta.iter().find(|(key, _)| key == k).map(|(_, v)| v.clone());
    assert_eq!(get("bounce.component").as_deref(), Some("direct"));
    for k in ["bounce.scene", "bounce.method", "bounce.seed", "bounce.device", "bounce.gpu_ms"] {
        assert!(get(k).is_some(), "EXR lacks {k}: {meta:?}");
    }
    let png_img = std::fs::read(&png).unwrap();
    assert_eq!(&png_img[1..4], b"PNG");
    // Nothing but the outputs is left behind (no temporary files).
    let names: Vec<_> = std::fs::read_dir(&d).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

fn expect_bad_input(args: &[&str], must_name: &str, out: &Path) {
    let r = bounce(args);
    assert_eq!(r.code, 2, "args {args:?}: stderr {}", r.stderr);
    let errs = error_lines(&r);
    assert_eq!(errs.len(), 1, "want one error line, got: {}", r.stderr);
    assert!(errs[0].contains(must_name), "error does not name `{must_name}`: {}", errs[0]);
    assert!(!out.exists(), "an output file was written despite the error");
}

#[test]
fn a_missing_mesh_is_exit_2_naming_the_file() {
    let d = scratch("missing-mesh");
    let scene = d.join("s.toml");
    std::fs::write(
        &scene,
        "mesh = \"nothere.obj\"\n[camera]\neye=[0,1,3]\ntarget=[0,1,0]\nup=[0,1,0]\nfov_y=40\n[[light]]\nposition=[0,1,0]\nintensity=[1,1,1]\n",
    )
    .unwrap();
    let out = d.join("o.exr");
    expect_bad_input(&["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap()], "nothere.obj", &out);
}

#[test]
fn a_malformed_scene_is_exit_2_naming_file_and_line() {
    let d = scratch("malformed");
    let scene = d.join("broken.toml");
    std::fs::write(&scene, "mesh = \"x.obj\"\n[camera]\neye = [0, 1, \n").unwrap();
    let out = d.join("o.exr");
    expect_bad_input(&["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap()], "broken.toml:", &out);
    let r = bounce(&["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    let line = error_lines(&r)[0].to_string();
    assert!(line.contains("broken.toml:3") || line.contains("broken.toml:4"), "no line number: {line}");
}

#[test]
fn a_missing_scene_file_and_impossible_sizes_are_exit_2() {
    let d = scratch("sizes");
    let out = d.join("o.exr");
    expect_bad_input(
        &["render", d.join("absent.toml").to_str().unwrap(), "--out", out.to_str().unwrap()],
        "absent.toml",
        &out,
    );
    let scene = bounce_tests::default_scene();
    expect_bad_input(
        &["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--width", "0"],
        "width",
        &out,
    );
    expect_bad_input(
        &["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--height", "100000"],
        "maxImageDimension2D",
        &out,
    );
    let r = bounce(&["render", scene.to_str().unwrap(), "--component", "sideways"]);
    assert_eq!(r.code, 2);
    assert_eq!(r.stderr.lines().count(), 1, "an argument error is one line: {}", r.stderr);
    assert!(r.stderr.starts_with("error:") && r.stderr.contains("sideways"), "{}", r.stderr);
    for (flag, value, named) in [
        ("--regions", "3", "regions"),
        ("--vpls", "0", "VPL count"),
        ("--defensive", "1.5", "defensive"),
        ("--gather-rays", "0", "gather-rays"),
        ("--voxels", "0", "voxels"),
    ] {
        expect_bad_input(
            &["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), flag, value],
            named,
            &out,
        );
    }
}

#[test]
fn info_lists_the_device() {
    let r = bounce(&["info"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("usable by bounce: yes"), "{}", r.stdout);
    assert!(r.stdout.contains("timestampValidBits"), "{}", r.stdout);
}

#[test]
fn bench_writes_csv_markdown_and_a_plot() {
    let d = scratch("bench");
    let scene = bounce_tests::default_scene();
    let args = [
        "bench",
        scene.to_str().unwrap(),
        "--out",
        d.to_str().unwrap(),
        "--methods",
        "uniform,gbg",
        "--vpls",
        "2,4",
        "--repeats",
        "2",
        "--width",
        "16",
        "--height",
        "16",
        "--dprsm-res",
        "16",
        "--voxels",
        "16",
        "--validation",
    ];
    let r = bounce(&args);
    assert_eq!(r.code, 0, "stderr: {}", r.stderr);
    let csv = std::fs::read_to_string(d.join("bench.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * 2 * 2, "one row per frame:\n{csv}");
    assert!(csv.lines().skip(1).all(|l| l
        .split(',')
        .nth(6)
        .and_then(|v| v.parse::<f64>().ok())
        .is_some_and(|v| v.is_finite())));
    let md = std::fs::read_to_string(d.join("bench.md")).unwrap();
    assert!(md.contains("| uniform |") && md.contains("| gbg |"), "{md}");
    assert_eq!(&std::fs::read(d.join("time_vs_error.png")).unwrap()[1..4], b"PNG");
    // The reference is cached: a second run does not render it again.
    let r2 = bounce(&args);
    assert_eq!(r2.code, 0);
    assert!(r2.stderr.contains("(cached)"), "{}", r2.stderr);
    let bad = bounce(&["bench", scene.to_str().unwrap(), "--out", d.to_str().unwrap(), "--methods", "all"]);
    assert_eq!(bad.code, 2);
    // An output folder under a file: one line, before the scene is loaded.
    let under_a_file = d.join("bench.csv").join("more");
    let bad = bounce(&["bench", scene.to_str().unwrap(), "--out", under_a_file.to_str().unwrap()]);
    assert_eq!(bad.code, 2, "{}", bad.stderr);
    assert!(error_lines(&bad).len() == 1 && bad.stderr.contains("is not a directory"), "{}", bad.stderr);
}

/// A cached ground truth is its scene's: edit the scene (here its light) and the next run renders the
/// truth anew instead of measuring against the old scene's; the same scene takes the cache again. A
/// dark scene's bench writes its whole output.
#[test]
fn a_cached_reference_is_rendered_anew_when_the_scene_changes() {
    let d = scratch("bench-edited");
    let obj = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 2 -1\nv 1 2 -1\nf 1 3 2\nf 1 4 3\nf 1 2 6\nf 1 6 5\n";
    std::fs::write(d.join("m.obj"), obj).unwrap();
    let toml = |i: f32| {
        format!("mesh = \"m.obj\"\n[camera]\neye=[0,1,3]\ntarget=[0,0.5,0]\nup=[0,1,0]\nfov_y=50\n[[light]]\nposition=[0,1.5,0.5]\nintensity=[{i},{i},{i}]\n")
    };
    let scene = d.join("s.toml");
    let out = d.join("out");
    let run = || {
        let args = ["bench", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--methods", "uniform"];
        let small = [
            "--vpls",
            "2",
            "--repeats",
            "1",
            "--reference-spp",
            "4",
            "--width",
            "8",
            "--height",
            "8",
            "--dprsm-res",
            "16",
        ];
        let r = bounce(&[&args[..], &small[..]].concat());
        assert_eq!(r.code, 0, "{}", r.stderr);
        r.stderr
    };
    std::fs::write(&scene, toml(1.0)).unwrap();
    assert!(run().contains("reference: rendering"));
    assert!(run().contains("(cached)"));
    std::fs::write(&scene, toml(2.0)).unwrap();
    let edited = run();
    assert!(
        edited.contains("made for another version of the scene") && edited.contains("reference: rendering"),
        "{edited}"
    );
    assert!(run().contains("(cached)"));
    // A dark scene (every error 0, nothing for the log axes) still writes its tables and its plot, the
    // plot's axes empty (it was an error after the tables were written, leaving an old plot beside them).
    std::fs::write(&scene, toml(0.0)).unwrap();
    let dark = run();
    assert!(dark.contains("reference: rendering"), "{dark}");
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("| uniform |"), "{md}");
    assert_eq!(&std::fs::read(out.join("time_vs_error.png")).unwrap()[1..4], b"PNG");
}

/// `compare`: relMSE and the mean ratio of a test EXR against a reference by their closed forms (one
/// pixel off by 1 of four, all channels: relMSE = ¼ · 1 / (1 + 0.01)); a reference with a non-finite
/// pixel, or of another size, is one error line and exit 2.
#[test]
fn compare_measures_an_exr_against_a_reference() {
    use bounce::output::{write_exr, RgbImage};
    let d = scratch("compare");
    let img = |pixels: Vec<[f32; 3]>| RgbImage { width: 2, height: 2, pixels };
    let path = |name: &str| d.join(name).to_str().unwrap().to_string();
    write_exr(Path::new(&path("ref.exr")), &img(vec![[1.0; 3]; 4]), &[]).unwrap();
    write_exr(Path::new(&path("test.exr")), &img(vec![[2.0; 3], [1.0; 3], [1.0; 3], [1.0; 3]]), &[]).unwrap();
    let r = bounce(&["compare", &path("test.exr"), &path("ref.exr"), "--json"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let field = |k: &str| -> f64 {
        let at = r.stdout.find(&format!("\"{k}\": ")).unwrap() + k.len() + 4;
        r.stdout[at..].split([',', '}']).next().unwrap().trim().parse().unwrap()
    };
    assert!((field("rel_mse") - 0.25 / 1.01).abs() < 1e-9, "{}", r.stdout);
    assert!((field("mean_ratio") - 1.25).abs() < 1e-9, "{}", r.stdout);
    write_exr(Path::new(&path("nan.exr")), &img(vec![[1.0; 3], [f32::NAN, 1.0, 1.0], [1.0; 3], [1.0; 3]]), &[])
        .unwrap();
    expect_bad_input(&["compare", &path("test.exr"), &path("nan.exr")], "non-finite", &d.join("none"));
    let wide = RgbImage { width: 4, height: 1, pixels: vec![[1.0; 3]; 4] };
    write_exr(Path::new(&path("wide.exr")), &wide, &[]).unwrap();
    expect_bad_input(&["compare", &path("test.exr"), &path("wide.exr")], "2x2", &d.join("none"));
    // A file that is no EXR is named so (an empty one read "failed to fill whole buffer", a PNG "file
    // identifier missing").
    std::fs::write(path("empty.exr"), "").unwrap();
    expect_bad_input(&["compare", &path("empty.exr"), &path("ref.exr")], "not an OpenEXR file", &d.join("none"));
    // The heatmap is said to be written.
    let r = bounce(&["compare", &path("test.exr"), &path("ref.exr"), "--heatmap", &path("flip.png")]);
    assert!(r.code == 0 && r.stderr.contains("wrote") && d.join("flip.png").exists(), "{}", r.stderr);
    // No command is one line, not the program's tagline as an error; a command's usage error points to
    // that command's help.
    expect_bad_input(&[], "no command given", &d.join("none"));
    expect_bad_input(&["compare", "--frobnicate"], "bounce compare --help", &d.join("none"));
    // Also where clap's message has no usage line (an invalid value).
    let s = bounce_tests::default_scene();
    expect_bad_input(&["render", s.to_str().unwrap(), "--method", "psm"], "bounce render --help", &d.join("none"));
}

/// A frame flag given that the frame does not read is said (`FrameSettings::reads`, which the reads
/// tests hold against the images), with the settings that decide it, also when given at its default
/// value; flags it reads are not. `bench` says those no method of its sweep reads.
#[test]
fn flags_the_frame_does_not_read_are_said() {
    let d = scratch("ignored-flags");
    let scene = bounce_tests::default_scene();
    let out = d.join("o.exr");
    let run = |extra: &[&str]| {
        let mut args = vec!["render", scene.to_str().unwrap(), "--width", "8", "--height", "8"];
        args.extend(["--out", out.to_str().unwrap()]);
        args.extend(extra);
        let r = bounce(&args);
        assert_eq!(r.code, 0, "{}", r.stderr);
        r.stderr.lines().filter(|l| l.starts_with("warning:")).map(str::to_string).collect::<Vec<_>>()
    };
    let w = run(&["--method", "uniform", "--vpls", "2", "--candidates", "4", "--spp", "8", "--mis-weights", "thesis"]);
    let said = "this frame (--method uniform, --visibility exact) does not read --mis-weights, --spp, --candidates";
    assert!(w.iter().any(|l| l.contains(said)), "{w:?}");
    let w = run(&["--method", "realtime", "--vpls", "2", "--denoise", "on"]);
    assert!(w.iter().any(|l| l.ends_with("does not read --vpls")), "{w:?}");
    // A flag at its default value is still a flag given.
    let w = run(&["--method", "ris", "--mis-weights", "consistent", "--psm-res", "256"]);
    assert!(w.iter().any(|l| l.ends_with("--source uniform) does not read --mis-weights, --psm-res")), "{w:?}");
    let w = run(&["--component", "direct", "--seed", "3", "--dprsm-res", "16"]);
    assert!(w.iter().any(|l| l.ends_with("(--component direct) does not read --seed, --dprsm-res")), "{w:?}");
    assert!(run(&["--method", "ris", "--vpls", "2", "--candidates", "4"]).is_empty());
    // --cdf-seed places the VPLs of every VPL method (it was said unread beside `uniform`).
    assert!(run(&["--method", "uniform", "--vpls", "2", "--cdf-seed", "3"]).is_empty());
    // Under --time-limit the warning reads the settings the frames run: ris's budget takes the gathered
    // source in the two rooms (so --gather-rays and --defensive act), and realtime's frames are averaged raw.
    let rooms = bounce_tests::workspace().join("assets/two-rooms/scene.toml");
    let limited = |extra: &[&str]| {
        let mut args = vec!["render", rooms.to_str().unwrap(), "--width", "8", "--height", "8", "--dprsm-res", "16"];
        args.extend(["--out", out.to_str().unwrap(), "--time-limit", "0.2"]);
        args.extend(extra);
        let r = bounce(&args);
        assert_eq!(r.code, 0, "{}", r.stderr);
        r.stderr
    };
    let e = limited(&["--method", "ris", "--gather-rays", "2", "--defensive", "0.6"]);
    assert!(e.contains("gathered CDF (gbg, defensive 0.6)") && !e.contains("warning:"), "{e}");
    let e = limited(&["--method", "realtime", "--denoise", "on"]);
    assert!(e.contains("warning: --time-limit averages realtime's raw frames and does not read --denoise"), "{e}");
    // bench (and suite) say the flags no method of the sweep reads.
    let dir = d.join("bench");
    let mut args = vec!["bench", scene.to_str().unwrap(), "--out", dir.to_str().unwrap(), "--methods", "uniform,gbg"];
    args.extend(["--vpls", "2", "--repeats", "1", "--reference", "all", "--width", "8", "--height", "8"]);
    args.extend(["--dprsm-res", "16", "--mis-weights", "thesis", "--gather-rays", "2"]);
    let r = bounce(&args);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("warning: no method of --methods uniform,gbg reads --mis-weights\n"), "{}", r.stderr);
}

/// `--defensive 0` (the thesis's CDFs, without a defensive share) renders, and says it is biased; with a
/// share, or with `uniform`, nothing is said.
#[test]
fn a_cdf_without_a_defensive_share_is_said_to_be_biased() {
    let d = scratch("defensive");
    let scene = bounce_tests::default_scene();
    let out = d.join("g.exr");
    let run = |method: &str, share: &str| {
        let args = ["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--method", method];
        let r = bounce(
            &[&args[..], &["--defensive", share, "--vpls", "2", "--width", "8", "--height", "8", "--dprsm-res", "16"]]
                .concat(),
        );
        assert_eq!(r.code, 0, "{}", r.stderr);
        r.stderr.contains("--defensive 0: ")
    };
    assert!(run("global", "0"));
    assert!(!run("global", "0.5"));
    assert!(!run("uniform", "0"));
}

/// Broken inputs: each gives exit code 2, exactly one `error:` line naming what is wrong, no output file,
/// and no panic (a panic would not return through `bounce::run` as a code at all).
/// `bench --animate`: one CSV row per method, mode and frame; per-frame relMSE, flicker and mean ratio recomputed
/// from the frames `render --frames` makes with the same seeds and the cached per-frame ground truth
/// (an independent path to the same numbers); the means in bench.md; the plot; the references cached.
#[test]
fn bench_animate_writes_relmse_and_flicker_per_frame() {
    let d = scratch("bench-animate");
    let scene = bounce_tests::default_scene();
    let size = ["--width", "16", "--height", "16", "--dprsm-res", "16", "--voxels", "16"];
    let mut args = vec!["bench", scene.to_str().unwrap(), "--out", d.to_str().unwrap(), "--animate", "orbit:8"];
    args.extend(["--frames", "3", "--methods", "uniform", "--vpls", "4", "--reference-spp", "16", "--validation"]);
    args.extend(size);
    let r = bounce(&args);
    assert_eq!(r.code, 0, "stderr: {}", r.stderr);
    let csv = std::fs::read_to_string(d.join("bench.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 3 + 2, "one row per mode and frame, then one mean row per mode:\n{csv}");
    // The mean rows are the means of the frame rows (relMSE over every frame, flicker over frames 1..).
    for mode in ["fresh", "coherent"] {
        let of = |col: usize, from: u32| -> Vec<f64> {
            rows.iter()
                .filter(|r| r[1] == mode && r[2].parse::<u32>().is_ok_and(|k| k >= from))
                .map(|r| r[col].parse().unwrap())
                .collect()
        };
        let mean_row = rows.iter().find(|r| r[1] == mode && r[2] == "mean").expect("a mean row per mode");
        // Without a denoiser the raw estimate's GPU time is the frame's.
        assert!(rows.iter().filter(|r| r[1] == mode).all(|r| r[9] == r[3]), "raw_gpu_ms differs:\n{csv}");
        for (col, from) in [(5, 0), (6, 1)] {
            let v = of(col, from);
            let want = v.iter().sum::<f64>() / v.len() as f64;
            let got: f64 = mean_row[col].parse().unwrap();
            assert!((got - want).abs() <= 1e-5 * want.abs(), "{mode} column {col}: {got} vs {want}");
        }
    }
    let md = std::fs::read_to_string(d.join("bench.md")).unwrap();
    assert!(md.contains("| uniform | fresh |") && md.contains("| uniform | coherent |"), "{md}");
    assert_eq!(&std::fs::read(d.join("flicker.png")).unwrap()[1..4], b"PNG");
    // The same frames through `render --frames` (coherent: seed 1 and CDF seed 1 for every frame).
    let frames = d.join("frames");
    let mut a = vec!["render", scene.to_str().unwrap(), "--frames", "3", "--out-dir", frames.to_str().unwrap()];
    a.extend(["--light-path", "orbit:8", "--component", "indirect", "--method", "uniform", "--vpls", "4"]);
    a.extend(["--cdf-seed", "1"]);
    a.extend(size);
    assert_eq!(bounce(&a).code, 0);
    let truth: Vec<Vec<[f32; 3]>> = (0..3)
        .map(|k| {
            let name = std::fs::read_dir(&d)
                .unwrap()
                .map(|e| e.unwrap().path())
                .find(|p| p.to_string_lossy().ends_with(&format!("-frame{k:04}.exr")))
                .expect("the per-frame ground truth is cached in the output folder");
            read_exr(&name).unwrap().0.pixels
        })
        .collect();
    let rendered: Vec<Vec<[f32; 3]>> =
        (0..3).map(|k| read_exr(&frames.join(format!("frame_{k:04}.exr"))).unwrap().0.pixels).collect();
    for k in 0..3usize {
        let row = rows.iter().find(|r| r[1] == "coherent" && r[2] == k.to_string()).unwrap();
        let rel: f64 = row[5].parse().unwrap();
        let metrics = bounce::metrics::Metrics::of(&rendered[k], &truth[k]);
        let want = metrics.rel_mse;
        assert!((rel - want).abs() <= 1e-5 * want, "frame {k}: relMSE {rel} vs {want}");
        let ratio: f64 = row[10].parse().unwrap();
        assert!((ratio - metrics.mean_ratio).abs() <= 1e-5, "frame {k}: mean ratio {ratio} vs {}", metrics.mean_ratio);
        assert!(row[11].is_empty(), "a denoised mean ratio without a denoiser");
        if k > 0 {
            let f: f64 = row[6].parse().unwrap();
            let want = bounce::metrics::flicker(&rendered[k], &rendered[k - 1], &truth[k], &truth[k - 1]);
            assert!((f - want).abs() <= 1e-5 * want, "frame {k}: flicker {f} vs {want}");
        } else {
            assert!(row[6].is_empty(), "frame 0 has no flicker");
        }
    }
    // The mean row's mean ratio: Σ image means / Σ truth means over the frames.
    let sum = |imgs: &[Vec<[f32; 3]>]| imgs.iter().flatten().flatten().map(|&c| c as f64).sum::<f64>();
    let want = sum(&rendered) / sum(&truth);
    let got: f64 = rows.iter().find(|r| r[1] == "coherent" && r[2] == "mean").unwrap()[10].parse().unwrap();
    assert!((got - want).abs() <= 1e-4 * want, "mean ratio over the frames {got} vs {want}");
    let again = bounce(&args);
    assert_eq!(again.code, 0);
    assert!(!again.stderr.contains("reference: frame"), "the ground truth was rendered again: {}", again.stderr);
}

#[test]
fn bad_inputs_give_one_line_and_exit_2() {
    let d = scratch("bad-inputs");
    let good_obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let toml = |mesh: &str, extra: &str| {
        format!("mesh = \"{mesh}\"\n[camera]\neye=[0,0.5,3]\ntarget=[0,0.5,0]\nup=[0,1,0]\nfov_y=40\n[[light]]\nposition=[0,0.5,1]\nintensity=[1,1,1]\n{extra}")
    };
    // (name, files to write, args after the scene, text the error must contain)
    type Case<'a> = (&'a str, Vec<(&'a str, String)>, Vec<&'a str>, &'a str);
    let cases: Vec<Case> = vec![
        (
            "nan vertex",
            vec![("m.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".into()), ("s.toml", toml("m.obj", ""))],
            vec![],
            "m.obj:2",
        ),
        (
            "inf vertex",
            vec![("m.obj", "v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n".into()), ("s.toml", toml("m.obj", ""))],
            vec![],
            "m.obj:2",
        ),
        (
            "a vertex beyond f32 by its w",
            vec![("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0 1e-300\nf 1 2 3\n".into()), ("s.toml", toml("m.obj", ""))],
            vec![],
            "beyond f32",
        ),
        (
            "a light beyond f32",
            vec![
                ("m.obj", good_obj.into()),
                ("s.toml", toml("m.obj", "").replace("position=[0,0.5,1]", "position=[1e39,0.5,1]")),
            ],
            vec![],
            "light[0].position",
        ),
        (
            "index out of range",
            vec![("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n".into()), ("s.toml", toml("m.obj", ""))],
            vec![],
            "m.obj",
        ),
        (
            "missing mtl",
            vec![("m.obj", format!("mtllib nope.mtl\n{good_obj}")), ("s.toml", toml("m.obj", ""))],
            vec![],
            "nope.mtl",
        ),
        (
            "missing texture",
            vec![
                ("m.obj", format!("mtllib m.mtl\nusemtl a\n{good_obj}")),
                ("m.mtl", "newmtl a\nKd 1 1 1\nmap_Kd gone.png\n".into()),
                ("s.toml", toml("m.obj", "")),
            ],
            vec![],
            "gone.png",
        ),
        (
            "negative intensity",
            vec![
                ("m.obj", good_obj.into()),
                ("s.toml", toml("m.obj", "").replace("intensity=[1,1,1]", "intensity=[1,-1,1]")),
            ],
            vec![],
            "intensity",
        ),
        (
            "fov 180",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", "").replace("fov_y=40", "fov_y=180"))],
            vec![],
            "fov",
        ),
        (
            "unknown key",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", "[render]\nwidht = 3\n"))],
            vec![],
            "widht",
        ),
        (
            "no light",
            vec![
                ("m.obj", good_obj.into()),
                (
                    "s.toml",
                    "mesh = \"m.obj\"\n[camera]\neye=[0,0.5,3]\ntarget=[0,0.5,0]\nup=[0,1,0]\nfov_y=40\n".into(),
                ),
            ],
            vec![],
            "light",
        ),
        (
            "huge width",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", ""))],
            vec!["--width", "1000000"],
            "width",
        ),
        ("zero vpls", vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", ""))], vec!["--vpls", "0"], "VPL"),
        // A count no frame needs: 4 billion filled the host's memory with dispatches before the first frame.
        (
            "too many vpls",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", ""))],
            vec!["--vpls", "4000000000"],
            "VPL count",
        ),
        (
            "huge dprsm",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", ""))],
            vec!["--dprsm-res", "16384"],
            "DPRSM",
        ),
        (
            "binary garbage",
            vec![("m.obj", "\u{0}\u{1}\u{2}garbage\n\u{7f}".into()), ("s.toml", toml("m.obj", ""))],
            vec![],
            "m.obj",
        ),
        ("garbage toml", vec![("s.toml", "\u{0}\u{1}[[[ = =".into())], vec![], "s.toml"),
        (
            "more picks than a reservoir holds",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", ""))],
            vec!["--method", "ris", "--picks", "9"],
            "--picks",
        ),
        (
            "a visibility the product no longer has",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", ""))],
            vec!["--visibility", "hybrid"],
            "--visibility",
        ),
        // Checked before the render: the EXR, whose own path is fine, must not be written either.
        (
            "a PNG where there is no directory",
            vec![("m.obj", good_obj.into()), ("s.toml", toml("m.obj", ""))],
            vec!["--png", "no-such-directory-of-bounce/x.png"],
            "no-such-directory-of-bounce/x.png",
        ),
    ];
    for (name, files, args, must) in cases {
        let dir = d.join(name.replace(' ', "-"));
        std::fs::create_dir_all(&dir).unwrap();
        for (f, text) in &files {
            std::fs::write(dir.join(f), text).unwrap();
        }
        let out = dir.join("out.exr");
        let scene = dir.join("s.toml");
        let mut argv = vec!["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--height", "8"];
        if !args.contains(&"--width") {
            argv.extend(["--width", "8"]);
        }
        argv.extend(args.iter().copied());
        let r = bounce(&argv);
        assert_eq!(r.code, 2, "{name}: exit {} stderr {}", r.code, r.stderr);
        let errs = error_lines(&r);
        assert_eq!(errs.len(), 1, "{name}: want one error line, got: {}", r.stderr);
        assert!(errs[0].contains(must), "{name}: the error does not name `{must}`: {}", errs[0]);
        assert!(!out.exists(), "{name}: an output file was written");
    }
    // An output path that is a directory (or ends like one), one file named for both outputs, and a name
    // whose extension is not the format written (an EXR's bytes went into `x.png`, a scene file could
    // be overwritten by its own render). An animation's frame whose name a folder holds is found before
    // the first frame renders, and no frame is written.
    let dir = d.join("zero-vpls");
    let (scene, out) = (dir.join("s.toml"), dir.join("out.exr"));
    let (scene, out) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let frames = dir.join("frames");
    std::fs::create_dir_all(frames.join("frame_0001.png")).unwrap();
    let in_dir = |name: &str| format!("{}/{name}", dir.display());
    for (args, named) in [
        (vec!["--out", dir.to_str().unwrap()], "is a directory"),
        (vec!["--out", &in_dir("new/")], "is a directory"),
        (vec!["--out", out, "--png", &format!("{}/./out.exr", dir.display())], "the same file"),
        (vec!["--out", &in_dir("out.png")], "must end in .exr"),
        (vec!["--out", scene], "must end in .exr"),
        (vec!["--out", out, "--png", &in_dir("other.exr")], "must end in .png"),
        (vec!["--frames", "3", "--out-dir", frames.to_str().unwrap()], "frame_0001.png"),
        // An animation writes into --out-dir: an --out or --png beside it was ignored without a word.
        (vec!["--frames", "2", "--out-dir", frames.to_str().unwrap(), "--png", &in_dir("x.png")], "--png"),
    ] {
        let r = bounce(&[&["render", scene, "--width", "8", "--height", "8"][..], &args].concat());
        assert_eq!(r.code, 2, "{named}: exit {} stderr {}", r.code, r.stderr);
        let errs = error_lines(&r);
        assert!(errs.len() == 1 && errs[0].contains(named), "{}", r.stderr);
        assert!(!Path::new(out).exists(), "{named}: an output file was written");
        assert!(std::fs::read_dir(&frames).unwrap().count() == 1, "{named}: a frame was written");
        assert!(std::fs::read_to_string(scene).unwrap().contains("[camera]"), "{named}: the scene was overwritten");
    }
    // A missing argument is named on the one line (clap lists it below its first line).
    let nowhere = d.join("nowhere");
    expect_bad_input(&["bench", scene], "--out <OUT>", &nowhere);
    // suite measures every method against uniform: uniform alone is nothing to compare.
    let suite = ["suite", scene, "--out", nowhere.to_str().unwrap(), "--methods", "uniform"];
    expect_bad_input(&suite, "another method", &nowhere);
}

/// `bounce view` as its own process under Xvfb (`xvfb-run`, installed by scripts/setup.sh). One at a
/// time: `xvfb-run -a` picks a free display number by looking for lock files, which two runs starting
/// together can both pick.
fn view(args: &[&str], display: bool) -> std::process::Output {
    static XVFB: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = XVFB.lock().unwrap_or_else(|e| e.into_inner());
    let bin = env!("CARGO_BIN_EXE_bounce-cli");
    let mut cmd = if display {
        let mut c = std::process::Command::new("xvfb-run");
        c.args(["-a", "-s", "-screen 0 320x240x24", bin]);
        c
    } else {
        let mut c = std::process::Command::new(bin);
        c.env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").env_remove("WAYLAND_SOCKET");
        c
    };
    cmd.arg("view").args(args).output().expect("run xvfb-run (package xvfb) and the bounce binary")
}

const VIEW_SETTINGS: [&str; 12] =
    ["--width", "32", "--height", "32", "--vpls", "4", "--dprsm-res", "32", "--voxels", "32", "--method", "gbg"];

/// The viewer's progressive accumulation is exactly the mean of the frames `bounce render` makes with
/// the same settings, seeds S, S+1, … and one CDF seed S (given, so one VPL set): 3 frames of gbg,
/// validation on, under Xvfb.
#[test]
fn view_accumulates_exactly_the_frames_render_makes() {
    let d = scratch("view");
    let scene = bounce_tests::default_scene();
    let shot = d.join("view.png");
    let mut args = vec![scene.to_str().unwrap(), "--frames", "3", "--screenshot", shot.to_str().unwrap()];
    args.extend(VIEW_SETTINGS);
    args.extend(["--seed", "5", "--cdf-seed", "5", "--validation"]);
    let o = view(&args, true);
    assert!(o.status.success(), "bounce view failed: {}", String::from_utf8_lossy(&o.stderr));
    assert!(shot.exists());
    let (v, meta) = read_exr(&shot.with_extension("exr")).unwrap();
    assert!(meta.iter().any(|(k, val)| k == "bounce.frames" && val == "3"), "{meta:?}");
    let mut sum = vec![[0.0f64; 3]; v.pixels.len()];
    for seed in ["5", "6", "7"] {
        let exr = d.join(format!("render-{seed}.exr"));
        let mut a =
            vec!["render", scene.to_str().unwrap(), "--out", exr.to_str().unwrap(), "--seed", seed, "--cdf-seed", "5"];
        a.extend(VIEW_SETTINGS);
        let r = bounce(&a);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let (img, _) = read_exr(&exr).unwrap();
        assert_eq!((img.width, img.height), (v.width, v.height), "the window was not 32×32");
        for (s, p) in sum.iter_mut().zip(&img.pixels) {
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
        }
    }
    let mut worst = 0.0f64;
    for (s, p) in sum.iter().zip(&v.pixels) {
        for c in 0..3 {
            let want = s[c] / 3.0;
            worst = worst.max((p[c] as f64 - want).abs() / want.abs().max(1e-3));
        }
    }
    let mean = v.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * v.pixels.len()) as f64;
    eprintln!("view vs mean of 3 renders: worst relative difference {worst:.2e}, image mean {mean:.4}");
    assert!(mean > 0.01, "the screenshot is black");
    assert!(worst < 1e-5, "the viewer's mean differs from the renders': {worst}");
}

/// The bar: 30 frames under Xvfb exit 0 and the screenshot shows the scene, its image mean
/// within 5 % of the converged `all` image's (30 × 4 VPLs per pixel: the mean's noise is ~1 %).
#[test]
fn view_30_frames_under_xvfb_shows_the_scene() {
    let d = scratch("view30");
    let scene = bounce_tests::default_scene();
    let shot = d.join("s.png");
    let mut args = vec![scene.to_str().unwrap(), "--frames", "30", "--screenshot", shot.to_str().unwrap()];
    args.extend(VIEW_SETTINGS);
    let o = view(&args, true);
    assert!(o.status.success(), "bounce view failed: {}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("30 frames in the mean, 30 in all, 0 real-time; 1 copy to host memory"), "{stdout}");
    let (v, _) = read_exr(&shot.with_extension("exr")).unwrap();
    let all_exr = d.join("all.exr");
    let mut a = vec!["render", scene.to_str().unwrap(), "--out", all_exr.to_str().unwrap()];
    a.extend(VIEW_SETTINGS[..10].iter().copied());
    a.extend(["--method", "all"]);
    let r = bounce(&a);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let (all, _) = read_exr(&all_exr).unwrap();
    let mean = |px: &[[f32; 3]]| px.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * px.len()) as f64;
    let (mv, ma) = (mean(&v.pixels), mean(&all.pixels));
    eprintln!("view, 30 frames: mean {mv:.4} vs all {ma:.4} ({:+.2}%)", 100.0 * (mv - ma) / ma);
    assert!(((mv - ma) / ma).abs() < 0.05, "{mv} vs {ma}");
    assert!(std::fs::metadata(&shot).unwrap().len() > 100, "no PNG screenshot");
}

/// Without --method the viewer renders `realtime` frames (denoised, shown alone) while the camera moves
/// and accumulates ris while nothing does: along a camera orbit every frame after the first (the scene's
/// own view) is real-time; a still view accumulates all of its frames.
#[test]
fn view_is_real_time_while_the_camera_moves() {
    let d = scratch("view-realtime");
    let scene = bounce_tests::default_scene();
    let shot = d.join("s.png");
    let small = ["--width", "32", "--height", "32", "--dprsm-res", "32", "--vpls", "2"];
    // A walk that stops after frame 2: the still frame after it carries the last real-time frame.
    let stop = d.join("stop.toml");
    std::fs::write(
        &stop,
        "[[key]]\nframe = 0\neye = [0, 1, 3.9]\ntarget = [0, 1, 0]\n\n[[key]]\nframe = 2\neye = [0.2, 1, 3.8]\ntarget = [0, 1, 0]\n",
    )
    .unwrap();
    for (path, want) in [
        (Some("orbit:8"), "1 frame in the mean, 4 in all, 3 real-time"),
        (None, "4 frames in the mean, 4 in all, 0 real-time"),
        (stop.to_str(), "1 frame in the mean with the last real-time frame, 4 in all, 2 real-time"),
    ] {
        let mut args = vec![scene.to_str().unwrap(), "--frames", "4", "--screenshot", shot.to_str().unwrap()];
        args.extend(small);
        args.push("--validation");
        if let Some(p) = path {
            args.extend(["--camera-path", p]);
        }
        let o = view(&args, true);
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "bounce view failed: {}", String::from_utf8_lossy(&o.stderr));
        assert!(stdout.contains(want), "{path:?}: {stdout}");
    }
}

/// The bar for a moving light: `view --light-path orbit --frames 30` under Xvfb exits 0, its
/// screenshot is exactly frame 29 of `render --frames 30 --light-path orbit` (same seed: `coherent`
/// gives every frame of a moving light the seed S, and the viewer's mean after a light move is that
/// one frame), it differs from the static light's frame with the same seed, and the whole run copied
/// to host memory once (the screenshot's mean).
#[test]
fn view_orbits_the_light_and_reads_back_only_the_screenshot() {
    let d = scratch("view-orbit");
    let scene = bounce_tests::default_scene();
    let shot = d.join("s.png");
    let mut args = vec![scene.to_str().unwrap(), "--light-path", "orbit", "--frames", "30"];
    args.extend(["--screenshot", shot.to_str().unwrap(), "--seed", "5", "--validation"]);
    args.extend(VIEW_SETTINGS);
    let o = view(&args, true);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "bounce view failed: {}", String::from_utf8_lossy(&o.stderr));
    assert!(stdout.contains("1 frame in the mean, 30 in all, 0 real-time; 1 copy to host memory"), "{stdout}");
    let (v, _) = read_exr(&shot.with_extension("exr")).unwrap();
    let frames = d.join("frames");
    let mut a = vec!["render", scene.to_str().unwrap(), "--frames", "30", "--out-dir", frames.to_str().unwrap()];
    a.extend(["--light-path", "orbit", "--seed", "5", "--cdf-seed", "5"]);
    a.extend(VIEW_SETTINGS);
    let r = bounce(&a);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let (rendered, meta) = read_exr(&frames.join("frame_0029.exr")).unwrap();
    assert!(meta.iter().any(|(k, val)| k == "bounce.frame" && val == "29"), "{meta:?}");
    assert_eq!(v.pixels, rendered.pixels, "the viewer's orbit frame 29 is not render's");
    assert!(frames.join("frame_0000.png").exists() && frames.join("frame_0029.png").exists());
    let still = d.join("still.exr");
    let mut a = vec!["render", scene.to_str().unwrap(), "--out", still.to_str().unwrap(), "--seed", "5"];
    a.extend(["--cdf-seed", "5"]);
    a.extend(VIEW_SETTINGS);
    assert_eq!(bounce(&a).code, 0);
    let (still, _) = read_exr(&still).unwrap();
    let moved = bounce_tests::rel_mse(&v.pixels, &still.pixels);
    eprintln!("orbit frame 29 against the static light: relMSE {moved:.3e}");
    assert!(moved > 1e-3, "the light did not visibly move: relMSE {moved}");
}

/// Light paths that cannot run: one `error:` line naming the problem, exit 2, nothing written.
#[test]
fn bad_light_paths_are_exit_2() {
    let d = scratch("light-path");
    let scene = bounce_tests::default_scene();
    let out = d.join("frames");
    let keys = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let outside = keys("outside.toml", "[[key]]\nframe = 0\nlight = 0\nposition = [0, 100, 0]\n");
    let no_light = keys("nolight.toml", "[[key]]\nframe = 0\nlight = 3\nposition = [0, 1, 0]\n");
    let twice = keys(
        "twice.toml",
        "[[key]]\nframe = 2\nlight = 0\nposition = [0, 1, 0]\n[[key]]\nframe = 2\nlight = 0\nposition = [0, 1, 0]\n",
    );
    let typo = keys("typo.toml", "[[key]]\nframe = 0\nlight = 0\npositon = [0, 1, 0]\n");
    let dark = keys("dark.toml", "[[key]]\nframe = 0\nlight = 0\nposition = [0, 1, 0]\nintensity = [-1, 0, 0]\n");
    for (path, named) in [
        ("orbit:0", "orbit:PERIOD"),
        ("orbit:x", "orbit:PERIOD"),
        ("orbital", "neither"),
        (d.join("absent.toml").to_str().unwrap(), "absent.toml"),
        (&outside, "outside the scene's bounds"),
        (&no_light, "1 light"),
        (&twice, "second key"),
        (&typo, "typo.toml:4"),
        (&dark, "non-negative"),
    ] {
        let args = ["render", scene.to_str().unwrap(), "--frames", "2", "--out-dir", out.to_str().unwrap()];
        let mut args = args.to_vec();
        args.extend(["--light-path", path, "--width", "8", "--height", "8"]);
        expect_bad_input(&args, named, &out);
    }
    let o = d.join("o.exr");
    let lone = ["render", scene.to_str().unwrap(), "--light-path", "orbit", "--out", o.to_str().unwrap()];
    expect_bad_input(&lone, "need --frames", &o);
}

/// `render --frames N --timings` without --out-dir times the frames back to back and writes nothing (no
/// frame, not --out's default); without --timings it is the one-line error naming --out-dir; an --out
/// beside --frames is refused (an animation writes into --out-dir).
#[test]
fn frames_without_an_out_dir_are_only_timed() {
    let d = scratch("timed-frames");
    let scene = bounce_tests::default_scene();
    let default_out = Path::new("out.exr");
    let before = default_out.exists();
    let args = ["render", scene.to_str().unwrap(), "--frames", "3", "--light-path", "orbit"];
    let mut timed = args.to_vec();
    timed.extend(["--width", "8", "--height", "8", "--vpls", "2", "--validation", "--timings"]);
    let r = bounce(&timed);
    assert_eq!(r.code, 0, "stderr: {}", r.stderr);
    assert!(r.stdout.contains("median over frames 1..3"), "{}", r.stdout);
    assert!(r.stdout.lines().any(|l| l.starts_with("total")), "{}", r.stdout);
    assert!(r.stderr.contains("not written"), "{}", r.stderr);
    assert!(before || !default_out.exists(), "--out's default was written");
    let o = d.join("o.exr");
    expect_bad_input(&args, "--out-dir", &o);
    let mut with_out = args.to_vec();
    with_out.extend(["--timings", "--out", o.to_str().unwrap()]);
    expect_bad_input(&with_out, "--out", &o);
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "nothing may be written");
}

/// A moving camera (`--camera-path`): `render --frames 3 --camera-path orbit:8` starts at the scene's own
/// view (frame 0 is `render`'s image without a path, bit for bit) and moves (frames 1 and 2 differ from
/// it); a keyframe file holding the scene's view renders that view; `bench --animate none --camera-path`
/// measures each frame against its own ground truth, and with a light path too. Bad paths: exit 2.
#[test]
fn camera_paths_move_the_camera_frame_by_frame() {
    let d = scratch("camera-path");
    let scene = bounce_tests::default_scene();
    let size = ["--width", "12", "--height", "12", "--dprsm-res", "16"];
    let common = ["--component", "indirect", "--method", "uniform", "--vpls", "4", "--seed", "3"];
    let frames = d.join("frames");
    let mut a = vec!["render", scene.to_str().unwrap(), "--frames", "3", "--out-dir", frames.to_str().unwrap()];
    a.extend(["--camera-path", "orbit:8"]);
    a.extend(common);
    a.extend(size);
    let r = bounce(&a);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let still = d.join("still.exr");
    let mut b = vec!["render", scene.to_str().unwrap(), "--out", still.to_str().unwrap()];
    b.extend(common);
    b.extend(size);
    assert_eq!(bounce(&b).code, 0);
    let frame = |k: u32| read_exr(&frames.join(format!("frame_{k:04}.exr"))).unwrap().0.pixels;
    let still = read_exr(&still).unwrap().0.pixels;
    assert!(frame(0) == still, "frame 0 is not the scene's own view");
    assert!(frame(1) != still && frame(2) != frame(1), "the camera did not move");
    // Keys that hold the scene's view (the Cornell box's camera) render it at every frame (a keyframe
    // file whose name begins with "orbit" is a file, not an orbit).
    let keys = d.join("orbit-keys.toml");
    let key = |f: u32| format!("[[key]]\nframe = {f}\neye = [0.0, 1.0, 3.9]\ntarget = [0.0, 1.0, 0.0]\n");
    std::fs::write(&keys, key(0) + &key(5)).unwrap();
    let held = d.join("held");
    let mut c = vec!["render", scene.to_str().unwrap(), "--frames", "2", "--out-dir", held.to_str().unwrap()];
    c.extend(["--camera-path", keys.to_str().unwrap()]);
    c.extend(common);
    c.extend(size);
    assert_eq!(bounce(&c).code, 0);
    for k in 0..2 {
        let held_k = read_exr(&held.join(format!("frame_{k:04}.exr"))).unwrap().0.pixels;
        assert!(held_k == still, "frame {k} left the keys' view (an interpolation that moves a held point)");
    }
    // bench: the camera alone, then camera and lights.
    for lights in ["none", "orbit:8"] {
        let out = d.join(format!("bench-{lights}").replace(':', "-"));
        let mut e = vec!["bench", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--animate", lights];
        e.extend(["--camera-path", "orbit:6", "--frames", "3", "--methods", "uniform", "--vpls", "4"]);
        e.extend(["--temporal", "coherent", "--reference-spp", "8", "--validation"]);
        e.extend(size);
        let r = bounce(&e);
        assert_eq!(r.code, 0, "{}", r.stderr);
        let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
        assert_eq!(csv.lines().count(), 1 + 3 + 1, "three frames and a mean row:\n{csv}");
        assert!(std::fs::read_to_string(out.join("bench.md")).unwrap().contains("camera orbit:6"));
    }
    // Bad camera paths.
    let bad = |name: &str, text: &str| {
        let p = d.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let on_target = bad("on.toml", "[[key]]\nframe = 0\neye = [0, 1, 0]\ntarget = [0, 1, 0]\n");
    let wide = bad("wide.toml", "[[key]]\nframe = 0\neye = [0, 1, 3]\ntarget = [0, 1, 0]\nfov_y = 180\n");
    let typo = bad("typo.toml", "[[key]]\nframe = 0\neye = [0, 1, 3]\ntraget = [0, 1, 0]\n");
    // Straight down along the scene's up: no view (black frames, exit 0, before it was checked).
    let down = bad("down.toml", "[[key]]\nframe = 0\neye = [0, 1.5, 0]\ntarget = [0, 0, 0]\n");
    // Eye and target trade places over four frames: at frame 2 they coincide.
    let swap = "[[key]]\nframe = 0\neye = [0, 1, 3]\ntarget = [0, 1, 1]\n[[key]]\nframe = 4\neye = [0, 1, 1]\ntarget = [0, 1, 3]\n";
    let swap = bad("swap.toml", swap);
    let out = d.join("bad-frames");
    for (path, named) in [
        ("orbit:0", "orbit:PERIOD"),
        (on_target.as_str(), "away from its target"),
        (wide.as_str(), "fov_y"),
        (typo.as_str(), "typo.toml:4"),
        (down.as_str(), "parallel to the view direction"),
        (swap.as_str(), "between the keys at frames 0 and 4"),
    ] {
        let mut args = vec!["render", scene.to_str().unwrap(), "--frames", "2", "--out-dir", out.to_str().unwrap()];
        args.extend(["--camera-path", path, "--width", "8", "--height", "8"]);
        expect_bad_input(&args, named, &out);
    }
}

/// Without a display: exit 2, one `error:` line that says so, no screenshot.
#[test]
fn view_without_a_display_is_a_clear_error() {
    let d = scratch("view-nodisplay");
    let shot = d.join("s.png");
    let scene = bounce_tests::default_scene();
    let o = view(&[scene.to_str().unwrap(), "--frames", "1", "--screenshot", shot.to_str().unwrap()], false);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(errors[0].contains("no display"), "{stderr}");
    assert!(!shot.exists());
    // Where the screenshot goes is checked first, display or not: its folder, and a name that is not
    // the EXR it writes beside the PNG.
    for (bad, named) in [(d.join("nowhere/s.png"), "no directory"), (d.join("s.exr"), "--screenshot names the PNG")] {
        let o = view(&[scene.to_str().unwrap(), "--frames", "1", "--screenshot", bad.to_str().unwrap()], false);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
        assert!(errors.len() == 1 && errors[0].contains(named), "{stderr}");
    }
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "a file was left behind");
}

/// A textured scene renders its texture (the `SPEC_TEXTURED` shader variant is on for it): a floor
/// quad whose 2 × 1 texture is red on the left and green on the right, lit from above, renders red on
/// the left half of the image and green on the right.
#[test]
fn a_textured_scene_renders_its_texture() {
    let d = scratch("textured");
    // 2 × 1 RGBA: red, green.
    image::RgbaImage::from_raw(2, 1, vec![255, 0, 0, 255, 0, 255, 0, 255]).unwrap().save(d.join("t.png")).unwrap();
    std::fs::write(d.join("m.mtl"), "newmtl tex\nKd 1 1 1\nmap_Kd t.png\n").unwrap();
    std::fs::write(
        d.join("m.obj"),
        "mtllib m.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 1\nvt 1 1\nvt 1 0\nvt 0 0\nusemtl tex\nf 1/1 4/4 3/3 2/2\n",
    )
    .unwrap();
    std::fs::write(
        d.join("s.toml"),
        "mesh = \"m.obj\"\n[camera]\neye = [0.0, 3.0, 0.001]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nfov_y = 30.0\n[[light]]\nposition = [0.0, 2.0, 0.0]\nintensity = [4.0, 4.0, 4.0]\n",
    )
    .unwrap();
    let exr = d.join("t.exr");
    let r = bounce(&[
        "render",
        d.join("s.toml").to_str().unwrap(),
        "--out",
        exr.to_str().unwrap(),
        "--component",
        "direct",
        "--width",
        "16",
        "--height",
        "16",
        "--validation",
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let (img, _) = read_exr(&exr).unwrap();
    let (mut left, mut right) = ([0.0f64; 3], [0.0f64; 3]);
    for (k, p) in img.pixels.iter().enumerate() {
        let side = if k % 16 < 8 { &mut left } else { &mut right };
        for c in 0..3 {
            side[c] += p[c] as f64;
        }
    }
    eprintln!("textured floor: left {left:?}, right {right:?}");
    assert!(left[0] > 10.0 * left[1].max(1e-9) && left[2] == 0.0, "left half not red: {left:?}");
    assert!(right[1] > 10.0 * right[0].max(1e-9) && right[2] == 0.0, "right half not green: {right:?}");
}

/// `render --time-limit`: progressive frames until the budget, their count and the time in the EXR's
/// metadata; without --method the path tracer; `all` (the same every frame) renders one frame and says so; `bench --time-limits` writes one
/// row per method and budget with the frames it averaged.
#[test]
fn time_limits_render_progressive_frames_and_bench_at_equal_time() {
    let d = scratch("time-limit");
    let scene = bounce_tests::default_scene();
    let s = scene.to_str().unwrap();
    let out = d.join("t.exr");
    let small = ["--width", "16", "--height", "16", "--dprsm-res", "16", "--voxels", "16", "--component", "indirect"];
    let mut args = vec!["render", s, "--out", out.to_str().unwrap(), "--method", "gbg", "--vpls", "4"];
    args.extend(small);
    args.extend(["--time-limit", "1.5", "--validation"]);
    let r = bounce(&args);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let (_, meta) = read_exr(&out).unwrap();
    let get = |k: &str| meta.iter().find(|(m, _)| m == &format!("bounce.{k}")).map(|(_, v)| v.clone());
    let frames: u32 = get("frames").expect("frames in the metadata").parse().unwrap();
    let wall: f64 = get("wall_s").expect("wall_s in the metadata").parse().unwrap();
    assert!(frames >= 2, "1.5 s at 16² holds more than one frame: {frames}");
    assert!(wall <= 1.5 * 1.5, "the budget was overrun: {wall} s");
    assert_eq!(get("time_limit_s").as_deref(), Some("1.5"));

    // ris without --vpls picks its budget per frame from the view: candidates on the Cornell box, where
    // visibility blocks little; shadow rays in the two rooms, where it blocks nearly everything, and
    // there candidates from the gathered CDF.
    for (scene, budget, gathered) in [
        (scene.clone(), "2 reservoirs × 128", false),
        (bounce_tests::workspace().join("assets/two-rooms/scene.toml"), "2 reservoirs × 64", true),
    ] {
        let mut args = vec!["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "--method", "ris"];
        args.extend(small);
        args.extend(["--time-limit", "0.5"]);
        let r = bounce(&args);
        assert_eq!(r.code, 0, "{}", r.stderr);
        assert!(r.stderr.contains(&format!("ris per frame: {budget} candidates")), "{}", r.stderr);
        assert_eq!(r.stderr.contains("from the gathered CDF"), gathered, "{}", r.stderr);
    }

    // Without --method, a time-limited render is the path tracer's, TIME_LIMIT_SPP samples a frame, and
    // says so; --vpls alone asks for the VPL default (ris); an explicit --method and --spp stand.
    for (extra, method, spp) in [
        (&[][..], "reference", "8"),
        (&["--vpls", "2"][..], "ris", "256"),
        (&["--method", "reference", "--spp", "2"][..], "reference", "2"),
        (&["--method", "uniform", "--vpls", "2"][..], "uniform", "256"),
    ] {
        let mut args = vec!["render", s, "--out", out.to_str().unwrap()];
        args.extend(small);
        args.extend(extra);
        args.extend(["--time-limit", "0.3"]);
        let r = bounce(&args);
        assert_eq!(r.code, 0, "{}", r.stderr);
        assert_eq!(r.stderr.contains("method: reference (no --method or --vpls"), extra.is_empty(), "{}", r.stderr);
        let (_, meta) = read_exr(&out).unwrap();
        let get = |k: &str| meta.iter().find(|(m, _)| m == &format!("bounce.{k}")).map(|(_, v)| v.clone());
        assert_eq!(get("method").as_deref(), Some(method), "{extra:?}");
        assert_eq!(get("spp").as_deref(), Some(spp), "{extra:?}");
    }

    let all_out = d.join("all.exr");
    let mut all = vec!["render", s, "--out", all_out.to_str().unwrap(), "--method", "all"];
    all.extend(small);
    all.extend(["--time-limit", "1"]);
    let r = bounce(&all);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stderr.contains("1 frame(s)") && r.stderr.contains("note:"), "{}", r.stderr);

    let bench_dir = d.join("bench");
    let mut bench = vec!["bench", s, "--out", bench_dir.to_str().unwrap(), "--methods", "uniform,gbg"];
    bench.extend(["--vpls", "4", "--repeats", "1", "--time-limits", "0.3,0.6", "--reference", "all"]);
    bench.extend(["--width", "16", "--height", "16", "--dprsm-res", "16", "--voxels", "16"]);
    let r = bounce(&bench);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let csv = std::fs::read_to_string(bench_dir.join("bench.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let (t_col, f_col) = (
        header.iter().position(|h| *h == "time_limit_s").unwrap(),
        header.iter().position(|h| *h == "frames").unwrap(),
    );
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 2, "one row per method and budget:\n{csv}");
    for row in &rows {
        assert!(["0.3", "0.6"].contains(&row[t_col]), "{row:?}");
        assert!(row[f_col].parse::<u32>().unwrap() >= 1, "{row:?}");
    }
    let md = std::fs::read_to_string(bench_dir.join("bench.md")).unwrap();
    assert!(md.contains("0.3 s: frames") && md.contains("0.6 s: frames"), "{md}");

    // Budgets no `Duration` holds (bench panicked after its reference, before), and a budget with an
    // animation, whatever else is given.
    let huge = d.join("huge");
    let mut args = vec!["bench", s, "--out", huge.to_str().unwrap(), "--methods", "uniform", "--time-limits", "1e20"];
    args.extend(small);
    expect_bad_input(&args, "--time-limits", &huge.join("bench.csv"));
    let suite = d.join("suite");
    expect_bad_input(&["suite", s, "--out", suite.to_str().unwrap(), "--time-limit", "inf"], "--time-limit", &suite);
    let mut args = vec!["render", s, "--frames", "2", "--timings", "--time-limit", "1"];
    args.extend(small);
    expect_bad_input(&args, "--time-limit and --frames", &out.with_file_name("none"));
}

/// `docs/cli.md` is the command line's reference: every command's `--help` as clap prints it. It must
/// match the schema; `BOUNCE_UPDATE_DOCS=1 cargo test -p bounce-tests cli_reference` rewrites it.
#[test]
fn cli_reference_matches_the_help() {
    let path = bounce_tests::workspace().join("docs/cli.md");
    let want = bounce::cli_reference();
    if std::env::var_os("BOUNCE_UPDATE_DOCS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(have == want, "docs/cli.md differs from `bounce --help`: rerun with BOUNCE_UPDATE_DOCS=1");
    // And the render command's help lists at most 35 distinct flags (the product's, not the lab's).
    let render = want.split("\n## bounce render").nth(1).unwrap().split("\n## ").next().unwrap();
    let mut flags: Vec<&str> = render
        .lines()
        .filter_map(|l| l.trim_start().strip_prefix("--").map(|f| f.split([' ', '<', '=']).next().unwrap()))
        .collect();
    flags.sort_unstable();
    flags.dedup();
    assert!(flags.len() <= 35, "render has {} flags: {flags:?}", flags.len());
}

/// The generated suite (`scripts/make-scenes.py --suite`): at least forty scenes in ten families, every
/// one loading under the scene contract, from millimetre to kilometre scales and far from the origin,
/// each with its lights inside its bounds, and a light path (`light-path.toml`) that `bench --animate`
/// accepts and that keeps every light inside the scene's bounds; the same seed writes the same files. The
/// dark-room family's views are the kind a real-time frame learns visibility in: visibility blocks at
/// least `REALTIME_LEARN_BLOCKED` of their unshadowed transport (the other families' most blocked view
/// has 55 %).
#[test]
fn the_generated_suite_has_forty_loadable_scenes_of_every_scale() {
    let d = scratch("suite-scenes");
    let script = bounce_tests::workspace().join("scripts/make-scenes.py");
    let make = |dir: &Path| {
        let s = std::process::Command::new("python3").arg(&script).arg("--suite").arg(dir).output().unwrap();
        assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    };
    make(&d.join("a"));
    make(&d.join("b"));
    let mut names: Vec<String> = std::fs::read_dir(d.join("a"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert!(names.len() >= 40, "{} scenes", names.len());
    let families: std::collections::BTreeSet<&str> = names.iter().map(|n| n.rsplit_once('-').unwrap().0).collect();
    assert_eq!(families.len(), 10, "{families:?}");
    let (mut smallest, mut largest, mut farthest) = (f64::MAX, 0.0f64, 0.0f64);
    for n in &names {
        let path = d.join("a").join(n).join("scene.toml");
        let scene = bounce_graph::scene::Scene::load(&path).unwrap_or_else(|e| panic!("{n}: {e}"));
        let size = (scene.bounds_max - scene.bounds_min).length() as f64;
        smallest = smallest.min(size);
        largest = largest.max(size);
        farthest = farthest.max(scene.origin.length() / size);
        for l in &scene.lights {
            let p = glam::Vec3::from_slice(&l.position[..3]);
            assert!(p.cmpge(scene.bounds_min).all() && p.cmple(scene.bounds_max).all(), "{n}: a light outside");
        }
        // The path starts where the scene puts each light, and moves it (a keyframe outside the bounds is
        // refused by the parser).
        let keys = d.join("a").join(n).join("light-path.toml");
        let path = bounce::light_path::LightPath::parse(keys.to_str().unwrap(), &scene)
            .unwrap_or_else(|e| panic!("{n}: {e:#}"));
        let (start, later) = (path.at(0), path.at(10));
        for (i, l) in scene.lights.iter().enumerate() {
            let p = glam::Vec3::from_slice(&l.position[..3]);
            let size = (scene.bounds_max - scene.bounds_min).length();
            assert!((start[i].position - p).length() <= 1e-5 * size, "{n}: light {i} starts elsewhere");
            assert!((later[i].position - p).length() > 1e-3 * size, "{n}: light {i} does not move");
        }
        let again = std::fs::read(d.join("b").join(n).join(format!("{n}.obj"))).unwrap();
        assert!(again == std::fs::read(d.join("a").join(n).join(format!("{n}.obj"))).unwrap(), "{n} differs");
    }
    assert!(smallest < 0.1 && largest > 1000.0, "scales {smallest} .. {largest}");
    assert!(farthest > 100.0, "no scene far from the origin ({farthest} of its size)");
    let gpu = bounce_tests::TestGpu::new();
    let dark: Vec<&String> = names.iter().filter(|n| n.starts_with("dark-room-")).collect();
    assert!(dark.len() >= 5, "{} dark rooms", dark.len());
    for n in dark {
        let scene = bounce_graph::scene::Scene::load(&d.join("a").join(n).join("scene.toml")).unwrap();
        let mut r = bounce_graph::frame::Renderer::new(&gpu, &scene).unwrap();
        let b = r.blocked_share(64, 64).unwrap().unwrap_or_else(|| panic!("{n}: nothing lit in view"));
        assert!(b >= bounce_graph::frame::REALTIME_LEARN_BLOCKED, "{n}: blocked share {b}");
    }
}

/// `bounce suite`, tiny: two scenes (a file and a folder), two methods, two seeds at equal time. One row per scene, method and
/// seed; `uniform`'s ratios are 1; gbg's geometric mean in suite.md is the geometric mean over scenes of
/// the median over seeds of its relMSE over `uniform`'s, recomputed here from suite.csv.
#[test]
fn suite_runs_every_method_on_every_scene_and_aggregates() {
    let d = scratch("suite");
    let ws = bounce_tests::workspace();
    // A scene file, and a scene's folder (its scene.toml).
    let (cornell, doorway) = (ws.join("assets/cornell-box/scene.toml"), ws.join("assets/doorway"));
    let out = d.join("out");
    let r = bounce(&[
        "suite",
        cornell.to_str().unwrap(),
        doorway.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--methods",
        "uniform,gbg",
        "--seeds",
        "2",
        "--time-limit",
        "0.05",
        "--width",
        "16",
        "--height",
        "16",
        "--reference-spp",
        "16",
        "--dprsm-res",
        "16",
        "--validation",
    ]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let csv = std::fs::read_to_string(out.join("suite.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2 * 2 * 2, "{csv}");
    let median2 = |scene: &str, method: &str| -> f64 {
        let v: Vec<f64> =
            rows.iter().filter(|r| r[0] == scene && r[2] == method).map(|r| r[6].parse().unwrap()).collect();
        assert_eq!(v.len(), 2);
        0.5 * (v[0] + v[1])
    };
    let ratio = |scene| median2(scene, "gbg") / median2(scene, "uniform");
    let geomean = (ratio("cornell-box") * ratio("doorway")).sqrt();
    let md = std::fs::read_to_string(out.join("suite.md")).unwrap();
    let line = md.lines().find(|l| l.starts_with("| gbg |")).expect("gbg's aggregate row");
    let shown: f64 = line.split('|').nth(2).unwrap().trim().parse().unwrap();
    assert!((shown - geomean).abs() <= 5e-4 * geomean.max(1.0), "{shown} vs {geomean}\n{md}");
    assert!(md.lines().any(|l| l.starts_with("| uniform | 1.000 |")), "{md}");
    assert_eq!(&std::fs::read(out.join("suite.png")).unwrap()[1..4], b"PNG");
    // A suite without the baseline is one error line.
    let r = bounce(&["suite", cornell.to_str().unwrap(), "--out", out.to_str().unwrap(), "--methods", "gbg"]);
    assert_eq!((r.code, error_lines(&r).len()), (2, 1), "{}", r.stderr);
    // At equal count every row is one frame of --vpls VPLs; a time budget beside it is an error line.
    let counted = d.join("counted");
    let args = ["suite", cornell.to_str().unwrap(), "--out", counted.to_str().unwrap(), "--methods", "uniform,gbg"];
    let tiny = ["--seeds", "2", "--vpls", "4", "--width", "8", "--height", "8", "--reference-spp", "4"];
    let r = bounce(&[&args[..], &tiny[..], &["--dprsm-res", "16", "--equal-count", "--validation"]].concat());
    assert_eq!(r.code, 0, "{}", r.stderr);
    let csv = std::fs::read_to_string(counted.join("suite.csv")).unwrap();
    let frames: Vec<&str> = csv.lines().skip(1).map(|l| l.split(',').nth(4).unwrap()).collect();
    assert_eq!(frames, ["1"; 4], "{csv}");
    assert!(std::fs::read_to_string(counted.join("suite.md")).unwrap().contains("4 VPLs a pixel"));
    let r = bounce(&[&args[..], &["--equal-count", "--time-limit", "1"]].concat());
    assert_eq!((r.code, error_lines(&r).len()), (2, 1), "{}", r.stderr);
}

/// `bounce suite` measures ris as `render --time-limit` runs it: without --vpls, each scene's ris takes the
/// per-view budget `render` chooses for the same view (the same line on stderr: the open budget on the
/// Cornell box, the gathered source in the two rooms); with --vpls, --vpls reservoirs as every method. So
/// does `bench --time-limits`.
#[test]
fn the_suite_and_bench_run_ris_with_renders_budget() {
    let d = scratch("suite-ris");
    let ws = bounce_tests::workspace();
    let scenes = [ws.join("assets/cornell-box/scene.toml"), ws.join("assets/two-rooms/scene.toml")];
    let size = ["--width", "16", "--height", "16", "--dprsm-res", "16"];
    let budget = |stderr: &str| -> Vec<String> {
        stderr.lines().filter(|l| l.starts_with("ris per frame:")).map(String::from).collect()
    };
    let mut rendered = vec![];
    for scene in &scenes {
        let png = d.join("r.exr");
        let args = ["render", scene.to_str().unwrap(), "--method", "ris", "--time-limit", "0.05", "--out"];
        let r = bounce(&[&args[..], &[png.to_str().unwrap()], &size[..]].concat());
        assert_eq!(r.code, 0, "{}", r.stderr);
        rendered.extend(budget(&r.stderr));
    }
    assert_eq!(rendered.len(), 2, "{rendered:?}");
    assert!(rendered[0].contains("128 candidates") && rendered[1].contains("gathered CDF"), "{rendered:?}");
    let out = d.join("out");
    let args = ["suite", scenes[0].to_str().unwrap(), scenes[1].to_str().unwrap(), "--methods", "uniform,ris"];
    let tiny = ["--seeds", "1", "--time-limit", "0.05", "--reference-spp", "4", "--validation", "--out"];
    let r = bounce(&[&args[..], &tiny[..], &[out.to_str().unwrap()], &size[..]].concat());
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(budget(&r.stderr), rendered);
    assert!(std::fs::read_to_string(out.join("suite.md")).unwrap().contains("ris: its per-view budget"));
    let r = bounce(&[&args[..], &tiny[..], &[out.to_str().unwrap(), "--vpls", "4"], &size[..]].concat());
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(budget(&r.stderr).is_empty(), "{}", r.stderr);
    // `bench --time-limits` the same way.
    let args = ["bench", scenes[0].to_str().unwrap(), "--methods", "uniform,ris", "--time-limits", "0.05"];
    let tiny = ["--repeats", "1", "--reference-spp", "4", "--validation", "--out", out.to_str().unwrap()];
    let r = bounce(&[&args[..], &tiny[..], &size[..]].concat());
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(budget(&r.stderr), rendered[..1]);
    // bench.csv's ris rows name the VPLs the budget shaded (reservoirs × picks), not the column's.
    let words: Vec<&str> = rendered[0].split_whitespace().collect();
    let number_before = |w: &str| words[words.iter().position(|x| *x == w).unwrap() - 1].parse::<u32>().unwrap();
    let shaded = number_before("reservoirs") * number_before("picks");
    let ris_vpls = || -> Vec<u32> {
        let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
        csv.lines().filter(|l| l.starts_with("ris,")).map(|l| l.split(',').nth(1).unwrap().parse().unwrap()).collect()
    };
    assert_eq!(ris_vpls(), [shaded]);
    let r = bounce(&[&args[..], &tiny[..], &size[..], &["--vpls", "4"]].concat());
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(budget(&r.stderr).is_empty(), "{}", r.stderr);
    assert_eq!(ris_vpls(), [4]);
}
