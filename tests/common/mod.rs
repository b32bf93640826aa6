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

/// `mpirun -n ranks mpfem` (the mpfem arguments follow): as root (CI containers) Open MPI
/// wants both variables; the "isolated" launcher starts local ranks without ssh (which a
/// container may lack: Open MPI's default launcher then refuses to start); more ranks than
/// cores need --oversubscribe; one thread per rank, not bound to a core.
pub fn mpirun(ranks: usize) -> Command {
    let mut c = Command::new("mpirun");
    c.env("OMPI_ALLOW_RUN_AS_ROOT", "1").env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1").env("OMPI_MCA_plm", "isolated");
    c.args(["--oversubscribe", "--bind-to", "none", "-n", &ranks.to_string(), env!("CARGO_BIN_EXE_mpfem")]);
    c
}

/// An empty scratch folder `mpfem-<test crate>-<process id>-<name>` in the system's temporary
/// folder (emptied when it exists). It stays after the test, to be looked at when the test
/// failed; the folders of the same test left by earlier runs (another process id that is no
/// longer running) are removed here, so that repeated runs (CI on one machine) do not fill
/// the temporary folder.
pub fn tmpdir(name: &str) -> PathBuf {
    let tmp = std::env::temp_dir();
    let prefix = format!("mpfem-{}-", env!("CARGO_CRATE_NAME"));
    let suffix = format!("-{name}");
    if let Ok(entries) = std::fs::read_dir(&tmp) {
        for e in entries.flatten() {
            let file = e.file_name();
            let Some(f) = file.to_str() else { continue };
            let Some(pid) = f.strip_prefix(&prefix).and_then(|r| r.strip_suffix(&suffix)).and_then(|p| p.parse::<u32>().ok()) else { continue };
            if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
    let d = tmp.join(format!("{prefix}{}{suffix}", std::process::id()));
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
