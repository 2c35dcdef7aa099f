"""The notebook session of the docs' Python guide (docs/python.md) runs as written: its
`>>>` cells through doctest, what they print compared with the page. The pictures the
page shows are the figures its cells draw, in order (and the PNG of its last cell); with
MEMCONTACT_DOCS_IMAGES=1 they are written to docs/images/python/ (else to a temporary
directory, so that every run draws them)."""

import doctest
import os
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from conftest import REPO  # noqa: E402

PAGE = REPO / "docs" / "python.md"


def test_walkthrough_runs_as_written(monkeypatch, tmp_path):
    monkeypatch.chdir(REPO)
    plt.close("all")
    text = PAGE.read_text()
    parser = doctest.DocTestParser()
    globs = {}
    # A code fence ends a cell's output (doctest ends it at a blank line).
    cells = re.sub(r"^```.*$", "", text, flags=re.M)
    test = parser.get_doctest(cells, globs, "walkthrough", str(PAGE), 0)
    runner = doctest.DocTestRunner(
        optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    )
    runner.run(test, clear_globs=False)
    result = runner.summarize(verbose=False)
    assert result.attempted > 30
    assert result.failed == 0, f"{result.failed} cells of docs/python.md print otherwise"
    # The pictures: the figures drawn, in order, then the renderer's PNG.
    images = re.findall(r"\]\(images/python/([\w-]+\.png)\)", text)
    figures = plt.get_fignums()
    assert len(images) == len(figures) + 1, (images, figures)
    out = (REPO / "docs" / "images" / "python" if os.environ.get("MEMCONTACT_DOCS_IMAGES")
           else tmp_path)
    out.mkdir(parents=True, exist_ok=True)
    for name, number in zip(images, figures):
        fig = plt.figure(number)
        fig.set_size_inches(7.0, 5.0)
        fig.savefig(out / name, dpi=110, bbox_inches="tight")
    (out / images[-1]).write_bytes(test.globs["png"])
    plt.close("all")
    for name in images:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
