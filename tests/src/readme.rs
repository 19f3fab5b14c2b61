//! The README's quoted figures held to what the commands produce today: every block
//! marked `<!-- figure: ID -->` in README.md is compared, line by line, with the output
//! of the command that produces it ([`crate::figures`]), in the test that computes the
//! figure (so each heavy figure runs once per test run). A change of behaviour that moves
//! a figure fails there until the README says the new one; `UPDATE_README=1 cargo test
//! --release -p tests` writes today's outputs into the blocks, to review.
use crate::repo;

/// Every figure of the README and the test file that checks it (`tests/tests/FILE`).
pub const FIGURES: [(&str, &str); 16] = [
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
];

/// The fenced block right after the marker `<!-- figure: id -->`.
pub fn block(readme: &str, id: &str) -> String {
    let marker = format!("<!-- figure: {id} -->");
    let at = readme
        .find(&marker)
        .unwrap_or_else(|| panic!("README.md has no `{marker}`"));
    let mut lines = readme[at + marker.len()..]
        .lines()
        .skip_while(|l| !l.starts_with("```"))
        .skip(1);
    let body: Vec<&str> = lines.by_ref().take_while(|l| *l != "```").collect();
    body.join("\n")
}

/// Tests run in parallel threads; the rewrite of README.md is one at a time.
static README_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// `UPDATE_README=1`: put today's output into the block instead of failing (then review
/// the diff of README.md and commit it: the figures are claims).
pub fn rewrite(readme: &str, id: &str, want: &str) -> String {
    let marker = format!("<!-- figure: {id} -->");
    let at = readme.find(&marker).expect("marker present") + marker.len();
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

/// Hold the README's figure `id` to `want` (the command's output today): fail with both
/// when they differ; with `UPDATE_README=1`, write `want` into the block instead.
pub fn same(id: &str, want: &str) {
    let path = repo().join("README.md");
    if std::env::var_os("UPDATE_README").is_some() {
        let _guard = README_LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let readme = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, rewrite(&readme, id, want)).unwrap();
        return;
    }
    let readme = std::fs::read_to_string(&path).unwrap();
    let have = block(&readme, id);
    let norm = |s: &str| {
        s.lines()
            .map(str::trim_end)
            .collect::<Vec<_>>()
            .join("\n")
            .trim()
            .to_string()
    };
    assert_eq!(
        norm(&have),
        norm(want),
        "README.md's figure `{id}` is not what the command gives today; update the README (or the regression):\n--- README\n{have}\n--- now\n{want}"
    );
}
