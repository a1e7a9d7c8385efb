//! Compiles every shader of the [`SHADERS`] table to SPIR-V with shaderc (glslang) into OUT_DIR, and writes
//! `shaders.rs` (one `pub const` of SPIR-V bytes per table row). A GLSL error fails `cargo build` with
//! file:line. (The numbers of `glsl/shared/bindings.glsl` become Rust constants in the scene crate's
//! build script, which needs no shaderc.)
//!
//! **Names.** A row's name is the source's file name, or, for a variant, `<stem>.<variant>.<stage>` where
//! the source is `<stem>.<stage>`: a dot before the stage extension means "variant of that stem" and
//! nothing else (build.rs checks it). The Rust constant is the name upper-cased with dots as underscores
//! (`gather.exact.comp` → `GATHER_EXACT_COMP`). Every `*.{vert,geom,frag,comp}` under `glsl/` and
//! `glsl/test/` must be the source of a row, so no file is silently left uncompiled.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One compiled shader: its name (see the module doc; a folder before it is dropped), its source file under
/// `glsl/`, and the macros defined for it, in this order (Granite's `register_variant`).
struct Shader {
    name: &'static str,
    source: &'static str,
    defines: &'static [&'static str],
}

impl Shader {
    /// The name without its folder (`test/layout_echo.comp` → `layout_echo.comp`).
    fn name(&self) -> &'static str {
        self.name.rsplit('/').next().unwrap()
    }
}

/// A shader compiled from `source` as it is.
const fn file(source: &'static str) -> Shader {
    Shader { name: source, source, defines: &[] }
}

/// `name`, a variant of `source` with `defines`.
const fn variant(name: &'static str, source: &'static str, defines: &'static [&'static str]) -> Shader {
    Shader { name, source, defines }
}

/// Every shader bounce compiles, grouped by pass.
const SHADERS: &[Shader] = &[
    file("gbuffer.vert"),
    file("gbuffer.frag"),
    // The reflective light maps, whose texels are the VPLs: one ray from the light per texel.
    file("dprsm.comp"),
    file("direct.comp"),
    file("voxelize.comp"),
    file("importance.comp"),
    file("importance_gbg.comp"),
    variant("importance_gbg.exact.comp", "importance_gbg.comp", &["EXACT_VISIBILITY"]),
    file("cdf_reduce.comp"),
    // psm: the shared VPL set (psm.comp) and its paraboloid shadow maps, rasterized (psm.vert, psm.geom: the
    // triangle's exact box on the VPL's face; psm.frag: each texel's exact depth).
    file("psm.comp"),
    file("psm.vert"),
    file("psm.geom"),
    file("psm.frag"),
    // gather and mis, each in one variant per `--visibility`: the voxel march, `exact` (shadow rays against
    // the BVH) and `psm` (the frame's shared VPL set and its shadow maps).
    // end_balls: each exact shadow ray's ends' empty balls, per pixel and (END_BALLS_VPLS) per VPL.
    file("end_balls.comp"),
    variant("end_balls.vpls.comp", "end_balls.comp", &["END_BALLS_VPLS"]),
    file("gather.comp"),
    variant("gather.exact.comp", "gather.comp", &["EXACT_VISIBILITY"]),
    variant("gather.psm.comp", "gather.comp", &["PSM_VISIBILITY"]),
    file("mis.comp"),
    variant("mis.exact.comp", "mis.comp", &["EXACT_VISIBILITY"]),
    variant("mis.psm.comp", "mis.comp", &["PSM_VISIBILITY"]),
    // ris: one file per stage (shared/ris.glsl is their common part). The initial stage draws its own
    // candidates, or takes them from the pool (RIS_POOL), optionally with the learned visibility
    // (RIS_LEARNED): the variants that bind something of their own; the rest are specialisations.
    file("ris_presample.comp"),
    file("ris_initial.comp"),
    variant("ris_initial.pool.comp", "ris_initial.comp", &["RIS_POOL"]),
    variant("ris_initial.pool_learned.comp", "ris_initial.comp", &["RIS_POOL", "RIS_LEARNED"]),
    file("ris_temporal.comp"),
    file("ris_spatial.comp"),
    file("ris_shade.comp"),
    variant("ris_shade.exact.comp", "ris_shade.comp", &["EXACT_VISIBILITY"]),
    file("reproject.comp"),
    file("denoise_temporal.comp"),
    file("denoise_variance.comp"),
    file("denoise_atrous.comp"),
    // The reference: two-strategy MIS (cosine at x, light side at y).
    file("reference.comp"),
    // The viewer's presentation: running mean, Reinhard, sRGB8.
    file("present.comp"),
    // Kernels used only by the tests.
    file("test/bvh_trace.comp"),
    file("test/cdf_sample.comp"),
    file("test/front_part.comp"),
    file("test/layout_echo.comp"),
    file("test/map_depth.comp"),
    file("test/owen_sobol.comp"),
    file("test/region_weights.comp"),
    file("test/shadow_queue.comp"),
    file("test/unit_normals.comp"),
    file("test/voxel_march.comp"),
    file("test/voxel_rcp.comp"),
];

/// `glsl/` from this package's root.
const GLSL_FROM_PACKAGE: &str = "../../glsl";

