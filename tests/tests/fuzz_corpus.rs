//! Replays the scene fuzzer's corpus (`tests/fuzz/corpus/scene`) and every input it ever crashed on
//! (`tests/fuzz/regressions`) through the same contract check the fuzz target runs
//! (`bounce_oracles::scene_fuzz::check_load`), on the stable toolchain: what the fuzzer found stays fixed.
//! The seeds that are well-formed must load and the broken ones must not, so the check is not vacuous.

use bounce_oracles::scene_fuzz::check_load;
use std::path::PathBuf;

fn inputs(sub: &str) -> Vec<PathBuf> {
    let dir = bounce_tests::workspace().join("tests/fuzz").join(sub);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_file() && p.file_name().is_some_and(|n| n != ".gitkeep"))
        .collect();
    v.sort();
    v
}

#[test]
fn the_fuzz_corpus_and_regressions_keep_the_loader_contract() {
    let root = std::env::temp_dir().join(format!("bounce-fuzz-replay-{}", std::process::id()));
    let (mut loaded, mut rejected) = (vec![], vec![]);
    let corpus = inputs("corpus/scene");
    assert!(corpus.len() >= 8, "the seed corpus is missing");
    for (k, path) in corpus.iter().chain(inputs("regressions").iter()).enumerate() {
        let data = std::fs::read(path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        // A panic inside names the input.
        let ok = std::panic::catch_unwind(|| check_load(&data, &root.join(k.to_string())))
            .unwrap_or_else(|_| panic!("{}: the loader broke its contract", path.display()));
        if ok {
            loaded.push(name)
        } else {
            rejected.push(name)
        }
    }
    let _ = std::fs::remove_dir_all(&root);
    eprintln!("fuzz corpus: {} loaded, {} rejected with a one-line error", loaded.len(), rejected.len());
    for seed in ["cornell-fixed", "cornell-toml", "textured-quad", "textured-quad-fixed", "two-lights-render"] {
        assert!(loaded.iter().any(|n| n == seed), "seed {seed} must load");
    }
    for seed in ["nan-vertex", "negative-index", "missing-texture"] {
        assert!(rejected.iter().any(|n| n == seed), "seed {seed} must be rejected");
    }
}
