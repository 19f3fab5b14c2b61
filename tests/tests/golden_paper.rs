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
    assert!(line.ends_with("over 24 coefficients"), "{line}");
    assert!(worst < 1e-3, "{line}");
}

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
    // Cramer's solution of (11): c(T) = c(T0) + a1 dT + a2 dT^2 passes through all rows.
    let text = std::fs::read_to_string(&tables).unwrap();
    for line in text
        .lines()
        .filter(|l| l.starts_with('-') || l.starts_with('7'))
    {
        let f: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        let dt = f[0] - 20.0;
        let c0 = j["at_t0"]["u0x"].as_f64().unwrap();
        let a = j["coefficients"]["alpha_x"].as_array().unwrap();
        let v = c0 + a[0].as_f64().unwrap() * dt + a[1].as_f64().unwrap() * dt * dt;
        assert!((v - f[10]).abs() < 1e-12, "{v} vs {}", f[10]);
    }
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
