//! The report of `cargo xtask embedded` (target/embedded/summary.md, printed too): per
//! build, what was checked, the instruction counts against their floors, flash and RAM by
//! section and component, and the budgets' verdicts.
use crate::budgets::{Budget, M1_FLOOR, PM1_FLOOR};
use crate::measure::Measured;

/// The whole report: the build with `physics` (and the C harness's line, or why it
/// failed) and the build without it.
pub fn report(full: &Measured, core: &Measured, c_harness: &str) -> String {
    format!(
        "## firmware-core on Cortex-M4F (QEMU mps2-an386), `cargo xtask embedded`\n\n\
         The harness is built and run twice: with the `physics` feature (the default; \
         the blob from `host-fit diagnose` is compensated too) and without it \
         (`default-features = false`, for units calibrated without in-flight terms).\n\n\
         ### With the `physics` feature\n\n{}\n### Without the `physics` feature\n\n{}",
        build(full, true, Some(c_harness)),
        build(core, false, None)
    )
}

/// One build's section.
fn build(m: &Measured, physics: bool, c_harness: Option<&str>) -> String {
    let mut s = String::new();
    for l in checked(m, physics)
        .iter()
        .map(String::as_str)
        .chain(c_harness)
    {
        s.push_str(&format!("- {l}\n"));
    }
    s.push_str(&instructions(m, physics));
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
fn checked(m: &Measured, physics: bool) -> Vec<String> {
    let mut lines = vec![format!(
        "{} compensated samples (3 methods) bit-identical to the host's f32 evaluation",
        m.samples
    )];
    if !physics && m.physics_refused {
        lines.push("the blob with physics terms is refused (Error::PhysicsNotBuiltIn)".into());
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
    let budget = if Budget::Flash.applies(m) {
        Budget::Flash
    } else {
        Budget::PhysicsFlash
    };
    s.push_str(&format!(
        "\nCompensation + blob decode (the library components above: validation in place, no copy; compiler_builtins and unclassified core code counted in, as the worst case): **{lib} bytes** ({:.1} KiB; target <= {} KiB: {}).\n",
        lib as f64 / 1024.0,
        budget.limit() as f64 / 1024.0,
        budget.verdict(m).word()
    ));
    s
}
