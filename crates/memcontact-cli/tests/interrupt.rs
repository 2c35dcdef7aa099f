//! Ctrl-C: SIGINT during a solve into a directory holding an older result stops the run
//! within 2 s with exit status 130, leaves the older result as it was (its files byte for
//! byte) and nothing stray beside it (no staging directory).

mod common;

use common::{bin, tmp_in};
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

/// A quick case (the older result).
const QUICK: &str = r#"
[mesh]
generator = "rectangle"
nx = 16
[membrane]
tension = 1
load = 8
[obstacle]
shape = 0.1
stiffness = 100
"#;

/// A case whose solve takes far longer than the test waits: coordinate descent on 16 641
/// unknowns with a tolerance it reaches only after a great many sweeps.
const SLOW: &str = r#"
[mesh]
generator = "rectangle"
nx = 128
[membrane]
tension = 1
load = 8
[obstacle]
shape = 0.1
stiffness = 100
[solver]
method = "coordinate"
tolerance = 1e-12
max_iterations = 100000000
"#;

/// Every file of `dir` with its bytes, sorted by name.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    files.sort();
    files
}

/// The names in `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    n.sort();
    n
}

#[test]
fn sigint_during_a_solve_exits_130_within_2_s_and_keeps_the_older_result() {
    let dir = tmp_in("interrupt", "solve");
    let (quick, slow) = (dir.join("quick.toml"), dir.join("slow.toml"));
    std::fs::write(&quick, QUICK).unwrap();
    std::fs::write(&slow, SLOW).unwrap();
    let out = dir.join("out");
    let o = bin()
        .args([
            "solve",
            quick.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let before = snapshot(&out);
    let entries_before = names(&dir);
    let mut child = bin()
        .args([
            "solve",
            slow.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Well into the solve (mesh and assembly take milliseconds here).
    std::thread::sleep(Duration::from_millis(1500));
    assert!(
        child.try_wait().unwrap().is_none(),
        "the slow solve ended by itself"
    );
    // SAFETY: signalling our own child.
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    let sent = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if sent.elapsed() > Duration::from_secs(20) {
            child.kill().unwrap();
            panic!("still running 20 s after SIGINT");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let took = sent.elapsed();
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(took < Duration::from_secs(2), "took {took:?} to stop");
    assert!(stderr.contains("interrupted"), "{stderr}");
    // The older result byte for byte, and nothing else beside it.
    assert_eq!(snapshot(&out), before);
    assert_eq!(names(&dir), entries_before);
}
