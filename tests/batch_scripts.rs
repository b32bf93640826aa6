//! The batch templates in `jobs/batch/` run for real, outside a batch system: `slurm.sbatch`
//! and `pbs.sh` with `LAUNCH=""` (mpfem started directly instead of by srun/mpirun) and
//! `REQUEUE` pointing at a script that records the requeue, `run_local.sh` as it is. Checked:
//! a SIGTERM to the batch script (what Slurm's `--signal=B:TERM@300` and PBS's pre-emption
//! send) reaches mpfem, which writes its checkpoint and exits 3; the script then requeues the
//! job (with its job id) and exits 3; the requeued script finds the checkpoint, passes
//! `--restart`, and the finished history equals an uninterrupted run's bit for bit (every
//! column of every row, exact string equality).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::{root, tmpdir};

/// The 2 × 2 biaxial disc job with friction (48 steps, a few seconds in debug).
fn case_in(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(root().join("jobs/compaction/discs_2x2_biaxial_mu02.toml")).unwrap();
    let path = dir.join("case.toml");
    std::fs::write(&path, format!("{text}\n[output]\ncheckpoint_every = 0\ncheckpoint_minutes = 0\n")).unwrap();
    path
}

fn rows(out: &Path) -> usize {
    std::fs::read_to_string(out.join("history.csv")).map_or(0, |t| t.lines().count().saturating_sub(1))
}

/// Run `script` in `dir` with `env`, send it SIGTERM once `out` has 4 history rows, and return
/// its exit code and its output.
fn interrupted(script: &str, args: &[&str], dir: &Path, out: &Path, env: &[(&str, String)]) -> (Option<i32>, String) {
    let log_path = dir.join(format!("{}.log", script.replace('/', "_")));
    let log = std::fs::File::create(&log_path).unwrap();
    let mut cmd = Command::new("bash");
    cmd.arg(root().join(script)).args(args).current_dir(dir).stdout(Stdio::from(log.try_clone().unwrap())).stderr(Stdio::from(log));
    for (k, v) in env {
        cmd.env(k, v);
    }
    let mut child = cmd.spawn().unwrap();
    let t0 = Instant::now();
    while rows(out) < 4 {
        assert!(child.try_wait().unwrap().is_none(), "{script} ended before the signal: {}", std::fs::read_to_string(&log_path).unwrap());
        assert!(t0.elapsed() < Duration::from_secs(120), "no history rows after 120 s");
        std::thread::sleep(Duration::from_millis(20));
    }
    // SAFETY: sending a signal to our own child process (the batch script)
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) }, 0);
    let status = child.wait().unwrap();
    (status.code(), std::fs::read_to_string(&log_path).unwrap())
}

fn finish(script: &str, args: &[&str], dir: &Path, env: &[(&str, String)]) -> String {
    let mut cmd = Command::new("bash");
    cmd.arg(root().join(script)).args(args).current_dir(dir);
    for (k, v) in env {
        cmd.env(k, v);
    }
    let o = cmd.output().unwrap();
    let text = format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{script} after the requeue: {text}");
    text
}

#[test]
fn batch_templates_checkpoint_requeue_and_continue() {
    let dir = tmpdir("templates");
    let case = case_in(&dir);
    let mpfem = env!("CARGO_BIN_EXE_mpfem").to_string();
    // the reference: one uninterrupted run
    let reference = dir.join("reference");
    let o = Command::new(&mpfem).args(["run", "--no-plots", "-q"]).arg(&case).arg("--out").arg(&reference).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let expected = std::fs::read_to_string(reference.join("history.csv")).unwrap();

    // a stand-in for scontrol/qrerun that records what it was asked
    let requeue = dir.join("requeue.sh");
    std::fs::write(&requeue, format!("#!/usr/bin/env bash\necho \"$@\" >> {}\n", dir.join("requeued").display())).unwrap();
    for (script, id_var, id) in [("jobs/batch/slurm.sbatch", "SLURM_JOB_ID", "4242"), ("jobs/batch/pbs.sh", "PBS_JOBID", "77.server")] {
        let out = dir.join(format!("out-{id}"));
        let _ = std::fs::remove_file(dir.join("requeued"));
        let env = vec![
            ("CASE", case.display().to_string()),
            ("OUT", out.display().to_string()),
            ("MPFEM", mpfem.clone()),
            ("LAUNCH", String::new()),
            ("REQUEUE", format!("bash {}", requeue.display())),
            (id_var, id.to_string()),
            ("PBS_O_WORKDIR", dir.display().to_string()),
        ];
        let (code, log) = interrupted(script, &[], &dir, &out, &env);
        assert_eq!(code, Some(3), "{script}: exit code after SIGTERM\n{log}");
        assert!(out.join("checkpoint.h5").exists(), "{script}: no checkpoint\n{log}");
        let asked = std::fs::read_to_string(dir.join("requeued")).unwrap_or_default();
        assert_eq!(asked.trim(), id, "{script}: requeue not asked for this job\n{log}");
        let log = finish(script, &[], &dir, &env);
        assert!(log.contains("continuing from") && log.contains("restarting from"), "{script}: {log}");
        assert_eq!(std::fs::read_to_string(out.join("history.csv")).unwrap(), expected, "{script}: the continued history differs");
    }

    // run_local.sh: interrupted, then run again with the same arguments
    let out = dir.join("out-local");
    let env = vec![("MPFEM", mpfem.clone())];
    let args = [case.to_str().unwrap(), out.to_str().unwrap()];
    let (code, log) = interrupted("jobs/batch/run_local.sh", &args, &dir, &out, &env);
    assert_eq!(code, Some(3), "run_local.sh: exit code after SIGTERM\n{log}");
    let log = finish("jobs/batch/run_local.sh", &args, &dir, &env);
    assert!(log.contains("continuing from"), "{log}");
    assert_eq!(std::fs::read_to_string(out.join("history.csv")).unwrap(), expected, "run_local.sh: the continued history differs");
    let _ = std::fs::remove_dir_all(&dir);
}
