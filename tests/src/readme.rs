//! The quoted figures of the README and the book held to what the commands produce
//! today: every block marked `<!-- figure: ID -->` in README.md or a chapter of the book
//! (`docs/*.md`) is compared, line by line, with the output of the command that produces
//! it ([`crate::figures`]), in the test that computes the figure (so each heavy figure
//! runs once per test run). Each marker is in exactly one of those files ([`holder`]
//! finds it). A change of behaviour that moves a figure fails there until the text says
//! the new one; `UPDATE_README=1 cargo test --release -p tests -- --include-ignored`
//! writes today's outputs into the blocks of whichever files hold them, to review (the
//! heavy figures are in the full tier: `#[ignore = "full tier ..."]`).
use crate::repo;
use std::path::PathBuf;

/// Every figure of the README and the book, and the test file that checks it
/// (`tests/tests/FILE`).
pub const FIGURES: [(&str, &str); 17] = [
    ("demo", "readme.rs"),
    ("coverage", "production.rs"),
    ("model-choice", "production.rs"),
    ("ggir-wrist", "production.rs"),
    ("imucal", "production.rs"),
    ("physics-blob", "diagnose.rs"),
    ("time-true", "time_true.rs"),
    ("blind-long", "readme.rs"),
    ("real-recordings", "readme.rs"),
    ("cats-tag", "readme.rs"),
    ("golden", "golden_paper.rs"),
    ("sweep", "sweep.rs"),
    ("plan-candidates", "plan.rs"),
    ("plan-done", "plan_done.rs"),
    ("demo-plan", "readme.rs"),
    ("demo-plan-program", "readme.rs"),
    ("discovered-flight", "discovered_flight.rs"),
];

/// The files that may hold figures: README.md and every `docs/*.md`, in name order.
pub fn documents() -> Vec<PathBuf> {
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repo().join("docs"))
        .expect("the docs/ folder")
        .map(|e| e.expect("a docs/ entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    docs.sort();
    docs.insert(0, repo().join("README.md"));
    docs
}

/// The ids of the figure markers of a text, in order: the lines that are
/// `<!-- figure: ID -->` and nothing else.
pub fn markers(text: &str) -> Vec<&str> {
    text.lines()
        .filter_map(|l| l.strip_prefix("<!-- figure: ")?.strip_suffix(" -->"))
        .collect()
}

/// The one file of [`documents`] that holds figure `id`, and its text: an error naming
/// the files when none holds it, or when it is marked more than once.
pub fn holder(id: &str) -> Result<(PathBuf, String), String> {
    let texts = documents()
        .into_iter()
        .map(|p| match std::fs::read_to_string(&p) {
            Ok(text) => Ok((p, text)),
            Err(e) => Err(format!("{p:?}: {e}")),
        })
        .collect::<Result<Vec<_>, String>>()?;
    holder_in(texts, id)
}

/// The one of these files (path, text) that holds figure `id`, marked once: an error
/// naming the files when none holds it, or when it is marked more than once.
pub fn holder_in(texts: Vec<(PathBuf, String)>, id: &str) -> Result<(PathBuf, String), String> {
    let mut holding: Vec<(PathBuf, String, usize)> = texts
        .into_iter()
        .map(|(p, text)| {
            let times = markers(&text).iter().filter(|m| **m == id).count();
            (p, text, times)
        })
        .filter(|(_, _, times)| *times > 0)
        .collect();
    let times: usize = holding.iter().map(|(_, _, n)| n).sum();
    match times {
        1 => {
            let (path, text, _) = holding.remove(0);
            Ok((path, text))
        }
        0 => Err(format!(
            "no `<!-- figure: {id} -->` in README.md or docs/*.md"
        )),
        _ => {
            let files: Vec<_> = holding.iter().map(|(p, _, _)| p).collect();
            Err(format!(
                "`<!-- figure: {id} -->` is marked {times} times, in {files:?}: one file holds each figure, once"
            ))
        }
    }
}

/// Where the line `<!-- figure: id -->` of a text ends (the marker on a line of its own,
/// not a mention of it in prose).
fn after_marker(text: &str, id: &str) -> Option<usize> {
    let marker = format!("<!-- figure: {id} -->");
    let mut at = 0;
    for line in text.split_inclusive('\n') {
        if line.trim_end_matches(['\n', '\r']) == marker {
            return Some(at + marker.len());
        }
        at += line.len();
    }
    None
}

/// The fenced block right after the marker `<!-- figure: id -->` in a text (the text of
/// the file that holds it).
pub fn block(readme: &str, id: &str) -> String {
    let at = after_marker(readme, id)
        .unwrap_or_else(|| panic!("no line `<!-- figure: {id} -->` in the text"));
    let mut lines = readme[at..]
        .lines()
        .skip_while(|l| !l.starts_with("```"))
        .skip(1);
    let body: Vec<&str> = lines.by_ref().take_while(|l| *l != "```").collect();
    body.join("\n")
}

/// Tests run in parallel threads; the rewrite of a file's figures is one at a time.
static README_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// `UPDATE_README=1`: put today's output into the block of a text instead of failing
/// (then review the diff of the file and commit it: the figures are claims).
pub fn rewrite(readme: &str, id: &str, want: &str) -> String {
    let at = after_marker(readme, id).expect("marker present");
    let open = at
        + readme[at..]
            .find("```")
            .expect("a fenced block after the marker");
    let body = open + readme[open..].find('\n').expect("a line after the fence") + 1;
    // An empty block closes on the line right after its fence.
    let close = if readme[body..].starts_with("```") {
        body
    } else {
        body + readme[body..]
            .find("\n```\n")
            .map(|i| i + 1)
            .expect("the fenced block is closed")
    };
    let want = want.trim_end();
    let sep = if want.is_empty() { "" } else { "\n" };
    format!("{}{want}{sep}{}", &readme[..body], &readme[close..])
}

/// Hold the figure `id` (in README.md or a `docs/*.md` chapter, whichever holds it) to
/// `want` (the command's output today): fail with both when they differ; with
/// `UPDATE_README=1`, write `want` into that file's block instead.
pub fn same(id: &str, want: &str) {
    if std::env::var_os("UPDATE_README").is_some() {
        let _guard = README_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let (path, text) = holder(id).unwrap_or_else(|e| panic!("{e}"));
        std::fs::write(&path, rewrite(&text, id, want)).unwrap();
        return;
    }
    let (path, text) = holder(id).unwrap_or_else(|e| panic!("{e}"));
    let have = block(&text, id);
    let norm = |s: &str| {
        s.lines()
            .map(str::trim_end)
            .collect::<Vec<_>>()
            .join("\n")
            .trim()
            .to_string()
    };
    let file = path.strip_prefix(repo()).unwrap_or(&path).display();
    assert_eq!(
        norm(&have),
        norm(want),
        "{file}'s figure `{id}` is not what the command gives today; update it (or the regression):\n--- {file}\n{have}\n--- now\n{want}"
    );
}
