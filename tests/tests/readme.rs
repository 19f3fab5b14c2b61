//! The figures of the README and the book that no other test computes are checked here,
//! and the check itself: every figure of README.md and docs/*.md is held by one test
//! (`tests::readme::FIGURES`), each marked in one file, once, and the block rewriting
//! changes nothing else. See `tests::readme` for `UPDATE_README=1`.
use tests::readme::{block, documents, holder, holder_in, markers, rewrite, same, FIGURES};
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

/// Every figure marker of README.md and docs/*.md is in the registry, once, in one file
/// (`holder` finds it), and the test file the registry names holds it to its command
/// (`same("ID"`): no figure goes unchecked.
#[test]
fn every_figure_is_checked_by_one_test() {
    let texts: Vec<String> = documents()
        .iter()
        .map(|p| std::fs::read_to_string(p).unwrap())
        .collect();
    assert!(texts.len() > 1, "README.md and the book's chapters");
    let mut ids: Vec<&str> = texts.iter().flat_map(|t| markers(t)).collect();
    let mut known: Vec<&str> = FIGURES.iter().map(|(id, _)| *id).collect();
    ids.sort_unstable();
    known.sort_unstable();
    assert_eq!(
        ids, known,
        "the figures of README.md and docs/*.md against tests::readme::FIGURES"
    );
    for (id, _) in FIGURES {
        let (path, text) = holder(id).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            !block(&text, id).is_empty(),
            "{path:?}: the figure `{id}` has no fenced block after its marker"
        );
    }
    for (id, file) in FIGURES {
        let text = std::fs::read_to_string(repo().join("tests/tests").join(file)).unwrap();
        assert!(
            text.contains(&format!("same(\"{id}\"")),
            "tests/tests/{file} does not check the figure `{id}`"
        );
    }
}

#[test]
fn the_check_can_fail() {
    let readme = "x\n<!-- figure: t -->\n```text\na  \nb\n```\n<!-- figure: e -->\n```\n```\n";
    assert_eq!(block(readme, "t"), "a  \nb");
    assert_eq!(block(readme, "e"), "");
    // a mention of the marker in prose is not the marker
    let mentioned = "see `<!-- figure: t -->`\n<!-- figure: t -->\n```\nreal\n```\n";
    assert_eq!(block(mentioned, "t"), "real");
    assert_eq!(block(&rewrite(mentioned, "t", "new"), "t"), "new");
    // a figure is found in whichever file holds it, and only when exactly one does, once
    let file = |name: &str, text: &str| (std::path::PathBuf::from(name), text.to_string());
    let docs = vec![file("README.md", "no figures"), file("docs/a.md", readme)];
    let (path, text) = holder_in(docs.clone(), "t").unwrap();
    assert_eq!(
        (path.to_str(), block(&text, "t").as_str()),
        (Some("docs/a.md"), "a  \nb")
    );
    let none = holder_in(docs.clone(), "absent").unwrap_err();
    assert!(none.contains("no `<!-- figure: absent -->`"), "{none}");
    let mut two = docs.clone();
    two.push(file("docs/b.md", readme));
    let err = holder_in(two, "t").unwrap_err();
    assert!(
        err.contains("marked 2 times") && err.contains("docs/b.md"),
        "{err}"
    );
    let twice = format!("{readme}{readme}");
    let err = holder_in(vec![file("docs/c.md", &twice)], "e").unwrap_err();
    assert!(err.contains("marked 2 times"), "{err}");
}

#[test]
fn rewriting_a_block_with_its_own_text_changes_nothing_else() {
    let mut seen = 0;
    for path in documents() {
        let readme = std::fs::read_to_string(&path).unwrap();
        for id in markers(&readme) {
            seen += 1;
            assert_eq!(
                rewrite(&readme, id, &block(&readme, id)),
                readme,
                "{path:?}: block {id}"
            );
            let changed = rewrite(&readme, id, "x");
            assert_eq!(block(&changed, id), "x");
            assert_eq!(
                rewrite(&changed, id, &block(&readme, id)),
                readme,
                "{path:?}: block {id} back"
            );
        }
    }
    assert_eq!(seen, FIGURES.len(), "figure markers found");
    // An empty block must not swallow the block after it.
    let two = "<!-- figure: a -->\n```text\n```\n\n<!-- figure: b -->\n```text\nB\n```\n";
    let filled = rewrite(two, "a", "A");
    assert_eq!(block(&filled, "a"), "A");
    assert_eq!(block(&filled, "b"), "B");
    assert_eq!(rewrite(two, "a", ""), two);
}
