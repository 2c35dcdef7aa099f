//! The references from the code to the documentation site cannot drift: every page
//! `docs/<page>.md` and every anchor `docs/<page>.md#<anchor>` that a Rust, Python, stub,
//! TOML or shell file of the repository names (the rustdoc's citations of the theory, the
//! examples' comments, the scripts' docstrings) must exist. An anchor must be written
//! explicitly on a heading of its page, `## Title {#anchor}`, so that renaming a heading
//! cannot move it; mkdocs' `--strict` build checks the links between the pages themselves.

use std::path::{Path, PathBuf};

/// The kinds of file whose references are checked.
const EXTENSIONS: [&str; 5] = ["rs", "py", "pyi", "toml", "sh"];

/// Directories that hold no sources of the repository: build output (Cargo's `target/`,
/// the site mkdocs builds into `site/`), version control, caches and environments.
fn skipped(dir: &Path, root: &Path) -> bool {
    let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or("");
    matches!(name, "target" | "node_modules" | "__pycache__")
        || (name.starts_with('.') && name != ".ci")
        || (dir.parent() == Some(root) && name == "site")
}

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .expect("the repository's root")
}

/// Every file under `dir` with one of [`EXTENSIONS`], in a stable order.
fn sources(dir: &Path, root: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("a directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            if !skipped(&path, root) {
                sources(&path, root, out);
            }
        } else if path
            .extension()
            .and_then(|e| e.to_str())
            .is_some_and(|e| EXTENSIONS.contains(&e))
        {
            out.push(path);
        }
    }
}

/// A reference to the documentation: the page's path under `docs/` and the anchor, if any.
#[derive(Debug, PartialEq)]
struct Reference {
    page: String,
    anchor: Option<String>,
}

fn is_word(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_' || c == b'-'
}

/// The references in `text`: `docs/` (not inside a longer path or word), path segments of
/// letters, digits, `_` and `-` separated by `/`, `.md` (not followed by a letter), and
/// optionally `#` and the anchor. Returns each with its line number (1-based).
fn references(text: &str) -> Vec<(usize, Reference)> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut from = 0;
    while let Some(found) = text[from..].find("docs/") {
        let start = from + found;
        from = start + "docs/".len();
        if start > 0 && (is_word(bytes[start - 1]) || matches!(bytes[start - 1], b'/' | b'.')) {
            continue;
        }
        let mut end = from;
        while end < bytes.len() && (is_word(bytes[end]) || bytes[end] == b'/') {
            end += 1;
        }
        let page = &text[from..end];
        let mut after = end + ".md".len();
        if !text[end..].starts_with(".md")
            || page.split('/').any(str::is_empty)
            || (after < bytes.len() && bytes[after].is_ascii_alphanumeric())
        {
            continue;
        }
        let mut anchor = None;
        if after < bytes.len() && bytes[after] == b'#' {
            let begin = after + 1;
            let mut stop = begin;
            while stop < bytes.len() && is_word(bytes[stop]) {
                stop += 1;
            }
            if stop > begin {
                anchor = Some(text[begin..stop].to_string());
                after = stop;
            }
        }
        from = after;
        let line = text[..start].matches('\n').count() + 1;
        out.push((
            line,
            Reference {
                page: format!("{page}.md"),
                anchor,
            },
        ));
    }
    out
}

/// The explicit anchors of a page: the `{#anchor}` (or `{#anchor .class}`) of its headings,
/// outside fenced code blocks.
fn anchors(page: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut fenced = false;
    for line in page.lines() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("```") || trimmed.starts_with("~~~") {
            fenced = !fenced;
            continue;
        }
        if fenced || !trimmed.starts_with('#') {
            continue;
        }
        if let Some(attrs) = trimmed
            .rfind("{#")
            .map(|i| &trimmed[i + 2..])
            .and_then(|rest| rest.split_once('}'))
        {
            if let Some(id) = attrs.0.split_whitespace().next() {
                out.push(id.to_string());
            }
        }
    }
    out
}

#[test]
fn the_reference_scanner_finds_pages_and_anchors() {
    // Written without the literal prefix, so that this file's own scan does not see them.
    let d = "docs/";
    let text = format!(
        "see {d}theory.md#problem-2c, then {d}case-file/exact.md#disk.\n\
         ({d}outputs.md) and `{d}theory.md#limits`; not ../{d}x.md, my{d}y.md, \
         {d}z.mdx or {d}*.md"
    );
    let got: Vec<_> = references(&text)
        .into_iter()
        .map(|(line, r)| (line, r.page, r.anchor))
        .collect();
    let some = |s: &str| Some(s.to_string());
    assert_eq!(
        got,
        [
            (1, "theory.md".to_string(), some("problem-2c")),
            (1, "case-file/exact.md".to_string(), some("disk")),
            (2, "outputs.md".to_string(), None),
            (2, "theory.md".to_string(), some("limits")),
        ]
    );
    let page = "# T\n\n## A {#a}\n```\n## not {#b}\n```\n### C {#c .x}\n## D\n";
    assert_eq!(anchors(page), ["a", "c"]);
}

#[test]
fn every_reference_to_the_docs_names_an_existing_page_and_anchor() {
    let root = repository();
    let docs = root.join("docs");
    let mut files = Vec::new();
    sources(&root, &root, &mut files);
    let mut checked = 0;
    let mut broken = Vec::new();
    let mut pages: std::collections::BTreeMap<String, Option<Vec<String>>> = Default::default();
    for file in &files {
        let Ok(text) = std::fs::read_to_string(file) else {
            continue;
        };
        for (line, reference) in references(&text) {
            checked += 1;
            let known = pages.entry(reference.page.clone()).or_insert_with(|| {
                std::fs::read_to_string(docs.join(&reference.page))
                    .ok()
                    .map(|page| anchors(&page))
            });
            let place = format!(
                "{}:{line}",
                file.strip_prefix(&root).unwrap_or(file).display()
            );
            match (known, &reference.anchor) {
                (None, _) => broken.push(format!(
                    "{place}: docs/{} is not a page of the site",
                    reference.page
                )),
                (Some(ids), Some(anchor)) if !ids.contains(anchor) => broken.push(format!(
                    "{place}: docs/{} has no heading with {{#{anchor}}} (its anchors: {})",
                    reference.page,
                    ids.join(", ")
                )),
                _ => {}
            }
        }
    }
    assert!(
        broken.is_empty(),
        "references to the documentation that do not resolve:\n{}",
        broken.join("\n")
    );
    // The scan itself must have worked: the sources cite the theory page about a hundred
    // times.
    assert!(
        checked >= 50,
        "only {checked} references to docs/ found in {} files",
        files.len()
    );
}
