//! The house rules of host-fit's source, checked like rust-analyzer's tidy test: modules
//! import one way (each layer uses only its own layer and those below, and no file module
//! imports in a circle), every module says what it is for, no function is longer than
//! [`MAX_FN_LINES`] lines of code (host-fit's sources, tests and benches, and the `tests`
//! crate), the command line's parser stays in `cli`, the library reads no environment,
//! and a closed set is matched exhaustively (no `_ =>` beside its variants).
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest function body allowed, in lines of code (blank and comment lines not counted).
const MAX_FN_LINES: usize = 120;

/// The layers of lib.rs's table: a module may use modules of its own rank or below.
const LAYERS: [(&str, u8); 25] = [
    ("error", 0),
    ("rng", 0),
    ("output", 0),
    ("progress", 0),
    ("data", 1),
    ("terms", 1),
    ("fit", 2),
    ("simulate", 2),
    ("blob", 3),
    ("verify", 3),
    ("vectors", 3),
    ("acceptance", 3),
    ("diagnose", 4),
    ("analysis", 5),
    ("blind", 5),
    ("plan", 5),
    ("store", 5),
    ("report", 6),
    ("batch", 6),
    ("demo", 6),
    ("demo_plan", 6),
    ("cli", 7),
    ("lib", 8),
    ("main", 8),
    ("", 8),
];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every folder whose functions the length rule covers: host-fit's sources, tests and
/// benches, and the end-to-end `tests` crate.
fn all_code() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    vec![
        root.join("src"),
        root.join("tests"),
        root.join("benches"),
        root.join("../tests/src"),
        root.join("../tests/tests"),
    ]
}

/// The closed sets of host-fit: a `match` with arms of one of them must name every
/// variant (or group them), never fall through `_ =>`.
const CLOSED: [&str; 21] = [
    "EffectId::",
    "Extra::",
    "Term::",
    "Param::",
    "Verdict::",
    "NoteKind::",
    "Class::",
    "Form::",
    "OtherForm::",
    "Outside::",
    "Nuisance::",
    "Slow::",
    "Digital::",
    "Refixed::",
    "Mixture::",
    "Profile::",
    "UnitStatus::",
    "MethodArg::",
    "Route::",
    "Compensation::",
    "Grouping::",
];

/// Every `.rs` file under `dir`, with its module path (`fit/lsq.rs` -> `fit::lsq`).
fn files(dir: &Path) -> Vec<(String, PathBuf)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p.strip_prefix(dir).unwrap().with_extension("");
                let mut parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                if parts.last().is_some_and(|l| l == "mod") {
                    parts.pop();
                }
                out.push((parts.join("::"), p));
            }
        }
    }
    out.sort();
    out
}

