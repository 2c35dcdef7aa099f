"""Rewrites the ```text title="Output" blocks of documentation pages with what their
python cells print now (the cells of a page run in order, in one namespace, in a scratch
directory holding a copy of examples/, as tests/test_docs.py runs them).

Usage: python docs/update_outputs.py docs/python.md [more pages...]
(with the memcontact package and matplotlib importable).
"""

import contextlib
import io
import os
import re
import shutil
import sys
import tempfile
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,})(?P<lang>[\w+-]*)(?P<info>.*)$")


def update(page: Path) -> None:
    lines = page.read_text(encoding="utf-8").split("\n")
    out_lines = []
    namespace = {"__name__": "__docs__"}
    last = None  # what the last python cell printed, until a non-blank line
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            if lines[i].strip():
                last = None
            out_lines.append(lines[i])
            i += 1
            continue
        indent, fence = m.group("indent"), m.group("fence")
        j = i + 1
        while not re.match(rf"^{re.escape(indent)}{fence}\s*$", lines[j]):
            j += 1
        body = textwrap.dedent("\n".join(lines[i + 1 : j]))
        marker = next((l for l in reversed(out_lines) if l.strip()), "")
        if m.group("lang") == "python" and "<!-- skip -->" not in marker:
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf):
                exec(compile(body + "\n", f"{page}:{i + 1}", "exec"), namespace)
            out_lines.extend(lines[i : j + 1])
            last = buf.getvalue().rstrip("\n")
        elif m.group("lang") == "text" and 'title="Output"' in m.group("info") and last is not None:
            out_lines.append(lines[i])
            out_lines.extend(indent + l if l else l for l in last.split("\n"))
            out_lines.append(lines[j])
            last = None
        else:
            out_lines.extend(lines[i : j + 1])
            last = None
        i = j + 1
    page.write_text("\n".join(out_lines), encoding="utf-8")


def main() -> None:
    os.environ.setdefault("MPLBACKEND", "Agg")
    pages = [Path(p).resolve() for p in sys.argv[1:]]
    with tempfile.TemporaryDirectory() as tmp:
        shutil.copytree(REPO / "examples", Path(tmp) / "examples")
        for page in pages:
            os.chdir(tmp)
            update(page)
            print(f"updated {page.relative_to(REPO)}")


if __name__ == "__main__":
    main()
