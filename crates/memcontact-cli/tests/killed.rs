//! Result sets survive a SIGKILL at any moment: `memcontact solve` is killed again and
//! again at random times around its write of an 11 MB result, and after every kill the
//! output directory holds either the complete previous result or the complete new one
//! (checked against the sizes and hashes summary.json lists, and the run id solution.vtu
//! carries), and the next run leaves no stray file behind.

mod common;

use common::{bin, tmp_in};
use std::path::Path;
use std::time::{Duration, Instant};

/// A case whose result set is large (ASCII VTU, a picture) but quick to compute.
const CASE: &str = r#"
[mesh]
generator = "rectangle"
nx = 192
[membrane]
tension = 1
load = 8
[obstacle]
shape = 0.1
stiffness = 100
[solver]
method = "multigrid"
[output]
vtu = "ascii"
plots = ["deflection"]
"#;

/// The run id of the complete result set in `dir`, or a description of what is wrong.
fn complete(dir: &Path) -> Result<String, String> {
    let text = std::fs::read_to_string(dir.join("summary.json"))
        .map_err(|e| format!("no summary.json: {e}"))?;
    let summary: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("summary.json: {e}"))?;
    let run_id = summary["run_id"].as_str().ok_or("no run id")?.to_string();
    let files = summary["files"].as_object().ok_or("no file list")?;
    let mut expected: Vec<String> = files.keys().cloned().collect();
    expected.push("summary.json".into());
    expected.sort();
    let mut present: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| e.to_string())?
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    present.sort();
    if present != expected {
        return Err(format!("files {present:?}, summary lists {expected:?}"));
    }
    for (name, record) in files {
        let actual = memcontact::write::file_record(&dir.join(name)).map_err(|e| e.to_string())?;
        if record["bytes"] != actual.bytes || record["xxh3"] != actual.xxh3.as_str() {
            return Err(format!("{name} is not the file summary.json lists"));
        }
    }
    // solution.vtu carries the same run id in its field data.
    let vtu = std::fs::read(dir.join("solution.vtu")).map_err(|e| e.to_string())?;
    let head = String::from_utf8_lossy(&vtu[..vtu.len().min(4096)]).into_owned();
    let at = head
        .find(r#"Name="run_id""#)
        .ok_or("solution.vtu has no run id")?;
    let codes = &head[at..];
    let codes = &codes[codes.find('>').unwrap() + 1..codes.find("</DataArray>").unwrap()];
    let id: String = codes
        .split_whitespace()
        .map(|c| c.parse::<u8>().unwrap() as char)
        .collect();
    if id != run_id {
        return Err(format!(
            "solution.vtu of run {id}, summary.json of run {run_id}"
        ));
    }
    Ok(run_id)
}

/// The names in `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A small deterministic generator of kill times (xorshift).
struct Random(u64);

impl Random {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn a_killed_solve_leaves_the_previous_result_or_the_new_one() {
    let cases = tmp_in("killed", "cases");
    let case = cases.join("big.toml");
    std::fs::write(&case, CASE).unwrap();
    let root = tmp_in("killed", "out");
    let out = root.join("result");
    let solve = |load: usize| {
        let mut c = bin();
        c.args(["solve", "-q", "-o"])
            .arg(&out)
            .arg(&case)
            .args(["--set", &format!("membrane.load={}", 8 + load)]);
        c.stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null());
        c
    };
    // A first complete result, and the time a whole run takes.
    let t0 = Instant::now();
    assert!(solve(0).status().unwrap().success());
    let full = t0.elapsed().as_secs_f64();
    let mut current = complete(&out).unwrap();
    let mut random = Random(0x9e37_79b9_7f4a_7c15);
    let (mut replaced, mut kept, mut during_write) = (0, 0, 0);
    // At least 40 kills, and more (up to 200) until the kills have hit the write and both
    // sides of the move into place: the machine's speed varies.
    let mut k = 0;
    while k < 40 || (k < 200 && (kept == 0 || replaced == 0 || during_write == 0)) {
        k += 1;
        let mut child = solve(k).spawn().unwrap();
        // Uniformly over the run and beyond, so that kills land in the solve, in the write
        // of every file, in the final move and after it.
        std::thread::sleep(Duration::from_secs_f64(random.unit() * 1.5 * full));
        let _ = child.kill();
        let _ = child.wait();
        let now = complete(&out).unwrap_or_else(|e| panic!("kill {k}: {e}"));
        if now == current {
            kept += 1;
        } else {
            replaced += 1;
            current = now;
        }
        // Beside the result: at most the staging directory of the run just killed.
        let beside: Vec<String> = names(&root).into_iter().filter(|n| n != "result").collect();
        assert!(beside.len() <= 1, "kill {k}: {beside:?}");
        // A staging directory with files in it: this kill hit the write.
        if beside.iter().any(|b| !names(&root.join(b)).is_empty()) {
            during_write += 1;
        }
    }
    // The kills hit the write and both sides of the move into place.
    eprintln!("kept {kept}, replaced {replaced}, during the write {during_write}");
    assert!(
        kept > 0 && replaced > 0 && during_write > 0,
        "kept {kept}, replaced {replaced}, during the write {during_write}"
    );
    // The next run cleans up after the killed ones.
    assert!(solve(0).status().unwrap().success());
    assert_ne!(complete(&out).unwrap(), current);
    assert_eq!(names(&root), ["result"]);
}