/// The source with comments, strings and char literals blanked (lines kept), so braces
/// and paths are only the code's.
fn code_only(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    let blank = |out: &mut Vec<u8>, c: u8| out.push(if c == b'\n' { b'\n' } else { b' ' });
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                blank(&mut out, b[i]);
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            while i < b.len() && !(b[i] == b'*' && b.get(i + 1) == Some(&b'/')) {
                blank(&mut out, b[i]);
                i += 1;
            }
            out.extend_from_slice(b"  ");
            i += 2;
        } else if c == b'r' && matches!(b.get(i + 1), Some(b'#') | Some(b'"')) && !ident(b, i) {
            let hashes = b[i + 1..].iter().take_while(|&&h| h == b'#').count();
            let mut end = i + 1 + hashes + 1;
            let close: Vec<u8> = std::iter::once(b'"')
                .chain(std::iter::repeat_n(b'#', hashes))
                .collect();
            while end < b.len() && !b[end..].starts_with(&close) {
                end += 1;
            }
            for &x in &b[i..(end + close.len()).min(b.len())] {
                blank(&mut out, x);
            }
            i = end + close.len();
        } else if c == b'"' {
            blank(&mut out, c);
            i += 1;
            while i < b.len() && b[i] != b'"' {
                if b[i] == b'\\' {
                    blank(&mut out, b[i]);
                    i += 1;
                }
                if i < b.len() {
                    blank(&mut out, b[i]);
                    i += 1;
                }
            }
            out.push(b' ');
            i += 1;
        } else if c == b'\'' && is_char_literal(b, i) {
            let end = b[i + 1..]
                .iter()
                .position(|&x| x == b'\'')
                .map(|p| i + 1 + p);
            let end = match end {
                Some(e) if b[i + 1] == b'\\' && e == i + 2 => {
                    e + 1 + b[e + 1..].iter().position(|&x| x == b'\'').unwrap_or(0)
                }
                Some(e) => e,
                None => b.len() - 1,
            };
            for &x in &b[i..=end.min(b.len() - 1)] {
                blank(&mut out, x);
            }
            i = end + 1;
        } else {
            out.push(c);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

fn ident(b: &[u8], i: usize) -> bool {
    i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_')
}

/// `'x'`, `'\n'`, `'\u{..}'` but not a lifetime `'a`.
fn is_char_literal(b: &[u8], i: usize) -> bool {
    match (b.get(i + 1), b.get(i + 2)) {
        (Some(b'\\'), _) => true,
        (Some(_), Some(b'\'')) => true,
        // a multi-byte UTF-8 character
        (Some(c), _) if *c >= 0x80 => true,
        _ => false,
    }
}

/// The module paths a file refers to: `crate::a::b::C`, `super::x`, `self::x` and paths
/// through its child modules (`child::f`), resolved from the crate root.
fn references(module: &str, children: &[String], code: &str) -> BTreeSet<Vec<String>> {
    let mut out = BTreeSet::new();
    let here: Vec<String> = module
        .split("::")
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect();
    let mut starts = vec![
        ("crate::".to_string(), Vec::new()),
        ("super::".to_string(), parent(&here)),
        ("self::".to_string(), here.clone()),
    ];
    for c in children {
        let mut base = here.clone();
        base.push(c.clone());
        starts.push((format!("{c}::"), base));
    }
    for (start, base) in &starts {
        let mut rest = code;
        while let Some(p) = rest.find(start) {
            let prev = rest[..p].chars().last();
            rest = &rest[p + start.len()..];
            if prev.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                continue;
            }
            for path in paths_at(rest) {
                let mut full = base.clone();
                full.extend(path);
                out.insert(full);
            }
        }
    }
    out
}

/// The parent module of a file module (`fit::lsq` -> `fit`; a `mod.rs` is its folder).
fn parent(here: &[String]) -> Vec<String> {
    here[..here.len().saturating_sub(1)].to_vec()
}

/// The paths starting at `s`: `a::b::C` or `{a::b, c}` (one level of braces).
fn paths_at(s: &str) -> Vec<Vec<String>> {
    let seg = |s: &str| -> Vec<String> {
        s.split("::")
            .map(|p| {
                p.trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect::<String>()
            })
            .take_while(|p| !p.is_empty())
            .collect()
    };
    if let Some(inner) = s.strip_prefix('{') {
        let end = inner.find('}').unwrap_or(inner.len());
        inner[..end].split(',').map(seg).collect()
    } else {
        let end = s
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(s.len());
        vec![seg(&s[..end])]
    }
}

/// The longest known module that is a prefix of `path`.
fn resolve(path: &[String], modules: &BTreeSet<String>) -> Option<String> {
    (1..=path.len())
        .rev()
        .map(|n| path[..n].join("::"))
        .find(|m| modules.contains(m))
}

fn rank(module: &str) -> u8 {
    let top = module.split("::").next().unwrap_or("");
    LAYERS
        .iter()
        .find(|(m, _)| *m == top)
        .map(|(_, r)| *r)
        .unwrap_or_else(|| {
            panic!("module `{top}` is in no layer: add it to lib.rs's table and LAYERS")
        })
}

