//! The report of `cargo xtask embedded` (target/embedded/summary.md, printed too): per
//! build, what was checked, the instruction counts against their floors, flash and RAM by
//! section and component, and the budgets' verdicts.
use crate::budgets::{Budget, M1_FLOOR, PM1_FLOOR, TERMS_FLOOR, TM1_FLOOR};
use crate::measure::{Build, Measured};

/// The whole report: every build (the first, with `physics` and `terms`, with the C
/// harness's line, or why it failed).
pub fn report(builds: &[Measured], c_harness: &str) -> String {
    let mut s = String::from(
        "## firmware-core on Cortex-M4F (QEMU mps2-an386), `cargo xtask embedded`\n\n\
         The harness is built and run three times: with the `physics` and `terms` features \
         (the default; the blob from `host-fit diagnose` and the golden blob with 8 \
         discovered terms are compensated too), with `physics` only (the blob with \
         discovered terms refused), and with neither (`default-features = false`, for \
         units calibrated without in-flight terms).\n",
    );
    for m in builds {
        let c = (m.build == Build::Terms).then_some(c_harness);
        s.push_str(&format!(
            "\n### {}{}\n\n{}",
            m.build.label().get(..1).unwrap_or("").to_uppercase(),
            m.build.label().get(1..).unwrap_or(""),
            build(m, c)
        ));
    }
    s
}

/// One build's section.
fn build(m: &Measured, c_harness: Option<&str>) -> String {
    let physics = m.build.physics();
    let mut s = String::new();
    for l in checked(m).iter().map(String::as_str).chain(c_harness) {
        s.push_str(&format!("- {l}\n"));
    }
    s.push_str(&instructions(m, physics));
    if m.build.terms() {
        s.push_str(&terms_rows(m));
    }
    s.push_str(&flash(m));
    s.push_str(&format!(
        "\nBudgets (`cargo xtask embedded` fails on a miss): {}.\n",
        crate::budgets::report(m)
    ));
    s.push_str(&format!(
        "\nSoft-double routines (__adddf3, __muldf3, __aeabi_d*, ...) in the binary: {}\n",
        if m.soft_double.is_empty() {
            "none".to_string()
        } else {
            m.soft_double.join(", ")
        }
    ));
    s
}

/// What the run checked and the stack and RAM it measured, one line each.
fn checked(m: &Measured) -> Vec<String> {
    let mut lines = vec![format!(
        "{} compensated samples (3 methods) bit-identical to the host's f32 evaluation",
        m.samples
    )];
    if !m.build.physics() {
        lines.push("the blob with physics terms is refused (Error::PhysicsNotBuiltIn)".into());
    }
    if !m.build.terms() {
        lines.push("the blob with discovered terms is refused (Error::TermsNotBuiltIn)".into());
    }
    for (what, max) in &m.departures {
        lines.push(format!(
            "f32 results vs the f64 evaluation of the same code, {what}: max {max} g"
        ));
    }
    let state_limit = Budget::State.limit();
    let mut ram = |v: Option<u64>, line: &dyn Fn(u64) -> String| lines.extend(v.map(line));
    ram(m.stack_decode, &|v| {
        format!("maximum stack of blob decoding (painted stack): {v} bytes")
    });
    ram(m.stack_compensate, &|v| {
        format!(
            "maximum stack of compensate, a temperature update included (painted stack): {v} bytes"
        )
    });
    ram(m.state, &|v| {
        format!("RAM of the compensator state (size_of::<FlashCompensator>): {v} bytes (target <= {state_limit})")
    });
    ram(m.blob_view, &|v| {
        format!(
            "RAM of a validated blob (size_of::<BlobView>; the tables stay in flash): {v} bytes"
        )
    });
    lines
}

