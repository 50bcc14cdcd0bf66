//! Every citation of a section of docs/model.md names a section that exists there.
//!
//! A citation is the document's path followed by a section number, "docs/model.md 3.2", also
//! with "section" or "Sec." before the number, across a line break (a comment's marker on the
//! next line is skipped), and with further numbers joined by "and" or a comma ("4.1 and 6",
//! "2.1, 3.2"; after a comma a number of more than two leading digits is a count, not a
//! section: "docs/model.md 1, 1200 disks" cites section 1). A section
//! exists when a heading of docs/model.md starts with its number ("## 3. Capillary bridges",
//! "### 3.2 Thin-thread model"). The test reads every .rs, .md, .toml and .sh file under the
//! repository root, leaving out `target/` and `.git/`.
//!
//! The root is `CARGO_MANIFEST_DIR` as `cargo test` sets it at run time, so the built test can
//! also check another checkout:
//! `CARGO_MANIFEST_DIR=/path/to/checkout target/release/deps/model_doc-HASH`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The cited document, relative to the repository root.
const DOC: &str = "docs/model.md";
const EXTENSIONS: [&str; 4] = ["rs", "md", "toml", "sh"];

fn root() -> PathBuf {
    std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")))
}

/// Section numbers of the headings (`##` to `####`) of the document.
fn headings(doc: &str) -> BTreeSet<String> {
    doc.lines()
        .filter_map(|line| {
            let rest = line.trim_start_matches('#');
            let level = line.len() - rest.len();
            if !(2..=4).contains(&level) {
                return None;
            }
            let word = rest.strip_prefix(' ')?.split_whitespace().next()?;
            let number = word.strip_suffix('.').unwrap_or(word);
            is_section_number(number).then(|| number.to_string())
        })
        .collect()
}

fn is_section_number(s: &str) -> bool {
    !s.is_empty()
        && s.split('.')
            .all(|part| !part.is_empty() && part.bytes().all(|b| b.is_ascii_digit()))
}

/// A section number at the start of `s` (digits, dot-separated), not followed by a letter or
/// digit ("2D" is no section): the number and the rest.
fn leading_number(s: &str) -> Option<(&str, &str)> {
    let bytes = s.as_bytes();
    let digits_from = |mut i: usize| {
        while i < bytes.len() && bytes[i].is_ascii_digit() {
            i += 1;
        }
        i
    };
    let mut end = digits_from(0);
    if end == 0 {
        return None;
    }
    // A dot continues the number only when digits follow it ("7." ends a sentence).
    while end + 1 < bytes.len() && bytes[end] == b'.' && bytes[end + 1].is_ascii_digit() {
        end = digits_from(end + 1);
    }
    if bytes
        .get(end)
        .is_some_and(|b| b.is_ascii_alphanumeric() || *b == b'_')
    {
        return None;
    }
    Some((&s[..end], &s[end..]))
}

/// Skips blanks, at most one line break, and a comment marker after it.
fn skip_separator(s: &str) -> &str {
    let s = s.trim_start_matches([' ', '\t']);
    let Some(next_line) = s.strip_prefix('\n') else {
        return s;
    };
    let t = next_line.trim_start_matches([' ', '\t']);
    let t = ["//!", "///", "//", "#"]
        .iter()
        .find_map(|marker| t.strip_prefix(marker))
        .unwrap_or(t);
    t.trim_start_matches([' ', '\t'])
}

