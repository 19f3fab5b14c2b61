//! The README's figures that no other test computes are checked here, and the check
//! itself: every figure of README.md is held by one test (`tests::readme::FIGURES`), and
//! the block rewriting changes nothing else. See `tests::readme` for `UPDATE_README=1`.
use tests::readme::{block, rewrite, same, FIGURES};
use tests::{figures, repo};

/// The demo's run: its comparison of the paper's models, the plan beside the paper test,
/// and the head of the plan's program.
#[test]
fn demo_table() {
    let d = figures::demo_run();
    same("demo", &d.table);
    same("demo-plan", &d.plan);
    same("demo-plan-program", &d.program_head);
}

#[test]
fn cats_tag_diagnosis() {
    same("cats-tag", &figures::cats_tag());
}

#[test]
#[ignore = "full tier (cargo xtask test --full): the three real recordings diagnosed, 45 s"]
fn real_recordings_diagnosed() {
    same("real-recordings", &figures::real_recordings().1);
}

#[test]
#[ignore = "full tier (cargo xtask test --full): the long blind suite, 17 min on 2 cores"]
fn blind_long_suite() {
    same("blind-long", &figures::blind_long());
}

/// Every figure marker of README.md is in the registry, and the test file the registry
/// names holds it to its command (`same("ID"`): no figure goes unchecked.
#[test]
fn every_figure_is_checked_by_one_test() {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let mut ids: Vec<&str> = readme
        .lines()
        .filter_map(|l| l.strip_prefix("<!-- figure: ")?.strip_suffix(" -->"))
        .collect();
    let mut known: Vec<&str> = FIGURES.iter().map(|(id, _)| *id).collect();
    ids.sort_unstable();
    known.sort_unstable();
    assert_eq!(
        ids, known,
        "README.md's figures against tests::readme::FIGURES"
    );
    for (id, file) in FIGURES {
        let text = std::fs::read_to_string(repo().join("tests/tests").join(file)).unwrap();
        assert!(
            text.contains(&format!("same(\"{id}\"")),
            "tests/tests/{file} does not check the README figure `{id}`"
        );
    }
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
