//! The link check of the README and the book: every relative Markdown link
//! `[text](target)` of README.md and docs/*.md must name a file that exists (relative to
//! the file that links), and a `#anchor` into a Markdown file one of its headings (the
//! anchor mdBook and GitHub make of it: [`slug`]). External links (a scheme such as
//! `https:` or `mailto:`) and links inside fenced code blocks or inline code are not
//! checked.
use std::path::{Component, Path, PathBuf};

/// Where the checked files are read from: the disk, or (in the tests) a few texts.
pub trait Files {
    /// Whether a file or folder exists at this (normalised) path.
    fn exists(&self, path: &Path) -> bool;
    /// The text of a file, when it can be read.
    fn read(&self, path: &Path) -> Option<String>;
}

/// The files on disk.
pub struct Disk;

impl Files for Disk {
    fn exists(&self, path: &Path) -> bool {
        path.exists()
    }
    fn read(&self, path: &Path) -> Option<String> {
        std::fs::read_to_string(path).ok()
    }
}

/// One link of a Markdown text: the line it is on (from 1) and its target as written.
#[derive(Debug, PartialEq, Eq)]
pub struct Link {
    /// The line of the `](`.
    pub line: usize,
    /// The destination, without its title or angle brackets.
    pub target: String,
}

/// The Markdown files the check reads: README.md and every docs/*.md, in name order.
pub fn documents(root: &Path) -> Result<Vec<PathBuf>, String> {
    let docs = root.join("docs");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&docs)
        .map_err(|e| format!("{}: {e}", docs.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    files.sort();
    files.insert(0, root.join("README.md"));
    Ok(files)
}

/// The text with what is not prose blanked out (fenced code blocks, inline code spans),
/// every line kept where it was, so a link's line and a heading stay where they are.
pub fn prose(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut fence: Option<(char, usize)> = None;
    let mut paragraph = String::new();
    for line in text.split_inclusive('\n') {
        let trimmed = line.trim_start();
        let run = |c: char| trimmed.chars().take_while(|x| *x == c).count();
        let opens = ['`', '~']
            .into_iter()
            .map(|c| (c, run(c)))
            .find(|(_, n)| *n >= 3);
        match (fence, opens) {
            (None, Some(f)) => {
                out.push_str(&blank_code(&std::mem::take(&mut paragraph)));
                fence = Some(f);
                out.push_str(&blank(line));
            }
            (Some((c, n)), Some((c2, n2)))
                if c == c2 && n2 >= n && trimmed[n2..].trim().is_empty() =>
            {
                fence = None;
                out.push_str(&blank(line));
            }
            (Some(_), _) => out.push_str(&blank(line)),
            (None, None) if line.trim().is_empty() => {
                out.push_str(&blank_code(&std::mem::take(&mut paragraph)));
                out.push_str(line);
            }
            (None, None) => paragraph.push_str(line),
        }
    }
    out.push_str(&blank_code(&paragraph));
    out
}

/// Everything but the line ends replaced by spaces.
fn blank(s: &str) -> String {
    s.chars()
        .map(|c| if c == '\n' { '\n' } else { ' ' })
        .collect()
}

/// A paragraph with its inline code spans blanked: a run of n backticks opens a span
/// that the next run of exactly n closes; a run never closed is a literal backtick.
fn blank_code(p: &str) -> String {
    let chars: Vec<char> = p.chars().collect();
    let run_at = |i: usize| chars[i..].iter().take_while(|c| **c == '`').count();
    let mut out = String::with_capacity(p.len());
    let mut i = 0;
    while i < chars.len() {
        if chars[i] != '`' {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let n = run_at(i);
        let mut j = i + n;
        let close = loop {
            match chars[j..].iter().position(|c| *c == '`') {
                None => break None,
                Some(k) if run_at(j + k) == n => break Some(j + k),
                Some(k) => j += k + run_at(j + k),
            }
        };
        let end = close.map_or(i + n, |c| c + n);
        let span: String = chars[i..end].iter().collect();
        if close.is_some() {
            out.push_str(&blank(&span));
        } else {
            out.push_str(&span);
        }
        i = end;
    }
    out
}

/// Every inline link and image of a Markdown text outside code: `[text](target)`,
/// `[text](target "title")`, `[text](<target>)`.
pub fn links(text: &str) -> Vec<Link> {
    let prose = prose(text);
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(k) = prose[from..].find("](") {
        let start = from + k + 2;
        let line = prose[..start].matches('\n').count() + 1;
        let rest = &prose[start..];
        let target = if let Some(inner) = rest.strip_prefix('<') {
            inner.split('>').next().unwrap_or_default().to_string()
        } else {
            let mut depth = 0usize;
            let end = rest
                .char_indices()
                .find(|(_, c)| match c {
                    '(' => {
                        depth += 1;
                        false
                    }
                    ')' if depth == 0 => true,
                    ')' => {
                        depth -= 1;
                        false
                    }
                    c => c.is_whitespace(),
                })
                .map_or(rest.len(), |(i, _)| i);
            rest[..end].to_string()
        };
        found.push(Link { line, target });
        from = start;
    }
    found
}

/// The anchor mdBook and GitHub give a heading: its text (a link's or code's text
/// included, their markup not) lowercased, each space a `-`, every other character but
/// letters, digits, `-` and `_` dropped.
pub fn slug(heading: &str) -> String {
    let mut text = String::new();
    let mut rest = heading;
    // a link in a heading counts with its text only
    while let Some(open) = rest.find('[') {
        let Some(mid) = rest[open..].find("](").map(|m| open + m) else {
            break;
        };
        let Some(close) = rest[mid..].find(')').map(|c| mid + c) else {
            break;
        };
        text.push_str(&rest[..open]);
        text.push_str(&rest[open + 1..mid]);
        rest = &rest[close + 1..];
    }
    text.push_str(rest);
    text.trim()
        .chars()
        .filter_map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' {
                Some(c.to_lowercase().collect::<String>())
            } else if c.is_whitespace() {
                Some("-".to_string())
            } else {
                None
            }
        })
        .collect()
}