/// The instruction counts against their floors.
fn instructions(m: &Measured, physics: bool) -> String {
    let net = |k: &str| m.net(k).unwrap_or(0);
    let mut s = String::from("\nInstructions executed (exact, TCG plugin; the call overhead, measured with a no-op of the same signature, subtracted):\n\n| operation | instructions | floor | multiple |\n|---|---|---|---|\n");
    let m1 = net("sample_m1");
    s.push_str(&format!(
        "| method 1 per sample (cached N(T)) | {m1} | {M1_FLOOR} (9 mul, 6 add, 3 sub) | {:.1}x |\n",
        m1 as f64 / M1_FLOOR as f64
    ));
    for (k, name) in [
        ("sample_m2full", "method 2 per sample, full model"),
        ("sample_m2simp", "method 2 per sample, simplified"),
    ] {
        s.push_str(&format!(
            "| {name} | {} | 39 (a_hat 18, M a_hat + e 18, subtraction 3) | {:.1}x |\n",
            net(k),
            net(k) as f64 / 39.0
        ));
    }
    // with physics: + filters and offsets (rate, hysteresis, warm-up: 12 mul/add + 3
    // sub), the K2/asymmetry correction (6 mul, 3 add, 3 abs, 9 mul + 6 add + 3 sub)
    let phys_rows = if physics {
        &[
            (
                "sample_pm1",
                "method 1 per sample with the physics terms",
                PM1_FLOOR,
            ),
            (
                "sample_pm2full",
                "method 2 (full) per sample with the physics terms",
                39 + 15 + 30,
            ),
        ][..]
    } else {
        &[]
    };
    for &(k, name, floor) in phys_rows {
        s.push_str(&format!(
            "| {name} | {} | {floor} (the method's floor, the offsets 15, the K2/asymmetry correction 30) | {:.1}x |\n",
            net(k),
            net(k) as f64 / floor as f64
        ));
    }
    if physics {
        for (k, name) in [
            (
                "step_pm1",
                "physics: the machines' step (every 0.1 s; lag, rate, hysteresis, warm-up, offsets), method 1 (+ one sample)",
            ),
            (
                "update_pm1",
                "physics: the machines' step and the temperature update of the diagnosed blob's table, method 1 (+ one sample)",
            ),
        ] {
            s.push_str(&format!("| {name} | {} | | |\n", net(k)));
        }
    }
    for (k, name) in [
        (
            "update_poly3",
            "temperature update, polynomial order 3 (+ one sample)",
        ),
        (
            "update_pwl5",
            "temperature update, PWL 5 breakpoints (+ one sample)",
        ),
    ] {
        s.push_str(&format!("| {name} | {} | | |\n", net(k)));
    }
    s.push_str(&format!(
        "| blob validation in place (the PWL blob through 5 stops, CRC included) | {} | | |\n",
        net("decode")
    ));
    s
}

/// The discovered terms' rows of the instruction table (the golden blob: physics terms
/// and a full table of 8 discovered terms).
fn terms_rows(m: &Measured) -> String {
    let net = |k: &str| m.net(k).unwrap_or(0);
    let mut s = String::new();
    for (k, name, floor) in [
        (
            "sample_tm1",
            "method 1 per sample with the physics terms and 8 discovered terms",
            TM1_FLOOR,
        ),
        (
            "sample_tm2full",
            "method 2 (full) per sample with the physics terms and 8 discovered terms",
            39 + 15 + 30 + TERMS_FLOOR,
        ),
    ] {
        s.push_str(&format!(
            "| {name} | {} | {floor} (as with the physics terms, + the 8 terms' {TERMS_FLOOR}: 3 magnitudes, 2 mul for each term's force part, 1 mul and 1 add into its axis) | {:.1}x |\n",
            net(k),
            net(k) as f64 / floor as f64
        ));
    }
    s.push_str(&format!(
        "| terms: the machines' step with 8 discovered terms (their state parts: dT, dTdt, decay(power_on) weights), method 1 (+ one sample) | {} | | |\n",
        net("step_tm1")
    ));
    s
}

/// Flash and RAM by section and by component, and the library's share.
fn flash(m: &Measured) -> String {
    let mut s = String::from("\nFlash and RAM of the linked test binary (llvm-size -A):\n\n| section | bytes |\n|---|---|\n");
    for (n, v) in &m.sizes {
        s.push_str(&format!("| {n} | {v} |\n"));
    }
    s.push_str("\nBy component (llvm-nm symbol sizes, text + rodata; LTO inlines across crates, so inlined code counts where it landed):\n\n| component | bytes |\n|---|---|\n");
    for (n, v) in &m.components {
        s.push_str(&format!("| {n} | {v} |\n"));
    }
    let lib = m.library_bytes();
    let budget = match m.build {
        Build::Core => Budget::Flash,
        Build::Physics => Budget::PhysicsFlash,
        Build::Terms => Budget::TermsFlash,
    };
    s.push_str(&format!(
        "\nCompensation + blob decode (the library components above: validation in place, no copy; compiler_builtins and unclassified core code counted in, as the worst case): **{lib} bytes** ({:.1} KiB; target <= {} KiB: {}).\n",
        lib as f64 / 1024.0,
        budget.limit() as f64 / 1024.0,
        budget.verdict(m).word()
    ));
    s
}
