//! Golden test: the paper's Tables 1-2 -> Table 3 through `host-fit temp-fit`.
use tests::{cli, cli_json, repo};

#[test]
fn temp_fit_reproduces_table3_within_1e_3_relative() {
    let tables = repo().join("testdata/paper/paper-tables.csv");
    let j = cli_json(&[
        "temp-fit",
        tables.to_str().unwrap(),
        "--model",
        "pwl",
        "--relative",
        "--json",
    ]);
    assert_eq!(j["model"], "pwl");
    assert_eq!(j["t0_c"], 20.0);
    let iv = j["intervals"].as_array().unwrap();
    assert_eq!(iv.len(), 2);
    assert_eq!(
        (iv[0]["from_c"].as_f64(), iv[0]["to_c"].as_f64()),
        (Some(-40.0), Some(20.0))
    );
    let (worst, line) = tests::figures::golden_table3();
    println!("{line}");
    tests::readme::same("golden", &line);
    assert!(line.ends_with("over 24 coefficients"), "{line}");
    assert!(worst < 1e-3, "{line}");
}

/// Cramer's solution of (11): `c(T) = c(T0) + a1 dT + a2 dT^2` through three temperatures
/// passes through every row of the table, for every one of the 12 coefficients.
#[test]
fn poly_order_2_through_three_temperatures_interpolates_the_table() {
    let tables = repo().join("testdata/paper/paper-tables.csv");
    let j = cli_json(&[
        "temp-fit",
        tables.to_str().unwrap(),
        "--model",
        "poly",
        "--order",
        "2",
        "--json",
    ]);
    let text = std::fs::read_to_string(&tables).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut checked = 0;
    for line in lines {
        let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let dt = f[0] - 20.0;
        for (col, name) in header.iter().enumerate().skip(1) {
            // the terms are named as the coefficients, offsets as the paper's alpha
            let term = name
                .strip_prefix("u0")
                .map_or(name.to_string(), |a| format!("alpha_{a}"));
            let c0 = j["at_t0"][name].as_f64().unwrap();
            let a = j["coefficients"][&term].as_array().unwrap();
            let v = c0 + a[0].as_f64().unwrap() * dt + a[1].as_f64().unwrap() * dt * dt;
            assert!(
                (v - f[col]).abs() < 1e-12,
                "{name} at {} C: {v} vs {}",
                f[0],
                f[col]
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 3 * 12, "three temperatures, 12 coefficients");
}

#[test]
fn poly_order_3_with_three_temperatures_says_what_is_missing() {
    let tables = repo().join("testdata/paper/paper-tables.csv");
    let (code, _, err) = cli(&[
        "temp-fit",
        tables.to_str().unwrap(),
        "--model",
        "poly",
        "--order",
        "3",
    ]);
    assert_eq!(code, 1);
    assert!(
        err.contains("4 or more temperatures") && err.contains("has 3"),
        "{err}"
    );
}
