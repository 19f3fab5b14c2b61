//! The paper's experiment on the twin (`host-fit demo`) and the paper's own tables
//! (`temp-fit` against Table 3).
use crate::{cli_json, repo};

/// `host-fit demo --seed 1`: the table it prints.
pub fn demo_table() -> String {
    demo_run().table
}

/// What the README quotes of one `host-fit demo --seed 1` run.
pub struct DemoRun {
    /// The first paragraph: the models' table, the data's choice, the verdicts.
    pub table: String,
    /// The second: the candidate plans, the choice, the paper test beside the plan.
    pub plan: String,
    /// The first lines of the plan's program (`plan.csv`) and its row count.
    pub program_head: String,
}

/// `host-fit demo --seed 1` (the shared run, [`crate::demo`]): its printed paragraphs
/// and the head of the program it writes.
pub fn demo_run() -> DemoRun {
    let d = crate::demo::demo();
    let mut paras = d.out.split("\n\n");
    let table = paras.next().unwrap_or("").trim_end().to_string();
    let plan = paras.next().unwrap_or("").trim_end().to_string();
    let program = std::fs::read_to_string(d.dir.join("plan.csv")).unwrap();
    let n = program.lines().count();
    let mut program_head: Vec<String> = program.lines().take(13).map(String::from).collect();
    program_head.push(format!("... ({n} lines in all)"));
    DemoRun {
        table,
        plan,
        program_head: program_head.join("\n"),
    }
}

/// `temp-fit` on the paper's Tables 1-2 (pwl, relative) against its Table 3: the
/// largest relative difference over the 24 coefficients, and the line quoting it.
pub fn golden_table3() -> (f64, String) {
    let tables = repo().join("testdata/paper/paper-tables.csv");
    let j = cli_json(&[
        "temp-fit",
        tables.to_str().unwrap(),
        "--model",
        "pwl",
        "--relative",
        "--json",
    ]);
    let iv = j["intervals"].as_array().unwrap();
    let text = std::fs::read_to_string(repo().join("testdata/paper/paper-table3.csv")).unwrap();
    let mut worst: f64 = 0.0;
    let mut n = 0;
    for l in text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("coefficient"))
    {
        let f: Vec<&str> = l.split(',').collect();
        for (k, col) in [(0, 2), (1, 3)] {
            let want: f64 = f[col].parse().unwrap();
            let got = iv[k]["coefficients"][f[0]]
                .as_f64()
                .unwrap_or_else(|| panic!("{} missing", f[0]));
            worst = worst.max(((got - want) / want).abs());
            n += 1;
        }
    }
    (
        worst,
        format!(
            "Table 3 reproduced: largest relative difference {worst:.1e} over {n} coefficients"
        ),
    )
}
