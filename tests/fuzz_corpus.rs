//! The kept fuzz corpus of the WKB reader (fuzz/corpus/wkb/: hand-made cases and every crash
//! fuzzing found, fixed since) through the fuzz target's own checks, so that each run of the
//! tests keeps them fixed without cargo-fuzz or a sanitizer build; scripts/fuzz.sh searches for
//! new ones.

#[path = "../fuzz/checks/wkb.rs"]
mod checks;

#[test]
fn every_kept_wkb_input_ends_in_a_map_or_an_error() {
    let corpus = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/wkb");
    let mut files: Vec<_> = std::fs::read_dir(&corpus)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .collect();
    files.sort();
    // The hand-made cases and the two crashes of 2026-12-01 at least.
    assert!(
        files.len() >= 13,
        "{} files in {}",
        files.len(),
        corpus.display()
    );
    for file in files {
        eprintln!("{}", file.display());
        checks::check(&std::fs::read(&file).unwrap());
    }
}
