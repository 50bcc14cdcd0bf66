//! The documentation's cross-references resolve: every relative link and image of README.md,
//! ARCHITECTURE.md and docs/*.md names a file of the repository, every `docs/NAME.md` a reader is
//! sent to exists, and every section quoted after a document (`docs/model-choices.md, "Shear
//! drive"`) starts one of that document's headings or bold paragraph titles.

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md, ARCHITECTURE.md and every Markdown file directly in docs/.
fn documents() -> Vec<PathBuf> {
    let mut files = vec![root().join("README.md"), root().join("ARCHITECTURE.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ is readable")
        .map(|e| e.expect("docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    files.extend(docs);
    files
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Targets of Markdown links and images, `[text](target)`, with the line they are on. Text inside
/// code spans and fenced code blocks is not a link.
fn link_targets(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Drop code spans: every second piece between backticks.
        let plain: String = line
            .split('`')
            .enumerate()
            .filter(|(i, _)| i % 2 == 0)
            .map(|(_, s)| s)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = plain.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let Some(end) = after.find(')') else { break };
            out.push((n + 1, after[..end].trim().to_string()));
            rest = &after[end..];
        }
    }
    out
}

fn is_external(target: &str) -> bool {
    target.starts_with("http://")
        || target.starts_with("https://")
        || target.starts_with("mailto:")
        || target.starts_with('#')
}

#[test]
fn every_relative_link_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let dir = doc.parent().expect("a document has a folder");
        for (line, target) in link_targets(&read(&doc)) {
            if is_external(&target) {
                continue;
            }
            let path = target.split('#').next().unwrap_or("");
            checked += 1;
            if !dir.join(path).exists() {
                broken.push(format!("{}:{line}: {target}", doc.display()));
            }
        }
    }
    assert!(checked > 0, "no relative link found: the scan is broken");
    assert!(
        broken.is_empty(),
        "links to missing files:\n{}",
        broken.join("\n")
    );
}

/// Every `docs/NAME.md` (or `ARCHITECTURE.md`) a document mentions, with its line.
fn mentioned_documents(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(i) = rest.find("docs/") {
            let tail = &rest[i..];
            let end = tail
                .find(|c: char| !(c.is_ascii_alphanumeric() || "/._-".contains(c)))
                .unwrap_or(tail.len());
            let name = tail[..end].trim_end_matches('.');
            let inside_path = line[..line.len() - rest.len() + i]
                .chars()
                .last()
                .is_some_and(|c| c.is_ascii_alphanumeric() || "/_-.".contains(c));
            if name.ends_with(".md") && !inside_path {
                out.push((n + 1, name.to_string()));
            }
            rest = &tail[end.max(1)..];
        }
    }
    out
}

#[test]
fn every_mentioned_document_exists() {
    let mut missing = Vec::new();
    for doc in documents() {
        for (line, name) in mentioned_documents(&read(&doc)) {
            if !root().join(&name).exists() {
                missing.push(format!("{}:{line}: {name}", doc.display()));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "documents that do not exist:\n{}",
        missing.join("\n")
    );
}

/// Section titles of a Markdown file: headings (`#` lines, without the hashes) and the bold
/// run-in titles that open a paragraph or a list item (`**Export streaming.** ...`).
fn headings(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| {
            if l.starts_with('#') {
                return Some(l.trim_start_matches('#').trim().to_string());
            }
            let bold = l.strip_prefix("- ").unwrap_or(l).strip_prefix("**")?;
            bold.find("**").map(|end| bold[..end].to_string())
        })
        .collect()
}

/// `(line, document, quoted section)` for every `docs/NAME.md, "Section"` or
/// `docs/NAME.md "Section"` (also `ARCHITECTURE.md`).
fn section_citations(text: &str) -> Vec<(usize, String, String)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for (doc_start, _) in line.match_indices(".md") {
            let before = &line[..doc_start];
            let start = before
                .rfind(|c: char| !(c.is_ascii_alphanumeric() || "/_-".contains(c)))
                .map_or(0, |i| i + 1);
            let name = format!("{}.md", &before[start..]);
            if !(name.starts_with("docs/") || name == "ARCHITECTURE.md") {
                continue;
            }
            let after = &line[doc_start + 3..];
            let after = after.strip_prefix(',').unwrap_or(after);
            let Some(quoted) = after.strip_prefix(" \"") else {
                continue;
            };
            if let Some(end) = quoted.find('"') {
                out.push((n + 1, name, quoted[..end].to_string()));
            }
        }
    }
    out
}

#[test]
fn every_cited_section_is_a_heading() {
    let mut wrong = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        for (line, name, section) in section_citations(&read(&doc)) {
            let target = root().join(&name);
            let Ok(text) = std::fs::read_to_string(&target) else {
                continue; // a missing document is every_mentioned_document_exists's failure
            };
            checked += 1;
            if !headings(&text)
                .iter()
                .any(|h| h.starts_with(section.as_str()))
            {
                wrong.push(format!("{}:{line}: {name}, \"{section}\"", doc.display()));
            }
        }
    }
    assert!(checked > 0, "no section citation found: the scan is broken");
    assert!(
        wrong.is_empty(),
        "cited sections that are no heading of their document (a heading must start with the \
         quoted text):\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_scanners_find_what_they_should() {
    let text = "see [a](docs/a.md#x) and `[b](not/this)`\n```\n[c](nor/this)\n```\n";
    assert_eq!(link_targets(text), vec![(1, "docs/a.md#x".to_string())]);
    assert_eq!(
        mentioned_documents("(docs/model.md 4.1), docs/x.svg, crates/docs/y.md."),
        vec![(1, "docs/model.md".to_string())]
    );
    assert_eq!(
        headings("# A b\n**Cold start** (x)\n- **Opt-in (issue 3).** y\nplain **not**\n"),
        vec!["A b", "Cold start", "Opt-in (issue 3)."]
    );
    assert_eq!(
        section_citations("(docs/model-choices.md, \"Shear drive\"; docs/a.md \"B c\")"),
        vec![
            (
                1,
                "docs/model-choices.md".to_string(),
                "Shear drive".to_string()
            ),
            (1, "docs/a.md".to_string(), "B c".to_string())
        ]
    );
}

/// The README's first code block holds the main job and the test command; `.ci/run` must run
/// exactly that test command (and nothing else that starts with `cargo test`).
#[test]
fn the_readme_test_command_is_what_ci_runs() {
    let readme = read(&root().join("README.md"));
    let block: Vec<&str> = readme
        .split("```")
        .nth(1)
        .expect("README.md opens with a code block")
        .lines()
        .skip(1)
        .collect();
    let command = |line: &str| line.split('#').next().unwrap_or("").trim().to_string();
    let readme_test: Vec<String> = block
        .iter()
        .map(|l| command(l))
        .filter(|c| c.starts_with("cargo test"))
        .collect();
    assert_eq!(
        readme_test,
        ["cargo test --release"],
        "the README's test command"
    );
    assert!(
        command(block[0]).starts_with("cargo run --release -- sweep run sweeps/quickstart.toml"),
        "the README's first command is the main job: {}",
        block[0]
    );
    let ci = read(&root().join(".ci/run"));
    let ci_test: Vec<String> = ci
        .lines()
        .map(command)
        .filter(|c| c.starts_with("cargo test"))
        .collect();
    assert_eq!(
        ci_test, readme_test,
        ".ci/run must run the README's test command"
    );
}
