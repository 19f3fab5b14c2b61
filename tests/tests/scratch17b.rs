use host_fit::data::positions::Positions;
use host_fit::data::recording::Recording;
use host_fit::fit::pipeline::{fit_chosen, ModelRequest};
use std::path::Path;
use tests::twins;

fn show(name: &str, rec: &Recording) {
    let oc = fit_chosen(rec, &ModelRequest::default()).unwrap();
    let fl = host_fit::diagnose::floor::floor(rec, &host_fit::diagnose::rules::Rules::default());
    let scale: Vec<String> = (0..3).map(|i| format!("{:.2}", oc.fit.axis_scale(i, true))).collect();
    let ratio: Vec<String> = (0..3)
        .map(|i| {
            let w = oc.noise.sigma[i] / 60f64.sqrt();
            let f = fl.axes[i].var_of_mean(60.0).map(f64::sqrt).unwrap_or(f64::NAN);
            format!("{:.2}", f / w)
        })
        .collect();
    println!(
        "{name:<42} {:<30} chi2red {:?} floor60/white60 {:?} sel: {}",
        oc.fit.basis.describe(),
        scale,
        ratio,
        oc.selection.as_ref().map(|s| s.candidates.iter().map(|c| format!("{} {:.4}", c.model, c.held_out_rms_dg_mg.unwrap_or(f64::NAN))).collect::<Vec<_>>().join(", ")).unwrap_or_default()
    );
}

#[test]
fn scratch() {
    for (name, cfg) in twins::all() {
        let (_, rec) = twins::recording(name, &cfg);
        show(name, &rec);
    }
    for f in ["/tmp/w17b/four.csv", "/tmp/w17b/four-miss.csv"] {
        let rec = Recording::read(Path::new(f), Positions::default()).unwrap();
        show(f, &rec);
    }
}
