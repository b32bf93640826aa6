//! Helpers shared by the integration tests: a test crate that needs them declares `mod common;`
//! and uses the part it needs.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root (`jobs/`, `tests/data/`, `docs/`).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The `mpfem` binary of this build.
pub fn mpfem() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mpfem"))
}

/// An empty scratch folder `mpfem-<test crate>-<process id>-<name>` in the system's temporary
/// folder (emptied when it exists).
pub fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mpfem-{}-{}-{name}", env!("CARGO_CRATE_NAME"), std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes `case` to `dir/case.toml` and runs `mpfem run --quiet --out dir/out` on it, which must
/// succeed; returns the output folder.
pub fn run_quiet(dir: &Path, case: &str) -> PathBuf {
    let path = dir.join("case.toml");
    std::fs::write(&path, case).unwrap();
    let out = dir.join("out");
    let st = mpfem().args(["run", "--quiet", "--out"]).arg(&out).arg(&path).status().unwrap();
    assert!(st.success(), "mpfem run {} failed", path.display());
    out
}
