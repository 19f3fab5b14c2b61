//! `cargo xtask book`: the manual under docs/ built with mdbook (`mdbook build docs`, into
//! target/book/) and every relative link of README.md and docs/*.md checked (`links`);
//! mdbook is installed from crates.io when missing. Also a step of `cargo xtask test`.
use crate::Steps;
use std::process::Command;

/// The step's name in the table.
const STEP: &str = "book (mdbook build, links checked)";

/// Install mdbook when missing, then build the book and check its links, one step.
pub fn book(s: &mut Steps) {
    if s.prepare("install mdbook", crate::setup::mdbook).is_none() {
        s.skip(STEP, "no mdbook");
        return;
    }
    let _ = s.step(STEP, build_and_check);
}

/// `mdbook build docs`, then the link check: the number of links checked, or what broke.
fn build_and_check() -> Result<(), String> {
    let root = crate::root();
    crate::sh(Command::new("mdbook").arg("build").arg(root.join("docs")))?;
    match crate::links::check(&root) {
        Ok(n) => {
            eprintln!(
                "book: {} written; {n} links of README.md and docs/*.md checked, none broken",
                root.join("target/book/index.html").display()
            );
            Ok(())
        }
        Err(bad) => Err(format!(
            "{} broken links (a file that is not there, relative to the file that links, or an anchor that is no heading of its file): fix the link or the heading:\n{}",
            bad.len(),
            bad.join("\n")
        )),
    }
}
