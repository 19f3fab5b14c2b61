//! The house rules of host-fit's source, checked like rust-analyzer's tidy test: modules
//! import one way (each layer uses only its own layer and those below, and no file module
//! imports in a circle), every module says what it is for, no function is longer than
//! [`MAX_FN_LINES`] lines of code (host-fit's sources, tests and benches, and the `tests`
//! crate), the command line's parser stays in `cli`, the library reads no environment,
//! a closed set (every enum found in the source) is matched exhaustively (no `_ =>`
//! beside its variants), every error states its kind, and an enum's names are derived
//! once and round-tripped by `tests/names.rs`.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest function body allowed, in lines of code (blank and comment lines not counted).
const MAX_FN_LINES: usize = 120;

/// The layers of lib.rs's table: a module may use modules of its own rank or below.
const LAYERS: [(&str, u8); 27] = [
    ("error", 0),
    ("rng", 0),
    ("output", 0),
    ("progress", 0),
    ("data", 1),
    ("terms", 1),
    ("model", 2),
    ("fit", 3),
    ("fuzzing", 3),
    ("simulate", 3),
    ("blob", 4),
    ("verify", 4),
    ("vectors", 4),
    ("acceptance", 4),
    ("diagnose", 5),
    ("analysis", 6),
    ("blind", 6),
    ("plan", 6),
    ("store", 6),
    ("report", 7),
    ("batch", 7),
    ("demo", 7),
    ("demo_plan", 7),
    ("cli", 8),
    ("lib", 9),
    ("main", 9),
    ("", 9),
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

/// The parent module of a file module (`model::lsq` -> `fit`; a `mod.rs` is its folder).
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

/// An `enum` of the source: its name, its derives, whether every variant is a unit one
/// (a closed set of names), and its body's text.
#[derive(Debug)]
struct EnumDef {
    name: String,
    derives: String,
    units_only: bool,
}

/// The enums defined in `code` (code only: comments and strings blanked).
fn enums(code: &str) -> Vec<EnumDef> {
    let mut out = Vec::new();
    for (i, _) in code.match_indices("enum ") {
        let b = code.as_bytes();
        if i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_') {
            continue;
        }
        let name: String = code[i + 5..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let Some(open) = code[i..].find('{').map(|o| i + o) else {
            continue;
        };
        if name.is_empty() || code[i + 5 + name.len()..open].contains(';') {
            continue;
        }
        let mut depth = 0i32;
        let mut close = open;
        for (k, c) in code[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => {}
            }
            if depth == 0 {
                close = open + k;
                break;
            }
        }
        let body = &code[open + 1..close];
        // the attributes above: back to the previous item's end
        let before = &code[..i];
        let from = before.rfind(['}', ';']).map_or(0, |p| p + 1);
        out.push(EnumDef {
            name,
            derives: before[from..].to_string(),
            units_only: !body.contains('(') && !body.contains('{'),
        });
    }
    out
}

/// Every enum of host-fit's source, with its file module.
fn all_enums() -> Vec<(String, EnumDef)> {
    let mut out = Vec::new();
    for (m, p) in files(&src()) {
        let code = code_only(&std::fs::read_to_string(&p).unwrap());
        out.extend(enums(&code).into_iter().map(|e| (m.clone(), e)));
    }
    out
}

/// Matches of `code` over one of the `closed` sets with a `_` arm: an arm (its guard
/// left out) names a variant at its top, or inside `Some(..)`. A variant inside a tuple
/// is a product of sets, where `_` stands for the combinations not named.
fn wildcards_over_closed_sets(code: &str, closed: &[String]) -> Vec<String> {
    let names_variant = |arm: &str| {
        let pattern = arm.split(" if ").next().unwrap_or(arm);
        pattern.split('|').any(|alt| {
            let alt = alt.trim().trim_start_matches('&');
            let alt = alt
                .strip_prefix("Some(")
                .unwrap_or(alt)
                .trim_start_matches('&');
            closed.iter().any(|c| alt.starts_with(&format!("{c}::")))
        })
    };
    match_arms(code)
        .into_iter()
        .filter(|arms| arms.iter().any(|a| a == "_") && arms.iter().any(|a| names_variant(a)))
        .map(|arms| arms.join(" | "))
        .collect()
}

