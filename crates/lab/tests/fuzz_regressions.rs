//! The fuzz targets' inputs kept in `fuzz/regressions/<target>/` — a few
//! seeds per reader, and every input a fuzzer found to fail, once fixed —
//! replayed on stable through the same code the fuzz targets run
//! (`fuzz/src/harness.rs`): each must give `Ok` or an error, never a panic
//! (see `fuzz/README.md`).

#[path = "../../../fuzz/src/harness.rs"]
mod harness;

use std::path::Path;

#[test]
fn every_kept_fuzz_input_reads_without_panicking() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/regressions");
    let mut failures = Vec::new();
    for &(target, run) in harness::TARGETS {
        let dir = root.join(target);
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        assert!(!files.is_empty(), "{target}: no input kept in {}", dir.display());
        for file in files {
            let data = std::fs::read(&file).unwrap();
            if std::panic::catch_unwind(|| run(&data)).is_err() {
                failures.push(format!("{target}: {}", file.display()));
            }
        }
    }
    assert!(failures.is_empty(), "panicked on:\n{}", failures.join("\n"));
}

#[test]
fn every_fuzz_target_has_a_folder_of_inputs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    for &(target, _) in harness::TARGETS {
        assert!(
            root.join("fuzz_targets").join(format!("{target}.rs")).is_file(),
            "{target}"
        );
        assert!(root.join("regressions").join(target).is_dir(), "{target}");
    }
    let binaries = std::fs::read_dir(root.join("fuzz_targets")).unwrap().count();
    assert_eq!(
        binaries,
        harness::TARGETS.len(),
        "a target without a harness entry"
    );
}