/// The import graph between file modules.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let fs = files(&src());
    let modules: BTreeSet<String> = fs.iter().map(|(m, _)| m.clone()).collect();
    let mut g = BTreeMap::new();
    for (m, p) in &fs {
        let code = code_only(&std::fs::read_to_string(p).unwrap());
        // unit tests are not part of the module graph (and their `super` is the file's)
        let code = code.split("#[cfg(test)]").next().unwrap_or("").to_string();
        let prefix = if m.is_empty() {
            String::new()
        } else {
            format!("{m}::")
        };
        let children: Vec<String> = modules
            .iter()
            .filter_map(|c| c.strip_prefix(&prefix))
            .filter(|c| !c.is_empty() && !c.contains("::"))
            .map(String::from)
            .collect();
        let deps: BTreeSet<String> = references(m, &children, &code)
            .iter()
            .filter_map(|r| resolve(r, &modules))
            .filter(|d| d != m && !d.is_empty())
            .collect();
        g.insert(m.clone(), deps);
    }
    g
}

#[test]
fn layers_point_one_way() {
    let mut bad = Vec::new();
    for (m, deps) in graph() {
        for d in deps {
            if rank(&d) > rank(&m) {
                bad.push(format!(
                    "{m} (layer {}) uses {d} (layer {})",
                    rank(&m),
                    rank(&d)
                ));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "imports pointing up a layer:\n{}",
        bad.join("\n")
    );
}

/// A cycle of the graph, if it has one (depth-first search for a back edge).
fn find_cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(m) {
            Some(1) => {
                let at = stack.iter().position(|s| s == m).unwrap_or(0);
                let mut cycle = stack[at..].to_vec();
                cycle.push(m.to_string());
                return Some(cycle);
            }
            Some(2) => return None,
            _ => {}
        }
        state.insert(m.to_string(), 1);
        stack.push(m.to_string());
        for d in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(d, g, state, stack) {
                return Some(c);
            }
        }
        stack.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    g.keys()
        .find_map(|m| visit(m, g, &mut state, &mut Vec::new()))
}

#[test]
fn no_module_imports_in_a_circle() {
    if let Some(c) = find_cycle(&graph()) {
        panic!("import cycle: {}", c.join(" -> "));
    }
}

#[test]
fn every_module_says_what_it_is_for() {
    let missing: Vec<String> = files(&src())
        .into_iter()
        .filter(|(_, p)| !std::fs::read_to_string(p).unwrap().starts_with("//!"))
        .map(|(m, _)| m)
        .collect();
    assert!(
        missing.is_empty(),
        "modules without a `//!` line: {missing:?}"
    );
}

/// `(name, code lines)` of every function in `code`.
fn function_lengths(code: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = code.lines().collect();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let Some(p) = l.find("fn ") else { continue };
        if p > 0 && !l[..p].ends_with([' ', '(']) {
            continue;
        }
        let name: String = l[p + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        if name.is_empty() {
            continue;
        }
        // the body: from the first `{` after the signature to its match (a `;` first
        // means a declaration without a body)
        let (mut depth, mut started, mut n) = (0i32, false, 0usize);
        'lines: for line in &lines[i..] {
            if !line.trim().is_empty() {
                n += 1;
            }
            for c in line.chars() {
                match c {
                    '{' => {
                        depth += 1;
                        started = true;
                    }
                    '}' => depth -= 1,
                    ';' if !started && depth == 0 => break 'lines,
                    _ => {}
                }
                if started && depth == 0 {
                    break 'lines;
                }
            }
        }
        if started {
            out.push((name, n));
        }
    }
    out
}

