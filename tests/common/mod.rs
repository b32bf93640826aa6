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

/// A CSV file of numbers (`history.csv`, `probes.csv`): its header and rows.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().expect("header").split(',').map(str::to_string).collect();
    let rows = lines.map(|l| l.split(',').map(|v| v.trim().parse::<f64>().expect("number")).collect()).collect();
    (header, rows)
}

/// Marks the processes [`on_ranks`] starts.
pub const RANK_CHILD: &str = "MPFEM_TEST_RANK_CHILD";

/// Run `work` on `ranks` real MPI processes of this test binary and return each process's
/// report (its line), in no particular order. The processes run the test `test` again (its
/// name, which must be unique in the binary); there this call runs `work` with MPI's world and
/// ends the process (a process whose `work` panics aborts them all, so that none waits for it).
/// `mpirun` is stopped after 300 s. Panics, with the processes' output, when `mpirun` fails or
/// a process gave no report.
pub fn on_ranks(ranks: usize, test: &str, work: fn(std::sync::Arc<dyn mpfem::parallel::Collective>) -> String) -> Vec<String> {
    if std::env::var_os(RANK_CHILD).is_some() {
        let comm = mpfem::parallel::launch();
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(comm.clone()))) {
            Ok(line) => println!("RANK REPORT {line}"),
            Err(_) => {
                comm.abort_all(101);
                std::process::exit(101);
            }
        }
        // (MPI finalises here)
        drop(comm);
        std::process::exit(0);
    }
    let exe = std::env::current_exe().expect("test binary");
    let out = Command::new("timeout")
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMPI_MCA_plm", "isolated")
        .env(RANK_CHILD, "1")
        .args(["300", "mpirun", "--oversubscribe", "--bind-to", "none", "-n", &ranks.to_string()])
        .arg(exe)
        .args(["--exact", test, "--nocapture", "--test-threads", "1"])
        .output()
        .expect("mpirun (scripts/setup.sh installs Open MPI)");
    let stdout = String::from_utf8_lossy(&out.stdout);
    // (libtest's own "test … " may precede a report on its line)
    let lines: Vec<String> = stdout.lines().filter_map(|l| l.find("RANK REPORT ").map(|i| l[i + 12..].to_string())).collect();
    assert!(out.status.success(), "mpirun -n {ranks}: {}\n{stdout}\n{}", out.status, String::from_utf8_lossy(&out.stderr));
    assert_eq!(lines.len(), ranks, "a report from every process:\n{stdout}");
    lines
}