/// A closed set is matched exhaustively: every enum host-fit defines (found in the
/// source, not listed by hand), in a `match` with arms of its variants, is never matched
/// with a `_ =>` beside them. A local name of the same spelling as another crate's
/// `#[non_exhaustive]` enum would need the wildcard: none is used here.
#[test]
fn closed_sets_are_matched_exhaustively() {
    let closed: Vec<String> = all_enums().into_iter().map(|(_, e)| e.name).collect();
    assert!(
        closed.len() > 40,
        "the enums of host-fit were not found: {closed:?}"
    );
    let mut bad = Vec::new();
    for (m, p) in files(&src()) {
        let code = code_only(&std::fs::read_to_string(&p).unwrap());
        for arms in wildcards_over_closed_sets(&code, &closed) {
            bad.push(format!("{m}: match {{ {arms} }}"));
        }
    }
    assert!(
        bad.is_empty(),
        "`_ =>` beside the variants of a closed set (name them):\n{}",
        bad.join("\n")
    );
}

/// Whether an enum's derives give it names (serde, strum or clap): those names are
/// its one table.
fn derives_names(derives: &str) -> bool {
    ["Serialize", "Deserialize", "strum::", "ValueEnum"]
        .iter()
        .any(|d| derives.contains(d))
}

/// The block (`{ .. }`, braces included) that opens at the first `{` at or after `at`.
fn block_at(text: &str, at: usize) -> &str {
    let Some(open) = text[at..].find('{').map(|o| at + o) else {
        return "";
    };
    let mut depth = 0i32;
    for (k, c) in text[open..].char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            _ => {}
        }
        if depth == 0 {
            return &text[open..=open + k];
        }
    }
    &text[open..]
}

/// The names of `ty` written by hand in `text` (the file's source): a `fn name`/`fn
/// as_str` of `impl Ty`, or an `impl Display for Ty`, whose arms are string literals.
fn hand_written_names(text: &str, ty: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (i, _) in text.match_indices(&format!("impl {ty} {{")) {
        let block = block_at(text, i);
        for f in ["fn name(", "fn as_str("] {
            for (j, _) in block.match_indices(f) {
                if block_at(block, j).contains("=> \"") {
                    out.push(format!(
                        "{ty}::{}",
                        f.trim_end_matches('(').trim_start_matches("fn ")
                    ));
                }
            }
        }
    }
    for (i, _) in text.match_indices(&format!("Display for {ty} {{")) {
        if block_at(text, i).contains("=> \"") {
            out.push(format!("Display for {ty}"));
        }
    }
    out
}

/// The paths `code` names from the crate `krate` (`host_fit::a::B`, and each of
/// `host_fit::a::{B, C}`).
fn crate_paths(code: &str, krate: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for (i, m) in code.match_indices(&format!("{krate}::")) {
        let rest = &code[i + m.len()..];
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(rest.len());
        let head = rest[..end].trim_end_matches(':');
        if rest[end..].starts_with('{') {
            let inner = &rest[end + 1..];
            let close = inner.find('}').unwrap_or(inner.len());
            for item in inner[..close].split(',') {
                let item = item.split(" as ").next().unwrap_or("").trim();
                out.insert(format!("{head}::{item}"));
            }
        } else {
            out.insert(head.to_string());
        }
    }
    out
}

/// Enum names are written once: an enum whose names a derive gives (serde, strum, clap)
/// has no second table written by hand beside them (a `fn name`, `fn as_str` or
/// `Display` of string literals), and `tests/names.rs` round-trips it, naming it by its
/// defining path (text -> enum -> text, and serde's JSON agrees with its Display).
#[test]
fn enum_names_are_written_once_and_round_tripped() {
    let names = code_only(
        &std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/names.rs"))
            .unwrap(),
    );
    let tested = crate_paths(&names, "host_fit");
    let (mut twice, mut untested) = (Vec::new(), Vec::new());
    for (m, p) in files(&src()) {
        let text = std::fs::read_to_string(&p).unwrap();
        for e in enums(&code_only(&text)) {
            if !(e.units_only && derives_names(&e.derives)) {
                continue;
            }
            twice.extend(
                hand_written_names(&text, &e.name)
                    .into_iter()
                    .map(|h| format!("{m}: {h}")),
            );
            let path = format!("{m}::{}", e.name);
            if !tested.contains(&path) {
                untested.push(path);
            }
        }
    }
    assert!(
        twice.is_empty(),
        "names written by hand beside the derived ones (derive them: strum, serde through it):\n{}",
        twice.join("\n")
    );
    assert!(
        untested.is_empty(),
        "enums with names that tests/names.rs does not round-trip:\n{}",
        untested.join("\n")
    );
}