/// The section numbers cited in `text`.
fn cited_sections(text: &str) -> Vec<String> {
    let mut cited = Vec::new();
    for (at, _) in text.match_indices(DOC) {
        let mut rest = skip_separator(&text[at + DOC.len()..]);
        for word in ["sections ", "section ", "Sec. "] {
            if let Some(r) = rest.strip_prefix(word) {
                rest = r;
                break;
            }
        }
        let Some((number, mut after)) = leading_number(rest) else {
            continue;
        };
        cited.push(number.to_string());
        loop {
            let (r, comma) = match (after.strip_prefix(" and "), after.strip_prefix(", ")) {
                (Some(r), _) => (r, false),
                (None, Some(r)) => (r, true),
                (None, None) => break,
            };
            let Some((number, a)) = leading_number(r) else {
                break;
            };
            // After a comma only a plausible section ("4.1, 6"), not a count ("1, 1200 disks").
            if comma && number.split('.').next().is_some_and(|top| top.len() > 2) {
                break;
            }
            cited.push(number.to_string());
            after = a;
        }
    }
    cited
}

fn collect_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("directory entry").path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if name != "target" && name != ".git" {
                collect_files(&path, out);
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

/// The citations in `files` of sections missing from `sections`, as "file:line: number".
fn missing(root: &Path, files: &[PathBuf], sections: &BTreeSet<String>) -> Vec<String> {
    let mut found = Vec::new();
    for path in files {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let text = String::from_utf8_lossy(&bytes);
        for (at, _) in text.match_indices(DOC) {
            let line = text[..at].matches('\n').count() + 1;
            let tail = &text[at..];
            let end = tail
                .match_indices(DOC)
                .nth(1)
                .map_or(tail.len(), |(i, _)| i);
            for number in cited_sections(&tail[..end]) {
                if !sections.contains(&number) {
                    let rel = path.strip_prefix(root).unwrap_or(path);
                    found.push(format!("{}:{line}: {DOC} {number}", rel.display()));
                }
            }
        }
    }
    found
}

#[test]
fn every_cited_section_of_the_model_document_exists() {
    let root = root();
    let doc = std::fs::read_to_string(root.join(DOC))
        .unwrap_or_else(|e| panic!("{}: {e}", root.join(DOC).display()));
    let sections = headings(&doc);
    assert!(
        sections.contains("3.2") && sections.contains("8"),
        "headings of {DOC} not found: {sections:?}"
    );
    let mut files = Vec::new();
    collect_files(&root, &mut files);
    files.sort();
    let cited: usize = files
        .iter()
        .map(|p| cited_sections(&String::from_utf8_lossy(&std::fs::read(p).unwrap())).len())
        .sum();
    let missing = missing(&root, &files, &sections);
    assert!(
        missing.is_empty(),
        "{} of {cited} citations name a section that {DOC} has no heading for \
         (sections: {sections:?}):\n{}",
        missing.len(),
        missing.join("\n")
    );
}

#[test]
fn the_parser_finds_citations_and_headings() {
    let doc = "# Title\n## 1. Units\n### 1.2 Standard systems\n## 3. Bridges\n### 3.2 Thin thread\n\
               #### 7.6 Rules\ncode # 9 not a heading\n";
    let sections = headings(doc);
    let expected: BTreeSet<String> = ["1", "1.2", "3", "3.2", "7.6"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    assert_eq!(sections, expected);

    let text = format!(
        "see {DOC} 3.2; ({DOC} 4.1 and 6), {DOC}'s 2D system, {DOC} section 5, {DOC} 7.\n\
         ({DOC} 2.1, 3.2), {DOC} 6, B.5.6,\n\
         /// wrapped ({DOC}\n/// 8), the file {DOC} itself, {DOC} 2D, {DOC} 1, 1200 disks"
    );
    assert_eq!(
        cited_sections(&text),
        ["3.2", "4.1", "6", "5", "7", "2.1", "3.2", "6", "8", "1"]
    );

    // A citation of a section without a heading is reported with its file and line.
    let dir = std::env::temp_dir().join(format!("model_doc_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("cites.md");
    std::fs::write(&file, format!("fine: {DOC} 3.2\nbroken: {DOC} 9.1\n")).unwrap();
    let found = missing(&dir, &[file], &sections);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(found, [format!("cites.md:2: {DOC} 9.1")]);
}