#[test]
fn no_function_is_longer_than_the_limit() {
    let mut long = Vec::new();
    for dir in all_code() {
        for (m, p) in files(&dir) {
            let code = code_only(&std::fs::read_to_string(&p).unwrap());
            for (name, n) in function_lengths(&code) {
                if n > MAX_FN_LINES {
                    long.push(format!("{}: {m}::{name}: {n} lines", dir.display()));
                }
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FN_LINES} lines of code:\n{}",
        long.join("\n")
    );
}

/// The arms of every `match` in `code`, at the match's own depth: for each match, the
/// text of each arm's pattern (up to its `=>`).
fn match_arms(code: &str) -> Vec<Vec<String>> {
    let b = code.as_bytes();
    let mut out = Vec::new();
    let mut at = 0;
    while let Some(p) = code[at..].find("match ") {
        let start = at + p;
        at = start + 6;
        if start > 0 && (b[start - 1].is_ascii_alphanumeric() || b[start - 1] == b'_') {
            continue;
        }
        // the arms' block: the first `{` after the scrutinee at bracket depth 0
        let mut i = at;
        let mut depth = 0i32;
        while i < b.len() {
            match b[i] {
                b'(' | b'[' => depth += 1,
                b')' | b']' => depth -= 1,
                b'{' if depth == 0 => break,
                b'{' => depth += 1,
                b'}' => depth -= 1,
                _ => {}
            }
            i += 1;
        }
        let (mut depth, mut arm, mut arms) = (0i32, String::new(), Vec::new());
        let mut in_pattern = true;
        for &c in &b[(i + 1).min(b.len())..] {
            match c {
                b'{' | b'(' | b'[' => depth += 1,
                b'}' | b')' | b']' if depth == 0 => break,
                b'}' | b')' | b']' => {
                    depth -= 1;
                    // a block body ends its arm
                    if depth == 0 && c == b'}' && !in_pattern {
                        in_pattern = true;
                        arm.clear();
                        continue;
                    }
                }
                b',' if depth == 0 && !in_pattern => {
                    in_pattern = true;
                    arm.clear();
                    continue;
                }
                _ => {}
            }
            if in_pattern {
                arm.push(c as char);
                if arm.ends_with("=>") && depth == 0 {
                    arms.push(arm.trim_end_matches("=>").trim().to_string());
                    in_pattern = false;
                }
            }
        }
        out.push(arms);
    }
    out
}

/// Matches of `code` over a closed set with a `_` arm.
fn wildcards_over_closed_sets(code: &str) -> Vec<String> {
    match_arms(code)
        .into_iter()
        .filter(|arms| {
            arms.iter().any(|a| a == "_")
                && arms.iter().any(|a| {
                    CLOSED.iter().any(|c| {
                        a.split(['|', '(', ' '])
                            .any(|w| w.trim_start_matches('&').starts_with(c))
                    })
                })
        })
        .map(|arms| arms.join(" | "))
        .collect()
}

#[test]
fn closed_sets_are_matched_exhaustively() {
    let mut bad = Vec::new();
    for (m, p) in files(&src()) {
        let code = code_only(&std::fs::read_to_string(&p).unwrap());
        for arms in wildcards_over_closed_sets(&code) {
            bad.push(format!("{m}: match {{ {arms} }}"));
        }
    }
    assert!(
        bad.is_empty(),
        "`_ =>` beside the variants of a closed set (name them):\n{}",
        bad.join("\n")
    );
}

/// Whether `code` uses the path `what` (`clap`, `std::env::var`).
fn uses(code: &str, what: &str) -> bool {
    code.match_indices(what).any(|(i, _)| {
        let before = code[..i].chars().last();
        !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
    })
}

#[test]
fn the_parser_stays_in_the_cli_and_the_library_reads_no_environment() {
    let mut bad = Vec::new();
    for (m, p) in files(&src()) {
        let code = code_only(&std::fs::read_to_string(&p).unwrap());
        if uses(&code, "clap") && !(m == "cli" || m.starts_with("cli::") || m == "main") {
            bad.push(format!(
                "{m} uses clap: the command line's types belong in cli"
            ));
        }
        for env in ["std::env::var", "env::var_os", "env::var("] {
            if uses(&code, env) && m != "main" {
                bad.push(format!(
                    "{m} reads the environment ({env}): only main does, once"
                ));
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The checks themselves can fail: a circle, an upward import, a long function.
#[test]
fn the_checks_catch_what_they_are_for() {
    let code = code_only("use crate::fit::lsq::Normal;\nuse super::{a::B, c};\nlet s = \"crate::cli\"; // crate::demo\n");
    let refs = references("diagnose::search", &[], &code);
    assert!(refs.contains(&vec!["fit".into(), "lsq".into(), "Normal".into()]));
    assert!(refs.contains(&vec!["diagnose".into(), "a".into(), "B".into()]));
    assert!(refs.contains(&vec!["diagnose".into(), "c".into()]));
    assert_eq!(
        refs.len(),
        3,
        "{refs:?}: strings and comments are not imports"
    );
    assert!(rank("fit::lsq") < rank("cli"));
    let child = references(
        "cli",
        &["args".into()],
        &code_only("args::Cli::parse(); xargs::f();"),
    );
    assert_eq!(
        child,
        BTreeSet::from([vec![
            "cli".into(),
            "args".into(),
            "Cli".into(),
            "parse".into()
        ]])
    );
    let edge = |a: &str, b: &str| (a.to_string(), BTreeSet::from([b.to_string()]));
    let circle = BTreeMap::from([edge("a", "b"), edge("b", "c"), edge("c", "a")]);
    assert_eq!(find_cycle(&circle).map(|c| c.len()), Some(4));
    let line = BTreeMap::from([edge("a", "b"), edge("b", "c")]);
    assert_eq!(find_cycle(&line), None);
    let long = format!("fn f() {{\n{}}}\n", "    x += 1;\n".repeat(MAX_FN_LINES));
    assert_eq!(
        function_lengths(&long),
        vec![("f".to_string(), MAX_FN_LINES + 2)]
    );
    let lifetimes = code_only("fn g<'a>(x: &'a str) -> char { let c = '{'; x.len(); c }");
    assert_eq!(function_lengths(&lifetimes), vec![("g".to_string(), 1)]);
    let wild = "match e { EffectId::A => f(x), EffectId::B | EffectId::C => { g() } _ => {} }";
    assert_eq!(
        wildcards_over_closed_sets(wild).len(),
        1,
        "{:?}",
        match_arms(wild)
    );
    let named = "match e { EffectId::A => 1, EffectId::B => match x { Some(_) => 2, _ => 3 } }";
    assert!(
        wildcards_over_closed_sets(named).is_empty(),
        "{:?}",
        match_arms(named)
    );
    let other = "match (a, b) { (Some(x), _) => 1, _ => 2 }";
    assert!(wildcards_over_closed_sets(other).is_empty());
    assert!(uses("let x = std::env::var(\"A\");", "std::env::var"));
    assert!(!uses("my_clap::f()", "clap"));
}

/// The `src/` folder of another crate of the workspace (`xtask`, `firmware-core`).
fn crate_src(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(name)
        .join("src")
}

/// The crates beside host-fit held to the same rules of module docs and function length.
const OTHER_CRATES: [&str; 2] = ["xtask", "firmware-core"];

#[test]
fn every_module_of_xtask_and_firmware_core_says_what_it_is_for() {
    let mut missing = Vec::new();
    for krate in OTHER_CRATES {
        for (m, p) in files(&crate_src(krate)) {
            if !std::fs::read_to_string(&p).unwrap().starts_with("//!") {
                missing.push(format!("{krate}/{m}"));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "modules without a `//!` line: {missing:?}"
    );
}

#[test]
fn no_function_of_xtask_or_firmware_core_is_longer_than_the_limit() {
    let mut long = Vec::new();
    for krate in OTHER_CRATES {
        let fs = files(&crate_src(krate));
        assert!(!fs.is_empty(), "no source found for {krate}");
        for (m, p) in fs {
            let code = code_only(&std::fs::read_to_string(&p).unwrap());
            for (name, n) in function_lengths(&code) {
                if n > MAX_FN_LINES {
                    long.push(format!("{krate}/{m}::{name}: {n} lines"));
                }
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FN_LINES} lines of code:\n{}",
        long.join("\n")
    );
}
