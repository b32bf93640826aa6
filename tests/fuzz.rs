//! A mutation fuzz of the case parser and of the checkpoint reader (issue "nothing lost,
//! nothing silent", item 9), in process, with a fixed seed so that a failure is repeatable.
//!
//! - **Case files**: every shipped job (compaction, paper, verification, robustness, the
//!   default) mutated one to three times — a byte changed, a line deleted, doubled or moved, a
//!   number replaced by an extreme one (0, −1, ±1e308, NaN, ±inf, ±2⁶³, 1e-300, 10¹⁸), a string
//!   value by another, a junk line inserted — and parsed and validated (`case::parse`: what
//!   `mpfem check` and `mpfem run` do before they mesh). No input may panic (caught and
//!   reported with the input, written next to the test's scratch folder), and every refusal
//!   must name its key or its line.
//! - **Checkpoints**: a 4-disc checkpoint mutated — bits flipped (1 to 8), a range zeroed, the
//!   file cut short — read (`Checkpoint::read`) and, when it reads, restored onto the case's
//!   model. No mutation may panic or restore into a state other than the intact one's.
//!
//! Counts: 20,000 case inputs and 2,000 checkpoint mutations by default (about a minute in a
//! release build); `MPFEM_FUZZ_CASES=N` and `MPFEM_FUZZ_CHECKPOINTS=N` run more, e.g. the
//! documented long run `MPFEM_FUZZ_CASES=1000000 MPFEM_FUZZ_CHECKPOINTS=100000 cargo test
//! --release --test fuzz -- --nocapture` (and `MPFEM_FUZZ_SEED=K` another sequence).

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

mod common;
use common::{mpfem, root, tmpdir};

/// xorshift64*: the fuzz's own pseudo-random numbers (repeatable, no dependency).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn count(var: &str, default: usize) -> usize {
    std::env::var(var).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn seed() -> u64 {
    std::env::var("MPFEM_FUZZ_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(0x9e37_79b9_7f4a_7c15) | 1
}

/// The shipped jobs: (path, text).
fn seeds() -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    for dir in ["jobs/compaction", "jobs/paper", "jobs/verification", "jobs/robustness"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(root().join(dir)).unwrap().flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|e| e == "toml")).collect();
        files.sort();
        for f in files {
            let text = std::fs::read_to_string(&f).unwrap();
            out.push((f, text));
        }
    }
    let d = root().join("jobs/default.toml");
    out.push((d.clone(), std::fs::read_to_string(&d).unwrap()));
    out
}

const EXTREMES: [&str; 14] = ["0", "-1", "1e308", "-1e308", "nan", "inf", "-inf", "9223372036854775807", "-9223372036854775808", "1e-300", "1000000000000000000", "0.0", "-0.5", "18446744073709551615"];
const WORDS: [&str; 12] = ["\"\"", "\"disc\"", "\"barrier\"", "\"penalty\"", "\"j2\"", "\"left\"", "\"top\"", "\"x\"", "[]", "{}", "true", "\"petsc\""];
const JUNK: [&str; 10] = ["[[bodies]]", "[solver]", "a.b.c.d.e.f = 1", "x = [1, [2, [3, [4]]]]", "[[walls]]\nside = \"left\"", "= 3", "[time]\nend = 1.0", "mesh_size = 1e-12", "position = -9.3e18", "\u{feff}"];

/// One mutation of a case file's text.
fn mutate(text: &str, rng: &mut Rng) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    if lines.is_empty() {
        return JUNK[rng.below(JUNK.len())].to_string();
    }
    let i = rng.below(lines.len());
    match rng.below(7) {
        0 => {
            // a byte of the line changed to a printable character (or the line emptied)
            let mut b = lines[i].clone().into_bytes();
            if b.is_empty() {
                lines[i] = JUNK[rng.below(JUNK.len())].to_string();
            } else {
                let k = rng.below(b.len());
                const CHARS: &[u8] = b" =[]{}.,\"'#0123456789-+eabcxyz_\\";
                b[k] = CHARS[rng.below(CHARS.len())];
                lines[i] = String::from_utf8_lossy(&b).into_owned();
            }
        }
        1 => {
            lines.remove(i);
        }
        2 => {
            let l = lines[i].clone();
            lines.insert(rng.below(lines.len() + 1), l);
        }
        3 | 4 => {
            // a number replaced by an extreme one, or a value by another word
            let l = &lines[i];
            if let Some(eq) = l.find('=') {
                let value = if rng.below(2) == 0 { EXTREMES[rng.below(EXTREMES.len())] } else { WORDS[rng.below(WORDS.len())] };
                lines[i] = format!("{}= {value}", &l[..eq]);
            } else if let Some(start) = l.find(|c: char| c.is_ascii_digit()) {
                let end = l[start..].find(|c: char| !(c.is_ascii_digit() || c == '.' || c == 'e' || c == '-')).map_or(l.len(), |e| start + e);
                lines[i] = format!("{}{}{}", &l[..start], EXTREMES[rng.below(EXTREMES.len())], &l[end..]);
            }
        }
        5 => {
            let j = rng.below(lines.len());
            lines.swap(i, j);
        }
        _ => lines.insert(i, JUNK[rng.below(JUNK.len())].to_string()),
    }
    lines.join("\n")
}

