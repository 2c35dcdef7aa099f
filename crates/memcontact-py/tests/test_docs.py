"""The documentation's examples run (docs/*.md and the README).

- Every ```toml block with a ``[mesh]`` section is a complete case: ``memcontact check``
  accepts it (written inside a copy of ``examples/``, so that relative mesh files resolve).
  Every other ```toml block is a fragment: ``memcontact check --fragment`` accepts it. A
  block preceded by ``<!-- invalid -->`` shows an error and must be refused.
- The ```python blocks of a page run in order in one namespace (the cells of a notebook),
  in a scratch directory holding a copy of ``examples/`` (so ``"examples/disk.toml"``
  resolves). A block followed by a ```text title="Output" block must print exactly that.
  A block preceded by ``<!-- skip -->`` (it needs a cluster) is only compiled.
- The ```console and ```sh blocks preceded by ``<!-- run -->`` run their ``memcontact ...``
  lines there too, and must succeed.
- The README stays short, keeps the two commands, and links only to pages that exist.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import shutil
import subprocess
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import List, Optional

import pytest

REPO = Path(__file__).resolve().parents[3]
DOCS = REPO / "docs"
README = REPO / "README.md"
PAGES = sorted(DOCS.rglob("*.md")) + [README]

FENCE = re.compile(r"^(?P<indent>[ \t]*)(?P<fence>`{3,})(?P<lang>[\w+-]*)(?P<info>.*)$")
MARKER = re.compile(r"^\s*<!--\s*(?P<name>[\w-]+)\s*-->\s*$")


@dataclass
class Block:
    page: Path
    line: int  # 1-based line of the opening fence
    lang: str
    info: str
    text: str
    marker: Optional[str]  # the HTML comment on the line before the fence
    output: Optional[str] = None  # the ```text title="Output" block that follows

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(REPO)}:{self.line}"


def blocks(page: Path) -> List[Block]:
    """The fenced code blocks of a page, dedented (blocks may sit inside tabs). A python
    block followed, after blank lines only, by a ```text title="Output" block gets that
    block's text as its output."""
    lines = page.read_text(encoding="utf-8").split("\n")
    found: List[Block] = []
    follows: Optional[Block] = None  # the python block the next block may be the output of
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if not m:
            if lines[i].strip():
                follows = None
            i += 1
            continue
        indent, fence = m.group("indent"), m.group("fence")
        close = re.compile(rf"^{re.escape(indent)}{fence}\s*$")
        j = i + 1
        while j < len(lines) and not close.match(lines[j]):
            j += 1
        body = textwrap.dedent("\n".join(lines[i + 1 : j])) + "\n"
        k = i - 1
        while k >= 0 and not lines[k].strip():
            k -= 1
        mk = MARKER.match(lines[k]) if k >= 0 else None
        block = Block(page, i + 1, m.group("lang"), m.group("info").strip(), body,
                      mk.group("name") if mk else None)
        if follows is not None and block.lang == "text" and 'title="Output"' in block.info:
            follows.output = block.text
            follows = None
        else:
            follows = block if block.lang == "python" else None
        found.append(block)
        i = j + 1
    return found


ALL = [b for p in PAGES for b in blocks(p)]
TOML = [b for b in ALL if b.lang == "toml"]
RUN = [b for b in ALL if b.lang in ("console", "sh") and b.marker == "run"]
PYTHON_PAGES = sorted({b.page for b in ALL if b.lang == "python"})


def _id(b: Block) -> str:
    return b.where


@pytest.fixture()
def scratch(tmp_path: Path) -> Path:
    """A scratch directory holding a copy of examples/."""
    shutil.copytree(REPO / "examples", tmp_path / "examples")
    return tmp_path


def is_complete(text: str) -> bool:
    return re.search(r"^\s*\[mesh\]\s*(#.*)?$", text, re.M) is not None


def test_the_docs_have_cases_and_snippets() -> None:
    assert len(TOML) >= 20, [b.where for b in TOML]
    assert any(b.marker == "invalid" for b in TOML)
    assert len(PYTHON_PAGES) >= 2


@pytest.mark.parametrize("block", TOML, ids=_id)
def test_toml_block(block: Block, cli: Path, scratch: Path) -> None:
    complete = is_complete(block.text)
    # Inside the copy of examples/, so that `file = "disk.msh"` resolves.
    path = scratch / "examples" / "_docs_block.toml"
    path.write_text(block.text, encoding="utf-8")
    args = [str(cli), "check"] + ([] if complete else ["--fragment"]) + [str(path)]
    o = subprocess.run(args, capture_output=True, text=True, cwd=scratch)
    if block.marker == "invalid":
        assert o.returncode != 0, f"{block.where}: refused as shown?\n{block.text}"
    else:
        assert o.returncode == 0, f"{block.where}\n{block.text}\n{o.stdout}\n{o.stderr}"


@pytest.mark.parametrize("block", RUN, ids=_id)
def test_run_block(block: Block, cli: Path, scratch: Path) -> None:
    commands = [l for l in block.text.split("\n") if l.startswith("memcontact ")]
    assert commands, f"{block.where}: no memcontact command to run"
    for command in commands:
        args = shlex.split(command)
        o = subprocess.run([str(cli)] + args[1:], capture_output=True, text=True, cwd=scratch)
        assert o.returncode == 0, f"{block.where}: {command}\n{o.stdout}\n{o.stderr}"


@pytest.mark.parametrize(
    "page", PYTHON_PAGES, ids=lambda p: str(p.relative_to(REPO))
)
def test_python_blocks(page: Path, scratch: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(scratch)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    namespace: dict = {"__name__": "__docs__"}
    for block in (b for b in blocks(page) if b.lang == "python"):
        code = compile(block.text, block.where, "exec")
        if block.marker == "skip":
            continue
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            exec(code, namespace)
        if block.output is not None:
            got = "\n".join(l.rstrip() for l in out.getvalue().strip("\n").split("\n"))
            want = "\n".join(l.rstrip() for l in block.output.strip("\n").split("\n"))
            assert got == want, f"{block.where}: the output the page shows"
    try:
        import matplotlib.pyplot as plt

        plt.close("all")
    except ImportError:  # pragma: no cover
        pass


def test_readme_is_short_and_keeps_the_two_commands() -> None:
    text = README.read_text(encoding="utf-8")
    assert len(text.split("\n")) <= 200 + 1
    assert "cargo run --release -p memcontact-cli -- solve examples/disk.toml -o out/disk" in text
    assert "./scripts/test.sh" in text


def test_readme_links_into_the_site_resolve() -> None:
    text = README.read_text(encoding="utf-8")
    links = re.findall(r"\]\((docs/[^)#\s]+)(#[^)\s]*)?\)", text)
    assert len(links) >= 10, links
    for target, _anchor in links:
        assert (REPO / target).is_file(), target
