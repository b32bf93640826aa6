//! A run whose disk fills up (issue "Nothing lost, nothing silent", item 5): the output folder
//! on a 1.5 MB tmpfs mounted for the test (root and `mount -t tmpfs`, as CI has: the test fails
//! where it cannot mount, it does not skip), a 2 × 2 disc compaction writing results every step
//! (about 4 MB in all). The run stops at the step whose output failed, exit code 1, naming the
//! file and the cause; every `history.csv` row is whole; `summary.json` is valid JSON saying
//! "failed" and why (written over the space reserved at the start); every step `results.xdmf`
//! names is readable in `results.h5`; no temporary file is left. The folder moved to a larger
//! disk restarts from its checkpoint and ends with the uninterrupted run's `history.csv`, byte
//! for byte. An output folder removed under a run stops it the same way.

mod common;

use common::{mpfem, root, tmpdir};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A tmpfs mounted at a folder, unmounted when dropped.
struct Mount(PathBuf);

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

#[test]
fn a_full_disk_stops_the_run_at_once_with_whole_output_and_restarts_elsewhere() {
    let dir = tmpdir("disk_full");
    let text = std::fs::read_to_string(root().join("jobs/compaction/discs_2x2_lateral.toml")).unwrap().replace("mesh_size = 4.0", "mesh_size = 8.0");
    assert!(text.contains("mesh_size = 8.0"), "the job's mesh size changed");
    let case = dir.join("case.toml");
    std::fs::write(&case, format!("{text}\n[output]\nevery = 1\ncheckpoint_every = 5\n")).unwrap();
    let run = |out: &Path, extra: &[&str]| mpfem().args(["run", "--no-plots", "-q"]).arg(&case).arg("--out").arg(out).args(extra).output().unwrap();

    // the uninterrupted run, on the large disk
    let whole = dir.join("whole");
    let o = run(&whole, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let whole_size: u64 = std::fs::read_dir(&whole).unwrap().map(|e| e.unwrap().metadata().unwrap().len()).sum();
    assert!(whole_size > 3_000_000, "the run writes {whole_size} bytes: the 1.5 MB disk would not fill");

    // the small disk
    let disk = dir.join("disk");
    std::fs::create_dir_all(&disk).unwrap();
    let mounted = Command::new("mount").args(["-t", "tmpfs", "-o", "size=1500k", "tmpfs"]).arg(&disk).status();
    assert!(mounted.is_ok_and(|s| s.success()), "cannot mount a tmpfs at {} (the test needs root, as in CI)", disk.display());
    let _mount = Mount(disk.clone());
    let out = disk.join("out");
    let o = run(&out, &[]);
    let said = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "a full disk is a failed run: {said}");
    assert!(said.contains("could not be written") && said.contains("No space left on device"), "the message names neither the failed write nor its cause: {said}");
    assert!(!said.contains("panicked"), "{said}");

    // every row whole: the header's column count, every field a number
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    assert!(history.ends_with('\n'), "history.csv ends in the middle of a row");
    let mut lines = history.lines();
    let columns = lines.next().expect("a header").split(',').count();
    let rows: Vec<&str> = lines.collect();
    assert!(rows.len() >= 5, "{} rows before the disk filled: the case no longer fills it mid-run", rows.len());
    for r in &rows {
        let fields: Vec<&str> = r.split(',').collect();
        assert!(fields.len() == columns && fields.iter().all(|f| f.parse::<f64>().is_ok()), "a cut row: {r}");
    }
    // the same rows as the uninterrupted run, as far as they go
    let reference = std::fs::read_to_string(whole.join("history.csv")).unwrap();
    assert!(reference.starts_with(&history), "the rows written before the disk filled differ from the uninterrupted run's");

    // summary.json: valid, failed, why
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).expect("summary.json is valid JSON");
    assert_eq!(summary["status"], "failed", "{summary}");
    assert!(summary["error"].as_str().is_some_and(|e| e.contains("output failed")), "{summary}");

    // every step results.xdmf names is readable in results.h5
    let xdmf = std::fs::read_to_string(out.join("results.xdmf")).unwrap();
    let mut named: Vec<String> = xdmf.split("results.h5:/").skip(1).map(|s| s.split('<').next().unwrap().trim().to_string()).collect();
    named.sort();
    named.dedup();
    assert!(!named.is_empty(), "results.xdmf names no dataset");
    let file = hdf5::File::open(out.join("results.h5")).expect("results.h5 opens");
    for path in &named {
        let d = file.dataset(path).unwrap_or_else(|e| panic!("{path}, named by results.xdmf: {e}"));
        let n: usize = d.shape().iter().product();
        assert!(n > 0, "{path} is empty");
        match d.dtype().map(|t| t.size()) {
            Ok(8) if path.ends_with("cells") => drop(d.read_raw::<i64>().unwrap_or_else(|e| panic!("{path}: {e}"))),
            Ok(8) => drop(d.read_raw::<f64>().unwrap_or_else(|e| panic!("{path}: {e}"))),
            _ => drop(d.read_raw::<i32>().unwrap_or_else(|e| panic!("{path}: {e}"))),
        }
    }
    drop(file);
    let left: Vec<String> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().to_string()).filter(|n| n.ends_with(".tmp")).collect();
    assert!(left.is_empty(), "temporary files left behind: {left:?}");

    // moved to a larger disk: the restart ends as the uninterrupted run
    let moved = dir.join("moved");
    copy_dir(&out, &moved);
    let o = run(&moved, &["--restart", moved.to_str().unwrap()]);
    assert!(o.status.success(), "the restart on the larger disk: {}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read(moved.join("history.csv")).unwrap(), reference.as_bytes(), "the restarted run's history.csv differs from the uninterrupted run's");
    drop(_mount);

    // the output folder taken away under the run: it stops at once too (the open files took
    // the rows into nowhere and the run went on to its end)
    let gone = dir.join("gone");
    let child = mpfem().args(["run", "--no-plots", "-q"]).arg(&case).arg("--out").arg(&gone).stderr(std::process::Stdio::piped()).spawn().unwrap();
    // (once the first step's row is written: the run is under way)
    while std::fs::read_to_string(gone.join("history.csv")).map_or(0, |t| t.lines().count()) < 2 {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    // (moved away in one step: removing it file by file races with the files the run creates)
    std::fs::rename(&gone, dir.join("gone-moved")).unwrap();
    let o = child.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "a removed output folder is a failed run: {said}");
    assert!(said.contains("could not be written") && (said.contains("was removed") || said.contains("No such file")), "{said}");
    let _ = std::fs::remove_dir_all(&dir);
}