fn main() {
    // The manifest dir at run time, not env!() at the script's compile time: a build cache shared by
    // two checkouts may reuse a build script compiled for the other one.
    let manifest = std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR");
    let glsl = Path::new(&manifest).join(GLSL_FROM_PACKAGE).canonicalize().expect("glsl/ exists");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    // Inputs are registered relative to the package root, where cargo resolves them: an absolute path
    // would be the first checkout's, and a second one sharing the build cache would never see its own
    // shaders change.
    println!("cargo:rerun-if-changed={GLSL_FROM_PACKAGE}");
    check_table(&glsl);
    compile_all(&glsl, &out);
}

/// Panics unless every row follows the naming rule (module doc), names are unique, and every stage file
/// under `glsl/` and `glsl/test/` is some row's source. Also registers every GLSL file for reruns.
fn check_table(glsl: &Path) {
    let mut names = std::collections::HashSet::new();
    for s in SHADERS {
        assert!(names.insert(s.name()), "SHADERS: `{}` twice", s.name);
        let file = s.source.rsplit('/').next().unwrap();
        let (stem, stage) = file.split_once('.').expect("a source has a stage extension");
        let plain = s.name == s.source && s.defines.is_empty() && !stage.contains('.');
        let variant = s.name().strip_prefix(&format!("{stem}.")).and_then(|r| r.strip_suffix(&format!(".{stage}")));
        let variant_ok = variant.is_some_and(|v| !v.is_empty() && !v.contains('.'));
        assert!(
            plain || (variant_ok && !s.defines.is_empty()),
            "SHADERS: `{}` from `{}`: a dot in a name means `<stem>.<variant>.<stage>` of `<stem>.<stage>`",
            s.name,
            s.source
        );
    }
    for dir in [glsl.to_path_buf(), glsl.join("test"), glsl.join("shared")] {
        for e in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())).flatten() {
            let p = e.path();
            let rel = p.strip_prefix(glsl).unwrap().to_str().unwrap().replace('\\', "/");
            println!("cargo:rerun-if-changed={GLSL_FROM_PACKAGE}/{rel}");
            if matches!(p.extension().and_then(|x| x.to_str()), Some("vert" | "geom" | "frag" | "comp")) {
                assert!(SHADERS.iter().any(|s| s.source == rel), "glsl/{rel} is in no row of build.rs's SHADERS");
            }
        }
    }
}

/// Compiles every row into `out/<name>.spv` and writes `out/shaders.rs`; panics with every error.
fn compile_all(glsl: &Path, out: &Path) {
    let compiler = shaderc::Compiler::new().expect("shaderc compiler");
    let mut options = shaderc::CompileOptions::new().expect("shaderc options");
    options.set_target_env(shaderc::TargetEnv::Vulkan, shaderc::EnvVersion::Vulkan1_3 as u32);
    options.set_source_language(shaderc::SourceLanguage::GLSL);
    // Optimised SPIR-V in every profile: the tests and the benchmark run the same code as a release
    // build, and lavapipe's loop iteration limit sees the loops spirv-opt leaves.
    options.set_optimization_level(shaderc::OptimizationLevel::Performance);
    if std::env::var("PROFILE").as_deref() != Ok("release") {
        options.set_generate_debug_info();
    }
    let root = glsl.to_path_buf();
    options.set_include_callback(move |name, _ty, from, _depth| {
        let base = Path::new(from).parent().unwrap_or(&root).to_path_buf();
        let candidates = [base.join(name), root.join(name)];
        for c in candidates {
            if let Ok(content) = std::fs::read_to_string(&c) {
                return Ok(shaderc::ResolvedInclude { resolved_name: c.display().to_string(), content });
            }
        }
        Err(format!("cannot find include `{name}` (from {from})"))
    });

    let mut rs = String::from("// Generated by build.rs from its SHADERS table: SPIR-V per shader.\n");
    let mut errors = vec![];
    for s in SHADERS {
        let kind = match s.source.rsplit('.').next().unwrap() {
            "vert" => shaderc::ShaderKind::Vertex,
            "geom" => shaderc::ShaderKind::Geometry,
            "frag" => shaderc::ShaderKind::Fragment,
            _ => shaderc::ShaderKind::Compute,
        };
        let path = glsl.join(s.source);
        let src = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut opts = options.clone();
        for m in s.defines {
            opts.add_macro_definition(m, None);
        }
        match compiler.compile_into_spirv(&src, kind, &path.display().to_string(), "main", Some(&opts)) {
            Ok(a) => {
                let spv = out.join(format!("{}.spv", s.name()));
                std::fs::write(&spv, a.as_binary_u8()).unwrap();
                let what = match s.defines {
                    [] => format!("`glsl/{}`", s.source),
                    d => format!("`glsl/{}` with {}", s.source, d.join(", ")),
                };
                let konst = s.name().replace('.', "_").to_uppercase();
                writeln!(
                    rs,
                    "/// SPIR-V of {what}.\npub const {konst}: &[u8] = include_bytes!({:?});",
                    spv.display().to_string()
                )
                .unwrap();
            }
            Err(e) => errors.push(format!("{}: {e}", s.name)),
        }
    }
    if !errors.is_empty() {
        for e in &errors {
            for line in e.lines() {
                println!("cargo:warning={line}");
            }
        }
        panic!("GLSL compilation failed:\n{}", errors.join("\n"));
    }
    std::fs::write(out.join("shaders.rs"), rs).unwrap();
}
