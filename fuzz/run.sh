#!/usr/bin/env bash
# Fuzzes the readers with cargo-fuzz (libFuzzer) on the stable toolchain.
#
#   fuzz/run.sh TARGET [SECONDS] [extra libFuzzer flags]   one target (default 60 s)
#   fuzz/run.sh all [SECONDS]                              every target in turn
#
# Targets: case (case-file parser and validation), expr (expression compiler and
# evaluator), gmsh (the MSH reader on raw bytes), gmsh_flavours (the MSH sections under
# each of the six headers), mesh (Mesh::new and what follows an accepted mesh),
# measurements (the [fit] measurements CSV reader).
# The corpus (fuzz/corpus/TARGET) is seeded from examples/, the test fixtures and
# fuzz/seeds/; crashes land in fuzz/artifacts/TARGET. Installs cargo-fuzz when missing.
# RUSTC_BOOTSTRAP=1 lets the stable compiler take the sanitizer flags cargo-fuzz passes.
set -euo pipefail
self="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
cd "$(dirname "$self")"
target="${1:?usage: fuzz/run.sh TARGET|all [SECONDS] [libFuzzer flags]}"
seconds="${2:-60}"
shift $(( $# >= 2 ? 2 : 1 ))
export RUSTC_BOOTSTRAP=1
if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install --locked cargo-fuzz
fi
TARGETS=(case expr gmsh gmsh_flavours mesh measurements)
if [ "$target" = all ]; then
    for t in "${TARGETS[@]}"; do "$self" "$t" "$seconds" "$@"; done
    exit 0
fi

seed() {
    local dir="corpus/$1"
    mkdir -p "$dir"
    case "$1" in
        case)
            cp ../examples/*.toml seeds/case/*.toml "$dir"/ ;;
        measurements)
            cp seeds/measurements/*.csv "$dir"/ ;;
        expr)
            # Each seed: 16 bytes of the point (x = 0.25, y = 0.75), then the expression.
            python3 - "$dir" ../examples/*.toml seeds/expr/*.txt <<'PY'
import re, struct, sys, pathlib, hashlib
out = pathlib.Path(sys.argv[1])
texts = set()
for f in sys.argv[2:]:
    t = pathlib.Path(f).read_text()
    if f.endswith(".txt"):
        texts.update(l for l in t.splitlines() if l.strip())
    else:
        texts.update(re.findall(r'"([^"\n]*[xyr(][^"\n]*)"', t))
for e in texts:
    data = struct.pack("<dd", 0.25, 0.75) + e.encode()
    (out / hashlib.sha1(data).hexdigest()).write_bytes(data)
PY
            ;;
        gmsh)
            cp ../examples/*.msh ../crates/memcontact/tests/data/*.msh "$dir"/ ;;
        gmsh_flavours)
            # The fixtures past their header, with the byte that picks it.
            python3 - "$dir" ../crates/memcontact/tests/data/*.msh <<'PY'
import sys, pathlib
out = pathlib.Path(sys.argv[1])
for f in sys.argv[2:]:
    b = pathlib.Path(f).read_bytes()
    end = b.index(b"$EndMeshFormat") + len(b"$EndMeshFormat\n")
    v4 = b"4.1" in b[:40]
    binary = b" 1 8" in b[:40] or b" 1 4" in b[:40]
    pick = (3 if v4 else 2) if binary else (1 if v4 else 0)
    (out / pathlib.Path(f).name).write_bytes(bytes([pick]) + b[end:])
PY
            ;;
        mesh)
            # The disc fixture as raw doubles, and a 3 × 3 grid of small integers.
            python3 - "$dir" ../crates/memcontact/tests/data/disk_v22_ascii.msh <<'PY'
import sys, pathlib, struct
out = pathlib.Path(sys.argv[1])
lines = pathlib.Path(sys.argv[2]).read_text().split("\n")
i = lines.index("$Nodes")
n = int(lines[i + 1])
tags, pts = {}, []
for k in range(n):
    t, x, y, _ = lines[i + 2 + k].split()
    tags[t] = len(pts); pts.append((float(x), float(y)))
j = lines.index("$Elements")
tris = []
for l in lines[j + 2: j + 2 + int(lines[j + 1])]:
    f = l.split()
    if f[1] == "2":
        nt = int(f[2]); tris.append([tags[v] for v in f[3 + nt:6 + nt]])
used = sorted({v for t in tris for v in t})
index = {v: k for k, v in enumerate(used)}
b = bytes([1]) + struct.pack("<H", len(used))
for v in used: b += struct.pack("<dd", *pts[v])
for t in tris: b += struct.pack("<HHH", *(index[v] for v in t)) + bytes([1])
(out / "disk").write_bytes(b)
g = bytes([0]) + struct.pack("<H", 9) + bytes(c for j in range(3) for i in range(3) for c in (8 * i, 8 * j))
for j in range(2):
    for i in range(2):
        a = 3 * j + i
        g += struct.pack("<HHH", a, a + 1, a + 4) + bytes([0]) + struct.pack("<HHH", a, a + 4, a + 3) + bytes([2])
(out / "grid").write_bytes(g)
PY
            ;;
        *) echo "unknown target $1 (choose ${TARGETS[*]} or all)" >&2; exit 2 ;;
    esac
}
seed "$target"
# Sanitizer instrumentation needs nightly features; `-s none` keeps libFuzzer's coverage
# guidance with plain (stable) code generation. Release mode with debug assertions.
exec cargo fuzz run -s none "$target" "corpus/$target" -- \
    -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 "$@"
