//! The CI fuzz run (issue 16): a fixed-seed batch of mutants of every scene under garments/
//! (and of the OBJ mesh beside the torso scene) through `plyshell check`, and a sample of
//! the small benchmark scenes through `plyshell solve`, each in a subprocess under a 4 GiB
//! address-space cap (`ulimit -v`), a 1 GiB `--max-memory` budget and a timeout. Any panic,
//! abort, hang or non-finite solve output fails the test; the counts by outcome are printed
//! (`cargo test --release --test fuzz -- --nocapture`). Longer local runs:
//! `plyshell fuzz --count 100000 --seed N`.

use std::path::PathBuf;
use std::time::Duration;

use plyshell::fuzz::{self, FuzzConfig, Outcome};

#[test]
fn mutants_of_the_shipped_scenes_never_crash_hang_or_write_nan() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let cfg = FuzzConfig {
        exe: PathBuf::from(env!("CARGO_BIN_EXE_plyshell")),
        corpus: fuzz::corpus(&root.join("garments")),
        seed: 16,
        count: 3000,
        solve_every: 5,
        solve_scenes: fuzz::SOLVE_SCENES.iter().map(|s| s.to_string()).collect(),
        check_timeout: Duration::from_secs(20),
        solve_timeout: Duration::from_secs(30),
        memory_cap: 4 << 30,
        budget: 1 << 30,
        jobs: 2,
        work: PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fuzz-ci"),
    };
    assert!(cfg.corpus.len() >= 20, "corpus: {:?}", cfg.corpus);
    let report = fuzz::run(&cfg).expect("fuzz run");
    println!("{report}");
    assert!(report.failures.is_empty(), "{report}");
    let checked: usize = report.check.values().sum();
    assert_eq!(checked, cfg.count);
    // The mutants exercise both paths: many are rejected with a position, some still pass.
    let located = report.check.get(&Outcome::ErrorLocated).copied().unwrap_or(0);
    assert!(located > checked / 2 && report.check.get(&Outcome::Ok).copied().unwrap_or(0) > checked / 20, "{report}");
    assert!(report.solve.values().sum::<usize>() >= 5, "{report}");
}