/// The tuple type aliases of `code`: `type X = (..);` (a struct with named fields says
/// what each part is).
fn tuple_aliases(code: &str) -> Vec<String> {
    code.match_indices("type ")
        .filter(|(i, _)| *i == 0 || !code.as_bytes()[i - 1].is_ascii_alphanumeric())
        .filter_map(|(i, m)| {
            let rest = &code[i + m.len()..];
            let (name, value) = rest.split_once('=')?;
            let name = name.trim();
            let ident = name
                .chars()
                .all(|c| c.is_alphanumeric() || "_<>' ,".contains(c));
            (ident && value.trim_start().starts_with('(')).then(|| name.to_string())
        })
        .collect()
}

#[test]
fn no_tuple_type_aliases() {
    let mut bad = Vec::new();
    for dir in all_code() {
        for (m, p) in files(&dir) {
            let aliases = tuple_aliases(&code_only(&std::fs::read_to_string(&p).unwrap()));
            if !aliases.is_empty() {
                bad.push(format!("{}: {m}: {}", dir.display(), aliases.join(", ")));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "tuple type aliases (a struct names its fields):\n{}",
        bad.join("\n")
    );
}

/// Where `text` names a thing after an issue number: an identifier `issue_N` (in the
/// code), or a comment line's `issue N's`, `of issue N`, `for issue N` (the number says
/// when a thing was asked for, not what it is; a citation such as `(issue N)` is fine).
fn named_after_issues(text: &str) -> Vec<String> {
    let code = code_only(text);
    let ident = |s: &str, i: usize| {
        i > 0 && (s.as_bytes()[i - 1].is_ascii_alphanumeric() || s.as_bytes()[i - 1] == b'_')
    };
    let mut out: Vec<String> = code
        .match_indices("issue_")
        .filter(|(i, m)| {
            !ident(&code, *i) && code[i + m.len()..].starts_with(|c: char| c.is_ascii_digit())
        })
        .map(|(i, _)| {
            code[i..]
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        })
        .collect();
    for line in text
        .lines()
        .map(str::trim_start)
        .filter(|l| l.starts_with("//"))
    {
        let lower = line.to_ascii_lowercase();
        for (i, m) in lower.match_indices("issue ") {
            let n: String = lower[i + m.len()..]
                .chars()
                .take_while(char::is_ascii_digit)
                .collect();
            let before = lower[..i].trim_end();
            let names = lower[i + m.len() + n.len()..].starts_with("'s")
                || before.ends_with(" of")
                || before.ends_with(" for");
            if !n.is_empty() && !ident(&lower, i) && names {
                out.push(format!("issue {n}"));
            }
        }
    }
    out
}

#[test]
fn nothing_is_named_after_an_issue_number() {
    let mut bad = Vec::new();
    for dir in all_code() {
        for (m, p) in files(&dir) {
            let found = named_after_issues(&std::fs::read_to_string(&p).unwrap());
            if !found.is_empty() {
                bad.push(format!("{}: {m}: {}", dir.display(), found.join(", ")));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "names after issue numbers (say what the thing is):\n{}",
        bad.join("\n")
    );
}

/// Temporary folders are `tempfile`'s (removed when the test ends, passed or failed, and
/// never shared by two runs): no folder is made by hand under the system's temp dir.
#[test]
fn temporary_folders_are_tempfiles() {
    let mut bad = Vec::new();
    for dir in all_code() {
        for (m, p) in files(&dir) {
            if uses(
                &code_only(&std::fs::read_to_string(&p).unwrap()),
                "temp_dir()",
            ) {
                bad.push(format!("{}: {m}", dir.display()));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "folders made by hand in temp_dir() (use tempfile):\n{}",
        bad.join("\n")
    );
}

/// The size lints of the workspace (function length, argument count) hold in every
/// crate: each takes the workspace's lints, or names them in its own.
#[test]
fn every_crate_has_the_size_lints() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let workspace = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    let members = workspace
        .split("members = [")
        .nth(1)
        .and_then(|s| s.split(']').next())
        .expect("the workspace lists its members");
    let size = ["too_many_lines", "too_many_arguments"];
    assert!(
        size.iter().all(|l| workspace.contains(l)),
        "the workspace's lints name {size:?}"
    );
    let mut bad = Vec::new();
    for m in members
        .split(',')
        .map(|m| m.trim().trim_matches('"'))
        .filter(|m| !m.is_empty())
    {
        let toml = std::fs::read_to_string(root.join(m).join("Cargo.toml")).unwrap();
        let lints = toml
            .split("[lints")
            .skip(1)
            .collect::<Vec<_>>()
            .join("[lints");
        let inherits =
            lints.starts_with(']') && lints[1..].trim_start().starts_with("workspace = true");
        if !inherits && !size.iter().all(|l| lints.contains(l)) {
            bad.push(m.to_string());
        }
    }
    assert!(
        bad.is_empty(),
        "crates without the size lints {size:?}: {bad:?}"
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

/// The kindless constructors of the error in `code` (error.rs): a `pub fn` returning
/// `Self` that neither takes an `ErrorKind`, nor is a method of an error (`self`), nor
/// names the kind it makes in its body.
fn kindless_constructors(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(p) = rest.find("pub fn ") {
        rest = &rest[p + 7..];
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let Some(open) = rest.find('{') else { break };
        let signature = &rest[..open];
        if !signature.contains("-> Self") {
            continue;
        }
        // the body: to the matching brace
        let (mut depth, mut end) = (0i32, open);
        for (i, c) in rest[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => {}
            }
            if depth == 0 {
                end = open + i;
                break;
            }
        }
        let body = &rest[open..end];
        if !(signature.contains("ErrorKind")
            || signature.contains("self")
            || body.contains("ErrorKind::"))
        {
            out.push(name);
        }
    }
    out
}

/// Whether `code` builds a `ty` by a struct literal (`Ty { field: .., ..}`), not by a
/// function (a `-> Ty {` body is not a literal).
fn struct_literal(code: &str, ty: &str) -> bool {
    code.match_indices(&format!("{ty} {{")).any(|(i, m)| {
        let rest = code[i + m.len()..].trim_start();
        let field: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let after = rest[field.len()..].trim_start();
        rest.starts_with("..")
            || (!field.is_empty()
                && ((after.starts_with(':') && !after.starts_with("::")) || after.starts_with(',')))
    })
}

/// Errors are one small `#[non_exhaustive]` enum of kinds: every constructor of
/// `HostError` states the kind it makes, and no code builds one by hand.
#[test]
fn every_error_has_a_kind() {
    let error = std::fs::read_to_string(src().join("error.rs")).unwrap();
    let kinds = error
        .find("pub enum ErrorKind")
        .expect("error.rs defines ErrorKind");
    assert!(
        error[..kinds].trim_end().ends_with("#[non_exhaustive]"),
        "ErrorKind is #[non_exhaustive]: a new kind is not a breaking change"
    );
    let bad = kindless_constructors(&code_only(&error));
    assert!(
        bad.is_empty(),
        "constructors of HostError without a kind: {bad:?}"
    );
    let mut by_hand = Vec::new();
    for dir in all_code() {
        for (m, p) in files(&dir) {
            let code = code_only(&std::fs::read_to_string(&p).unwrap());
            if m != "error"
                && (struct_literal(&code, "HostError") || uses(&code, "HostError::msg("))
            {
                by_hand.push(format!("{}: {m}", dir.display()));
            }
        }
    }
    assert!(
        by_hand.is_empty(),
        "errors built without a kind (use HostError::new(ErrorKind::.., ..)):\n{}",
        by_hand.join("\n")
    );
}

/// The checks themselves can fail: a circle, an upward import, a long function.
#[test]
fn the_checks_catch_what_they_are_for() {
    let code = code_only("use crate::model::lsq::Normal;\nuse super::{a::B, c};\nlet s = \"crate::cli\"; // crate::demo\n");
    let refs = references("diagnose::search", &[], &code);
    assert!(refs.contains(&vec!["model".into(), "lsq".into(), "Normal".into()]));
    assert!(refs.contains(&vec!["diagnose".into(), "a".into(), "B".into()]));
    assert!(refs.contains(&vec!["diagnose".into(), "c".into()]));
    assert_eq!(
        refs.len(),
        3,
        "{refs:?}: strings and comments are not imports"
    );
    assert!(rank("model::lsq") < rank("cli"));
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
    let closed = ["EffectId".to_string()];
    assert_eq!(
        wildcards_over_closed_sets(wild, &closed).len(),
        1,
        "{:?}",
        match_arms(wild)
    );
    let named = "match e { EffectId::A => 1, EffectId::B => match x { Some(_) => 2, _ => 3 } }";
    assert!(
        wildcards_over_closed_sets(named, &closed).is_empty(),
        "{:?}",
        match_arms(named)
    );
    let guarded = "match r { Ok(f) if k == EffectId::A => 1, _ => 2 }";
    assert!(wildcards_over_closed_sets(guarded, &closed).is_empty());
    let some = "match r { Some(EffectId::A) => 1, _ => 2 }";
    assert_eq!(wildcards_over_closed_sets(some, &closed).len(), 1);
    let other = "match (a, b) { (Some(x), _) => 1, _ => 2 }";
    assert!(wildcards_over_closed_sets(other, &closed).is_empty());
    let kindless = "impl E { pub fn msg(m: String) -> Self { E { m } } \
        pub fn new(kind: ErrorKind, m: String) -> Self { x } \
        pub fn io(e: X) -> Self { Self::new(ErrorKind::Io, e) } \
        pub fn within(self, f: P) -> Self { self } pub fn kind(&self) -> ErrorKind { k } }";
    assert_eq!(kindless_constructors(kindless), ["msg"]);
    assert!(struct_literal("Err(E { file: None, ..e })", "E"));
    assert!(!struct_literal("fn f() -> E {\n    let m = 1;", "E"));
    assert!(!struct_literal("fn f() -> E {\n    E::new(k, m)", "E"));
    let defs = enums(&code_only(
        "#[derive(Serialize)]\nenum A { X, Y }\nfn f() {}\nenum B { Z(u8) }\npub enum C;",
    ));
    assert_eq!(
        defs.iter()
            .map(|e| (e.name.as_str(), e.units_only))
            .collect::<Vec<_>>(),
        [("A", true), ("B", false)]
    );
    assert!(derives_names(&defs[0].derives) && !derives_names(&defs[1].derives));
    let hand = "impl A {\n    pub fn name(self) -> &'static str {\n        match self { A::X => \"x\", A::Y => \"y\" }\n    }\n}\nimpl B {\n    pub fn name(self) -> &'static str { self.into() }\n}";
    assert_eq!(hand_written_names(hand, "A"), ["A::name"]);
    assert!(hand_written_names(hand, "B").is_empty());
    assert_eq!(
        crate_paths(
            "use host_fit::a::{B, C as D};\nhost_fit::e::F::iter()",
            "host_fit"
        ),
        BTreeSet::from(["a::B".into(), "a::C".into(), "e::F::iter".into()])
    );
    assert_eq!(
        tuple_aliases("type A = (f64, f64);\npub type B<'a> = (&'a str, u8);\ntype C = Vec<u8>;\nlet subtype = (1, 2);"),
        ["A", "B<'a>"]
    );
    assert_eq!(
        named_after_issues("fn issue_18() {}\n// the forms of issue 18's classes\n//! The twin (issue 19), of issue 17\nlet tissue_3 = \"of issue 4\";"),
        ["issue_18", "issue 18", "issue 17"]
    );
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

/// The modules (of `modules`, as `a::b`) that the layout page's row of their layer (a
/// table row `| N | ...`, N the layer's rank) does not name as `` `b` `` or `` `b/` ``.
fn unnamed_in_layout(page: &str, modules: &[String]) -> Vec<String> {
    let row = |layer: u8| {
        page.lines()
            .find(|l| l.starts_with(&format!("| {layer} |")))
            .unwrap_or("")
    };
    modules
        .iter()
        .filter(|m| {
            let base = m.rsplit("::").next().unwrap_or(m);
            let r = row(rank(m));
            !r.contains(&format!("`{base}`")) && !r.contains(&format!("`{base}/`"))
        })
        .cloned()
        .collect()
}

/// docs/layout.md is the code's map: every module of host-fit is named in its layer's
/// row, so a module added, moved or renamed shows up there or fails here.
#[test]
fn the_layout_page_names_every_module_in_its_layer() {
    let page = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/layout.md"),
    )
    .unwrap();
    let modules: Vec<String> = files(&src()).into_iter().map(|(m, _)| m).collect();
    let missing = unnamed_in_layout(&page, &modules);
    assert!(
        missing.is_empty(),
        "docs/layout.md does not name these modules in their layer's row: {missing:?}"
    );
    // the check itself: a module named in another layer's row is not named
    let page = "| 2 | `model/` | `lsq` |\n| 3 | `fit/` | `select` |\n";
    let ms = [
        "model::lsq".to_string(),
        "fit::lsq".to_string(),
        "fit::select".to_string(),
    ];
    assert_eq!(unnamed_in_layout(page, &ms), vec!["fit::lsq".to_string()]);
}