#[test]
fn mutated_case_files_never_panic_and_every_refusal_names_a_key_or_line() {
    let n = count("MPFEM_FUZZ_CASES", 20_000);
    let seeds = seeds();
    assert!(seeds.len() >= 30, "only {} seed jobs", seeds.len());
    let mut rng = Rng(seed());
    let out = tmpdir("cases");
    let (mut accepted, mut refused) = (0usize, 0usize);
    let mut panics: Vec<PathBuf> = Vec::new();
    let mut unnamed: Vec<(PathBuf, String)> = Vec::new();
    // (a panic is caught and reported below: no panic message on stderr per input)
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|i| if std::env::var_os("MPFEM_FUZZ_VERBOSE").is_some() { eprintln!("{i}") }));
    for k in 0..n {
        let (path, text) = &seeds[rng.below(seeds.len())];
        let mut t = text.clone();
        for _ in 0..1 + rng.below(3) {
            t = mutate(&t, &mut rng);
        }
        let base = path.parent().unwrap();
        if std::env::var_os("MPFEM_FUZZ_VERBOSE").is_some() {
            std::fs::write(out.join("current.toml"), &t).unwrap();
        }
        let r = catch_unwind(AssertUnwindSafe(|| mpfem::case::parse(&t, base).map(|c| c.bodies.len())));
        match r {
            Ok(Ok(_)) => accepted += 1,
            Ok(Err(e)) => {
                refused += 1;
                if e.key.is_empty() && !e.message.contains("line ") && unnamed.len() < 20 {
                    let f = out.join(format!("unnamed-{k}.toml"));
                    std::fs::write(&f, &t).unwrap();
                    unnamed.push((f, e.to_string()));
                }
            }
            Err(_) => {
                let f = out.join(format!("panic-{k}.toml"));
                std::fs::write(&f, &t).unwrap();
                panics.push(f);
            }
        }
    }
    std::panic::set_hook(hook);
    println!("{n} mutated case files from {} jobs: {accepted} accepted, {refused} refused, {} panics, {} refusals naming neither key nor line", seeds.len(), panics.len(), unnamed.len());
    assert!(panics.is_empty(), "{} inputs panicked, e.g. {:?} (rerun: mpfem check FILE)", panics.len(), &panics[..panics.len().min(5)]);
    assert!(unnamed.is_empty(), "refusals naming neither key nor line: {unnamed:#?}");
    assert!(accepted > n / 20 && refused > n / 20, "the mutations are too mild or too wild: {accepted} accepted, {refused} refused");
    let _ = std::fs::remove_dir_all(&out);
}

/// A checkpoint of 4 discs at step 5 (`mpfem run`), the case it was written for, its bytes.
fn checkpoint(dir: &Path) -> (PathBuf, Vec<u8>) {
    let text = std::fs::read_to_string(root().join("jobs/compaction/discs_2x2_lateral.toml")).unwrap();
    let text = text.replace("mesh_size = 4.0", "mesh_size = 8.0").replace("end = 3.0", "end = 0.3");
    let case = dir.join("small.toml");
    std::fs::write(&case, format!("{text}\n[output]\ncheckpoint_every = 5\n")).unwrap();
    let out = dir.join("run");
    let o = mpfem().args(["run", "--no-plots", "-q"]).arg(&case).arg("--out").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(out.join("checkpoint.h5")).unwrap();
    (case, bytes)
}

#[test]
fn mutated_checkpoints_never_panic_nor_restore_into_another_state() {
    let n = count("MPFEM_FUZZ_CHECKPOINTS", 2_000);
    let dir = tmpdir("checkpoints");
    let (case, good) = checkpoint(&dir);
    let c = mpfem::case::load(&case).unwrap();
    let model = mpfem::model::Model::from_case(&c).unwrap();
    let path = dir.join("mutated.h5");
    std::fs::write(&path, &good).unwrap();
    let intact = mpfem::checkpoint::Checkpoint::read(&path).unwrap().restore(model.clone(), c.time, c.solver).unwrap().state();
    let mut rng = Rng(seed() ^ 0xabcd);
    let (mut refused, mut restored) = (0usize, 0usize);
    let mut panics = Vec::new();
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|i| if std::env::var_os("MPFEM_FUZZ_VERBOSE").is_some() { eprintln!("{i}") }));
    for k in 0..n {
        let mut bytes = good.clone();
        match rng.below(10) {
            0 => bytes.truncate(rng.below(good.len())),
            1 => {
                let at = rng.below(bytes.len());
                let len = 1 + rng.below(64);
                for b in bytes.iter_mut().skip(at).take(len) {
                    *b = 0;
                }
            }
            _ => {
                for _ in 0..1 + rng.below(8) {
                    let at = rng.below(bytes.len());
                    bytes[at] ^= 1 << rng.below(8);
                }
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        let r = catch_unwind(AssertUnwindSafe(|| match mpfem::checkpoint::Checkpoint::read(&path) {
            Err(_) => None,
            Ok(ck) => ck.restore(model.clone(), c.time, c.solver).ok().map(|s| s.state()),
        }));
        match r {
            Ok(None) => refused += 1,
            Ok(Some(state)) => {
                // what reads must be the intact state, bit for bit (the flip hit bytes nothing
                // reads)
                assert_eq!(format!("{:?}", state.sol.u.iter().map(|v| v.to_bits()).collect::<Vec<_>>()), format!("{:?}", intact.sol.u.iter().map(|v| v.to_bits()).collect::<Vec<_>>()), "mutation {k} restored other displacements");
                assert_eq!(format!("{:?}", state.scalars), format!("{:?}", intact.scalars), "mutation {k} restored other scalars");
                restored += 1;
            }
            Err(_) => {
                let f = dir.join(format!("panic-{k}.h5"));
                std::fs::write(&f, &bytes).unwrap();
                panics.push(f);
            }
        }
    }
    std::panic::set_hook(hook);
    println!("{n} mutated checkpoints: {refused} refused, {restored} restored to the intact state (mutations in bytes nothing reads), {} panics", panics.len());
    assert!(panics.is_empty(), "{} mutations panicked, e.g. {:?}", panics.len(), &panics[..panics.len().min(5)]);
    let _ = std::fs::remove_dir_all(&dir);
}
