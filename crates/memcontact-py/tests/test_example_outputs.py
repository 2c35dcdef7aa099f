"""The outputs of every example are those of the release before the library was
reorganised into one run (`memcontact solve` of each example, a load sweep and a
convergence study and rigid-limit sweep): every file byte for byte, except what differs
from run to run by design (run ids, times, and the hashes of files that hold a run id).

The expected digests (data/example_outputs.json) were made with that release's binary,
and made again once since, when TNNMG went from two to three multigrid cycles per Newton
correction while the vertex states change (a deliberate change of the iterates: every
example's u then agreed with that release's to 1.7e-11 of its maximum, with the same
vertex states, and no iteration count grew except roof-frame's, 9 to 10), and again
when the pictures learned to tell two bodies apart (the four pictures of the six
examples with a body below, and their summaries' file hashes; nothing else changed):

    python crates/memcontact-py/tests/test_example_outputs.py PATH/TO/memcontact

(which rewrites the JSON file); the test computes the same digests with this release."""

import csv
import hashlib
import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
EXAMPLES = REPO / "examples"
GOLDEN = HERE / "data" / "example_outputs.json"

#: The runs: a name, then the command's arguments after the binary (OUT is the output
#: directory). They run in the repository, so that the case files' paths (which titles and
#: summaries show) are the same wherever it is.
RUNS = [
    (f"solve {p.stem}", ["solve", f"examples/{p.name}", "-o", "OUT", "-q"])
    for p in sorted(EXAMPLES.glob("*.toml"))
    # Adaptive runs, sensitivities and fits came later than that release (their files are
    # checked by test_adapt, test_sensitivity and the command-line tool's tests).
    if not any(s in p.read_text() for s in ("[adapt]", "[sensitivity]", "[fit]"))
] + [
    (
        "sweep roof",
        ["solve", "examples/roof.toml", "-o", "OUT", "-q", "--set", "sweep.parameter=load_factor",
         "--set", "sweep.from=0.5", "--set", "sweep.to=1.5", "--set", "sweep.steps=3"],
    ),
    ("convergence disk", ["convergence", "examples/disk.toml", "--levels", "2", "-q", "-o", "OUT"]),
    (
        "convergence compare",
        ["convergence", "examples/manufactured-square.toml", "--levels", "2", "-q", "-o", "OUT",
         "--compare", "foundation"],
    ),
    (
        "h sweep disk",
        ["convergence", "examples/disk.toml", "--levels", "0", "--h-sweep", "-q", "-o", "OUT",
         "--h-values", "10,1000"],
    ),
]

#: Keys of summary.json and manifest.json that differ from run to run by design.
VOLATILE = {"run_id", "time_mesh_s", "time_assembly_s", "time_solve_s", "time_write_s",
            "time_total_s", "solver_phases_s"}


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def digest_csv(data: bytes) -> str:
    """A CSV file without its columns of seconds."""
    rows = list(csv.reader(io.StringIO(data.decode())))
    keep = [k for k, name in enumerate(rows[0]) if not name.endswith("_s") and name != "seconds"]
    return sha("\n".join(",".join(r[k] for k in keep) for r in rows).encode())


def digest_json(data: bytes) -> object:
    """summary.json or manifest.json without the run's own values: its run id, its times,
    and the records of the files that hold the run id or times (those files are compared
    themselves, without them)."""
    value = json.loads(data)
    for key in VOLATILE:
        value.pop(key, None)
    files = value.get("files")
    if isinstance(files, dict):
        value["files"] = {
            name: record for name, record in files.items()
            if not name.endswith(("solution.vtu", "summary.json", "sweep.csv", "h_sweep.csv"))
            and not name.split("/")[-1].startswith("convergence-")
            and name.split("/")[-1] != "convergence.csv"
        }
    return value


def digest_dir(out: Path) -> dict:
    """Every file of a result set (subdirectories included) by its path, digested."""
    run_ids = set()
    for summary in list(out.rglob("summary.json")) + list(out.rglob("manifest.json")):
        run_ids.add(json.loads(summary.read_bytes()).get("run_id", ""))
    found = {}
    for path in sorted(out.rglob("*")):
        if path.is_dir():
            continue
        name = path.relative_to(out).as_posix()
        data = path.read_bytes()
        if path.suffix == ".json":
            found[name] = digest_json(data)
        elif path.name in ("convergence.csv", "h_sweep.csv", "sweep.csv") or path.name.startswith(
            "convergence-"
        ):
            found[name] = digest_csv(data)
        elif path.suffix == ".vtu":
            # The run id is in its field data as the ASCII codes of its digits.
            for run_id in run_ids:
                if run_id:
                    codes = " ".join(str(ord(c)) for c in run_id).encode()
                    data = data.replace(codes, b"run id")
            found[name] = sha(data)
        else:
            found[name] = sha(data)
    return found


def run(binary: str, args: list, out: Path) -> dict:
    """Runs one command into `out` and digests what it wrote."""
    argv = [binary] + [str(out) if a == "OUT" else a for a in args]
    subprocess.run(argv, check=True, capture_output=True, cwd=REPO)
    return digest_dir(out)


def run_all(binary: str, work: Path) -> dict:
    return {name: run(binary, args, work / name.replace(" ", "_")) for name, args in RUNS}


@pytest.mark.parametrize("name", [n for n, _ in RUNS])
def test_outputs_are_those_of_the_release_before(cli, tmp_path, name):
    golden = json.loads(GOLDEN.read_text())
    assert name in golden, f"no expected outputs for {name}: regenerate {GOLDEN.name}"
    found = run(str(cli), dict(RUNS)[name], tmp_path / "out")
    expected = golden[name]
    assert sorted(found) == sorted(expected)
    for file, value in expected.items():
        assert found[file] == value, f"{name}: {file} differs"


if __name__ == "__main__":
    import tempfile

    with tempfile.TemporaryDirectory() as work:
        digests = run_all(sys.argv[1], Path(work))
    GOLDEN.parent.mkdir(exist_ok=True)
    GOLDEN.write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")
    print(f"wrote {GOLDEN}: {len(digests)} runs")