/// The anchors of a Markdown text's headings (`#` to `######`, outside code blocks), a
/// repeated one numbered as mdBook and GitHub do (`name`, `name-1`, `name-2`).
pub fn anchors(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let masked = prose(text);
    for (line, shown) in text.lines().zip(masked.lines()) {
        let t = shown.trim_start();
        if shown.len() - t.len() > 3 {
            continue;
        }
        let hashes = t.chars().take_while(|c| *c == '#').count();
        let after = &line.trim_start()[hashes.min(line.trim_start().len())..];
        if !(1..=6).contains(&hashes) || !(after.is_empty() || after.starts_with([' ', '\t'])) {
            continue;
        }
        let title = after.trim().trim_end_matches('#').trim_end();
        let base = slug(title);
        let mut name = base.clone();
        let mut n = 0;
        while out.contains(&name) {
            n += 1;
            name = format!("{base}-{n}");
        }
        out.push(name);
    }
    out
}

/// A path with `.` and `..` resolved by its words alone (the docs hold no symlinks).
fn normal(p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if out.file_name().is_some() => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// Whether a target names another scheme (`https:`, `mailto:`): not a file here.
fn external(target: &str) -> bool {
    target.split_once(':').is_some_and(|(scheme, _)| {
        scheme.len() > 1
            && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
            && scheme
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    })
}

/// Every broken link of one Markdown file, as `FILE:LINE: target: why`.
pub fn broken(file: &Path, text: &str, files: &dyn Files, shown: &Path) -> Vec<String> {
    let dir = file.parent().unwrap_or(Path::new(""));
    let mut out = Vec::new();
    for Link { line, target } in links(text) {
        if external(&target) {
            continue;
        }
        let (path, anchor) = target.split_once('#').unwrap_or((&target, ""));
        let to = if path.is_empty() {
            file.to_path_buf()
        } else {
            normal(&dir.join(path))
        };
        let why = if target.is_empty() {
            Some("an empty link".to_string())
        } else if !files.exists(&to) {
            Some(format!("no such file ({})", to.display()))
        } else if anchor.is_empty() || to.extension().is_none_or(|x| x != "md") {
            None
        } else {
            let heads = files.read(&to).map(|t| anchors(&t)).unwrap_or_default();
            (!heads.iter().any(|h| h == anchor))
                .then(|| format!("no heading with the anchor `#{anchor}` in {}", to.display()))
        };
        if let Some(why) = why {
            out.push(format!("{}:{line}: `{target}`: {why}", shown.display()));
        }
    }
    out
}

/// Check README.md and docs/*.md under `root`: how many links were checked, or every
/// broken one.
pub fn check(root: &Path) -> Result<usize, Vec<String>> {
    let files = documents(root).map_err(|e| vec![e])?;
    let mut bad = Vec::new();
    let mut n = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).map_err(|e| vec![format!("{}: {e}", f.display())])?;
        n += links(&text).len();
        bad.extend(broken(f, &text, &Disk, f.strip_prefix(root).unwrap_or(f)));
    }
    if bad.is_empty() {
        Ok(n)
    } else {
        // the files named relative to the repository, as the links are written
        let prefix = format!("{}/", root.display());
        Err(bad.iter().map(|b| b.replace(&prefix, "")).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// A few files in memory.
    struct Memory(HashMap<PathBuf, String>);

    impl Files for Memory {
        fn exists(&self, path: &Path) -> bool {
            self.0.contains_key(path) || self.0.keys().any(|k| k.starts_with(path))
        }
        fn read(&self, path: &Path) -> Option<String> {
            self.0.get(path).cloned()
        }
    }

    fn repo() -> Memory {
        let files = [
            ("README.md", "# Title\n\n## The two commands\n"),
            ("docs/a.md", "# A chapter\n\n## Setting up the line's server\n\n## Notes\n\n## Notes\n\n```c\n#include \"x.h\"\n```\n"),
            ("host-fit/src/lib.rs", "//! lib"),
        ];
        Memory(
            files
                .iter()
                .map(|(p, t)| (PathBuf::from(p), t.to_string()))
                .collect(),
        )
    }

    fn check_one(file: &str, text: &str) -> Vec<String> {
        broken(Path::new(file), text, &repo(), Path::new(file))
    }

    #[test]
    fn good_links_pass() {
        let text = "See [the README](../README.md#the-two-commands), [a](a.md),
[its server](a.md#setting-up-the-lines-server), [notes](a.md#notes-1), [here](#a-chapter),
[code](../host-fit/src/lib.rs), [folder](../host-fit/), ![img](<a.md> \"title\"),
[web](https://example.com/x.md), [mail](mailto:a@b.c).";
        assert_eq!(check_one("docs/a.md", text), Vec::<String>::new());
        assert_eq!(
            check_one(
                "README.md",
                "[chapter](docs/a.md#notes) [lib](./host-fit/src/lib.rs)"
            ),
            Vec::<String>::new()
        );
    }

    #[test]
    fn a_broken_file_link_and_a_broken_anchor_are_found() {
        let text = "Fine: [a](a.md).\nBroken: [gone](gone.md) and\n[anchor](a.md#no-such-heading), [self](#notes-2), [c](a.md#include-xh).";
        let bad = check_one("docs/a.md", text);
        assert_eq!(bad.len(), 4, "{bad:#?}");
        assert!(
            bad[0].starts_with("docs/a.md:2: `gone.md`: no such file (docs/gone.md)"),
            "{}",
            bad[0]
        );
        assert!(bad[1].starts_with("docs/a.md:3: `a.md#no-such-heading`: no heading with the anchor `#no-such-heading`"), "{}", bad[1]);
        assert!(bad[2].contains("`#notes-2`"), "{}", bad[2]);
        // a `#include` in a code block is no heading
        assert!(bad[3].contains("`#include-xh`"), "{}", bad[3]);
        // from the README, docs/ is one folder down, not beside it
        let bad = check_one("README.md", "[wrong](../docs/a.md) [empty]()");
        assert_eq!(bad.len(), 2, "{bad:#?}");
        assert!(bad[0].contains("no such file"), "{}", bad[0]);
        assert!(bad[1].contains("an empty link"), "{}", bad[1]);
    }

    #[test]
    fn code_is_not_checked() {
        let text = "```rust\nlet x = a[i](b);\nlet _ = [x](gone.md);\n```\n\nSee `[x](gone.md)` and ``a ` [y](gone.md)``.\n\n~~~\n[z](gone.md)\n~~~\n";
        assert_eq!(links(text), Vec::<Link>::new());
        let text = "a span over\ntwo lines: `[x](gone.md) and\nmore` then [real](real.md)";
        assert_eq!(
            links(text),
            [Link {
                line: 3,
                target: "real.md".into()
            }]
        );
    }

    #[test]
    fn anchors_are_the_slugs_of_headings() {
        assert_eq!(
            slug("Chamber and tilter program (`PLAN.csv`)"),
            "chamber-and-tilter-program-plancsv"
        );
        assert_eq!(
            slug("The chamber operator's procedure"),
            "the-chamber-operators-procedure"
        );
        assert_eq!(
            slug("firmware-core on a Cortex-M4F"),
            "firmware-core-on-a-cortex-m4f"
        );
        assert_eq!(slug("See [the blob](blob.md) now"), "see-the-blob-now");
        assert_eq!(
            anchors("# A\n## A\n    # indented code\n#nospace\n### B ###\n"),
            ["a", "a-1", "b"]
        );
    }
}
