//! The README's quoted figures are the ones the commands produce today: every block
//! marked `<!-- figure: ID -->` in README.md is compared, line by line, with the output
//! of the command that produces it (`tests::figures`). A change of behaviour that moves
//! a figure fails here until the README says the new one (`UPDATE_README=1 cargo test
//! --release -p tests --test readme` writes today's outputs into the blocks, to review).
use tests::{figures, repo};

/// The fenced block right after the marker `<!-- figure: id -->`.
fn block(readme: &str, id: &str) -> String {
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
fn rewrite(readme: &str, id: &str, want: &str) -> String {
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

fn same(id: &str, want: &str) {
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

#[test]
fn demo_table() {
    same("demo", &figures::demo_table());
}

#[test]
fn golden_table3() {
    same("golden", &figures::golden_table3().1);
}

#[test]
fn physics_blob() {
    same("physics-blob", &figures::physics_blob().2);
}

#[test]
fn time_true_diagnosed_blobs() {
    same("time-true", &tests::time_true::table().1);
}

#[test]
fn cats_tag_diagnosis() {
    same("cats-tag", &figures::cats_tag());
}

#[test]
fn real_recordings_diagnosed() {
    same("real-recordings", &figures::real_recordings().1);
}

#[test]
fn blind_long_suite() {
    same("blind-long", &figures::blind_long());
}

#[test]
fn model_choice_against_plain_least_squares() {
    same("model-choice", &figures::model_choice().1);
}

#[test]
fn coverage_of_the_predicted_error() {
    same("coverage", &figures::coverage().1);
}

#[test]
fn ggir_wrist_held_out() {
    same("ggir-wrist", &figures::ggir_wrist().2);
}

#[test]
fn imucal_one_temperature() {
    same("imucal", &figures::imucal().1);
}

#[test]
fn the_check_can_fail() {
    let readme = "x\n<!-- figure: t -->\n```text\na  \nb\n```\n<!-- figure: e -->\n```\n```\n";
    assert_eq!(block(readme, "t"), "a  \nb");
    assert_eq!(block(readme, "e"), "");
}

#[test]
fn rewriting_a_block_with_its_own_text_changes_nothing_else() {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let ids: Vec<&str> = readme
        .lines()
        .filter_map(|l| l.strip_prefix("<!-- figure: ")?.strip_suffix(" -->"))
        .collect();
    assert!(ids.len() >= 9, "figure markers found: {ids:?}");
    for id in ids {
        assert_eq!(
            rewrite(&readme, id, &block(&readme, id)),
            readme,
            "block {id}"
        );
        let changed = rewrite(&readme, id, "x");
        assert_eq!(block(&changed, id), "x");
        assert_eq!(
            rewrite(&changed, id, &block(&readme, id)),
            readme,
            "block {id} back"
        );
    }
    // An empty block must not swallow the block after it.
    let two = "<!-- figure: a -->\n```text\n```\n\n<!-- figure: b -->\n```text\nB\n```\n";
    let filled = rewrite(two, "a", "A");
    assert_eq!(block(&filled, "a"), "A");
    assert_eq!(block(&filled, "b"), "B");
    assert_eq!(rewrite(two, "a", ""), two);
}
