//! The user guide as text: the README's size, links that resolve, every
//! page in the book's table of contents, and no history on user pages.
//! (The book itself is built, and its tutorials run, by scripts/test.sh.)

use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Every file under `dir` whose name ends with `ext`, sorted.
fn files(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.to_string_lossy().ends_with(ext) {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The text of `markdown` outside fenced code blocks, line by line.
fn prose_lines(markdown: &str) -> Vec<&str> {
    let mut fenced = false;
    let mut out = Vec::new();
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if !fenced {
            out.push(line);
        }
    }
    out
}

/// The blocks a reader sees as one paragraph: table cells one by one, list
/// items one by one, other text up to a blank line.
fn paragraphs(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut current = String::new();
    let flush = |current: &mut String, out: &mut Vec<String>| {
        if !current.trim().is_empty() {
            out.push(current.trim().to_string());
        }
        current.clear();
    };
    for line in prose_lines(markdown) {
        let trimmed = line.trim();
        if trimmed.starts_with('|') {
            flush(&mut current, &mut out);
            out.extend(trimmed.split('|').map(|c| c.trim().to_string()));
        } else if trimmed.is_empty() || trimmed.starts_with('#') {
            flush(&mut current, &mut out);
        } else if trimmed.starts_with("- ") || trimmed.starts_with("* ") {
            flush(&mut current, &mut out);
            current.push_str(trimmed);
        } else {
            current.push(' ');
            current.push_str(trimmed);
        }
    }
    flush(&mut current, &mut out);
    out
}

/// README.md reads in a few minutes: at most 12 000 bytes, no paragraph or
/// table cell over 800 characters, and its first commands are the set-up
/// and the test suite.
#[test]
fn readme_is_short() {
    let readme = read(&repo().join("README.md"));
    assert!(readme.len() <= 12_000, "README.md: {} bytes", readme.len());
    for p in paragraphs(&readme) {
        let n = p.chars().count();
        assert!(n <= 800, "README.md: a paragraph of {n} characters: {p}");
    }
    let first_block = readme
        .split("```")
        .nth(1)
        .expect("README.md has a code block");
    assert!(
        first_block
            .contains("bash scripts/setup.sh && target/release/ribbar run specs/r1-coarse.yaml")
            && first_block.contains("bash scripts/test.sh"),
        "README.md's first code block is the set-up and the test command: {first_block}"
    );
}

/// The pages a user reads: everything but the validation part, where
/// measurements and their history go.
fn user_pages() -> Vec<PathBuf> {
    let root = repo();
    let mut pages: Vec<PathBuf> = files(&root.join("docs/src"), ".md")
        .into_iter()
        .filter(|p| !p.starts_with(root.join("docs/src/validation")))
        .collect();
    for extra in [
        "README.md",
        "docs/architecture.md",
        "specs/README.md",
        "python/README.md",
    ] {
        pages.push(root.join(extra));
    }
    pages
}

/// A token that looks like an abbreviated or full commit hash: 7 to 40
/// hex digits with at least one digit and one letter.
fn is_commit_hash(token: &str) -> bool {
    (7..=40).contains(&token.len())
        && token
            .chars()
            .all(|c| c.is_ascii_digit() || ('a'..='f').contains(&c))
        && token.chars().any(|c| c.is_ascii_digit())
        && token.chars().any(|c| c.is_ascii_alphabetic())
}

const MONTHS: [&str; 12] = [
    "January",
    "February",
    "March",
    "April",
    "May",
    "June",
    "July",
    "August",
    "September",
    "October",
    "November",
    "December",
];

/// A date in `text`: an ISO date, a month named beside a year or a day, or
/// words that date a figure ("yesterday", "earlier the same day").
fn find_date(text: &str) -> Option<String> {
    let words: Vec<&str> = text
        .split(|c: char| !(c.is_alphanumeric() || c == '-'))
        .filter(|w| !w.is_empty())
        .collect();
    for (i, w) in words.iter().enumerate() {
        let parts: Vec<&str> = w.split('-').collect();
        if parts.len() == 3
            && parts[0].len() == 4
            && parts[1].len() == 2
            && parts[2].len() == 2
            && parts.iter().all(|p| p.chars().all(|c| c.is_ascii_digit()))
            && (parts[0].starts_with("19") || parts[0].starts_with("20"))
        {
            return Some(w.to_string());
        }
        if MONTHS.contains(w) {
            let is_day_or_year = |s: Option<&&str>| {
                s.is_some_and(|s| {
                    s.chars().all(|c| c.is_ascii_digit()) && (s.len() <= 2 || s.len() == 4)
                })
            };
            if is_day_or_year(words.get(i + 1)) || (i > 0 && is_day_or_year(words.get(i - 1))) {
                return Some(format!(
                    "{} {w}",
                    words.get(i.wrapping_sub(1)).unwrap_or(&"")
                ));
            }
        }
    }
    let lower = text.to_lowercase();
    [
        "yesterday",
        "earlier the same day",
        "this morning",
        "last week",
    ]
    .iter()
    .find(|p| lower.contains(*p))
    .map(|p| p.to_string())
}

/// No user page names a commit or a date: figures with their history
/// belong to the validation part, which says what version they ran on.
#[test]
fn user_pages_have_no_commit_hashes_or_dates() {
    let mut found = Vec::new();
    for page in user_pages() {
        let text = read(&page);
        for (n, line) in text.lines().enumerate() {
            for token in line.split(|c: char| !c.is_ascii_alphanumeric()) {
                if is_commit_hash(token) {
                    found.push(format!("{}:{}: {token}", page.display(), n + 1));
                }
            }
            if let Some(date) = find_date(line) {
                found.push(format!("{}:{}: {date}", page.display(), n + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "history on user pages:\n{}",
        found.join("\n")
    );
}

/// The checks above can fail: they see a hash and dates where there are.
#[test]
fn hashes_and_dates_are_recognised() {
    assert!(is_commit_hash("e239e8a"));
    assert!(!is_commit_hash("1234567") && !is_commit_hash("defaced") && !is_commit_hash("e239"));
    assert!(find_date("measured on 2026-11-01").is_some());
    assert!(find_date("run on 3 March, 40 s").is_some());
    assert!(find_date("in March 2024").is_some());
    assert!(find_date("earlier the same day it took 49 s").is_some());
    assert!(find_date("May the solve converge: 0.4 mm, 2.5 MPa").is_none());
}

/// `path` with `.` and `..` resolved, without touching the file system.
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

/// The targets of the Markdown links and images of `markdown`, and of its
/// `src="…"` attributes, outside code.
fn link_targets(markdown: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in prose_lines(markdown) {
        // Inline code may show link syntax without being a link.
        let line: String = line.split('`').step_by(2).collect::<Vec<_>>().join("");
        let mut rest = line.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let end = after.find(')').unwrap_or(after.len());
            out.push(
                after[..end]
                    .split_whitespace()
                    .next()
                    .unwrap_or("")
                    .to_string(),
            );
            rest = &after[end..];
        }
        let mut rest = line.as_str();
        while let Some(i) = rest.find("src=\"") {
            let after = &rest[i + 5..];
            let end = after.find('"').unwrap_or(after.len());
            out.push(after[..end].to_string());
            rest = &after[end..];
        }
    }
    out
}

/// The anchors mdBook gives the headings of `markdown`.
fn anchors(markdown: &str) -> BTreeSet<String> {
    prose_lines(markdown)
        .into_iter()
        .filter_map(|l| l.strip_prefix('#'))
        .map(|h| {
            h.trim_start_matches('#')
                .trim()
                .to_lowercase()
                .chars()
                .filter_map(|c| match c {
                    ' ' => Some('-'),
                    c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                    _ => None,
                })
                .collect()
        })
        .collect()
}

/// Every relative link of the README and the book resolves: to a file
/// inside the book for its pages (the built book holds nothing else), to
/// a heading that exists for a `#anchor`.
#[test]
fn internal_links_resolve() {
    let root = repo();
    let book = root.join("docs/src");
    let mut pages = files(&book, ".md");
    pages.push(root.join("README.md"));
    let mut broken = Vec::new();
    for page in &pages {
        let text = read(page);
        for target in link_targets(&text) {
            if target.is_empty() || target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (file, anchor) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let resolved = if file.is_empty() {
                page.clone()
            } else {
                normalise(&page.parent().unwrap().join(file))
            };
            let inside_book = !page.starts_with(&book) || resolved.starts_with(&book);
            if !resolved.is_file() || !inside_book {
                broken.push(format!("{}: {target}", page.display()));
                continue;
            }
            if let Some(anchor) = anchor {
                if resolved.extension().is_some_and(|e| e == "md")
                    && !anchors(&read(&resolved)).contains(anchor)
                {
                    broken.push(format!("{}: {target} (no such heading)", page.display()));
                }
            }
        }
    }
    assert!(
        broken.is_empty(),
        "links that do not resolve:\n{}",
        broken.join("\n")
    );
}

/// Every page of docs/src is in the book's table of contents, and every
/// entry there is a page: a page left out would not be built.
#[test]
fn every_page_is_in_the_summary() {
    let book = repo().join("docs/src");
    let summary = read(&book.join("SUMMARY.md"));
    let listed: BTreeSet<PathBuf> = link_targets(&summary)
        .into_iter()
        .map(|t| book.join(t))
        .collect();
    for entry in &listed {
        assert!(
            entry.is_file(),
            "SUMMARY.md lists {} that does not exist",
            entry.display()
        );
    }
    for page in files(&book, ".md") {
        if page.file_name().is_some_and(|n| n == "SUMMARY.md") {
            continue;
        }
        assert!(
            listed.contains(&page),
            "{} is not in SUMMARY.md",
            page.display()
        );
    }
}
