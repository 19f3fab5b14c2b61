//! The reports as a reader sees them: every report is opened in headless Chromium
//! (Debian's, `/usr/bin/chromium`; `cargo xtask test` installs it) at three desktop
//! widths. Nothing may be wider than the window (no page to scroll sideways, no text cut
//! in a box), no text of a plot may leave its drawing or overlap another, and every plot
//! gets a real width; a screenshot of the whole page (its full height) must show content
//! in every figure, in several colours, and white margins at the bottom and the right
//! (nothing cut). The plots' structure and their data are checked on the page's source
//! (`reports::check_plots`: titles, axis labels with units, a legend entry per series,
//! markers and lines through the embedded data). The models' colours must be told apart
//! at a glance, by people with any of the three dichromacies too: every pair of the
//! series colours of the worst-|dg| plot at least [`MIN_DELTA_E`] apart (CIEDE2000, in
//! normal and simulated colour vision), and each drawn on the screenshot.
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};
use tests::{cli, lab, repo};

#[path = "reports/colour.rs"]
mod colour;
mod reports;

/// The smallest CIEDE2000 difference between two series colours of the worst-|dg| plot
/// (the models and the uncompensated unit), in normal vision and in each simulated
/// dichromacy: 20 is a difference seen at a glance (2 is about the least noticeable).
const MIN_DELTA_E: f64 = 20.0;

const CHROMIUM: &str = "/usr/bin/chromium";
/// The widths the layout is checked at (a laptop, a desktop, a wide screen), px.
const WIDTHS: [u32; 3] = [1024, 1400, 1920];
/// The screenshot's width, px.
const SHOT_WIDTH: u32 = 1400;

/// One Chromium at a time (each is heavy; the machine may have two cores).
static BROWSER: Mutex<()> = Mutex::new(());

fn chromium() -> &'static str {
    assert!(
        Path::new(CHROMIUM).exists(),
        "{CHROMIUM} is missing: the reports' browser test needs Debian's Chromium. \
         `cargo xtask test` installs it (as root); by hand: apt-get install chromium fonts-dejavu-core"
    );
    CHROMIUM
}

/// Run headless Chromium on `page` with `args`; its stdout. Killed after two minutes.
fn run_chromium(page: &Path, args: &[String]) -> Vec<u8> {
    let _one = BROWSER.lock().unwrap_or_else(|e| e.into_inner());
    let profile = tempdir();
    let mut child = Command::new(chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--hide-scrollbars",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .args(args)
        .arg(format!("file://{}", page.display()))
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("chromium starts");
    let mut out = Vec::new();
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        use std::io::Read;
        let _ = stdout.read_to_end(&mut out);
        out
    });
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("chromium did not finish on {} in 120 s", page.display());
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    reader.join().unwrap()
}

/// A folder of the test's own, removed when the test drops it (passed or failed).
fn tempdir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

/// Measures the page as laid out and appends the result, as JSON, in `#layout-check`.
const MEASURE: &str = r#"<script>(function () {
  const vw = window.innerWidth, r = {
    viewport: vw, scroll_width: document.documentElement.scrollWidth,
    height: document.documentElement.scrollHeight,
    overflow: [], pre_cut: [], cut_text: [], overlaps: [], narrow: [], figures: []
  };
  const name = (e) => e.tagName.toLowerCase() + (e.id ? '#' + e.id : '');
  for (const e of document.body.querySelectorAll('*')) {
    if (e.closest('svg') && e.tagName.toLowerCase() !== 'svg') continue;
    const b = e.getBoundingClientRect();
    if (b.width > 0 && (b.right > vw + 0.5 || b.left < -0.5)) r.overflow.push(name(e));
  }
  for (const p of document.querySelectorAll('pre'))
    if (p.scrollWidth > p.clientWidth + 1) r.pre_cut.push(p.textContent.slice(0, 60));
  for (const f of document.querySelectorAll('figure')) {
    const svg = f.querySelector('svg'), s = svg.getBoundingClientRect();
    const fb = f.getBoundingClientRect();
    // the drawing's scale on the page: a text's size as read is its font size times it
    const vb = svg.viewBox.baseVal, scale = vb && vb.width ? s.width / vb.width : 1;
    const fig = { id: f.id, left: fb.left + window.scrollX, top: fb.top + window.scrollY,
                  width: s.width, height: s.height, min_text_px: 1e9, point_labels: [] };
    r.figures.push(fig);
    if (s.width < 300) r.narrow.push(f.id + ' ' + s.width.toFixed(0));
    const boxes = [];
    for (const t of svg.querySelectorAll('text')) {
      const b = t.getBoundingClientRect();
      if (t.textContent.trim())
        fig.min_text_px = Math.min(fig.min_text_px, parseFloat(getComputedStyle(t).fontSize) * scale);
      if (t.classList.contains('point-label') && b.width > 0) fig.point_labels.push(t.textContent);
      if (b.left < s.left - 0.5 || b.right > s.right + 0.5 || b.top < s.top - 0.5 || b.bottom > s.bottom + 0.5)
        r.cut_text.push(f.id + ': ' + t.textContent);
      for (const [o, ob] of boxes) {
        const w = Math.min(b.right, ob.right) - Math.max(b.left, ob.left);
        const h = Math.min(b.bottom, ob.bottom) - Math.max(b.top, ob.top);
        if (w > 1 && h > 1) r.overlaps.push(f.id + ': "' + t.textContent + '" on "' + o + '"');
      }
      boxes.push([t.textContent, b]);
    }
  }
  const pre = document.createElement('pre');
  pre.id = 'layout-check';
  pre.textContent = JSON.stringify(r);
  document.body.appendChild(pre);
})();</script>"#;

/// The layout of `html` at window width `width`, measured in Chromium.
fn layout(html: &str, width: u32, dir: &Path) -> serde_json::Value {
    let page = dir.join(format!("measured-{width}.html"));
    let at = html.rfind("</body>").expect("a body");
    std::fs::write(&page, format!("{}{MEASURE}{}", &html[..at], &html[at..])).unwrap();
    let dom = String::from_utf8(run_chromium(
        &page,
        &["--dump-dom".into(), format!("--window-size={width},1000")],
    ))
    .unwrap();
    let start = dom.find("<pre id=\"layout-check\">").unwrap_or_else(|| {
        panic!(
            "the measuring script did not run:\n{}",
            &dom[..dom.len().min(400)]
        )
    }) + "<pre id=\"layout-check\">".len();
    let end = start + dom[start..].find("</pre>").unwrap();
    let text = dom[start..end]
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&");
    serde_json::from_str(&text).unwrap()
}

/// A decoded screenshot: width, height, RGB rows.
struct Shot {
    w: usize,
    h: usize,
    rgb: Vec<[u8; 3]>,
}

impl Shot {
    fn px(&self, x: usize, y: usize) -> [u8; 3] {
        self.rgb[y * self.w + x]
    }
}

fn white(c: [u8; 3]) -> bool {
    c.iter().all(|v| *v >= 235)
}

fn screenshot(page: &Path, height: u32, dir: &Path) -> Shot {
    let png = dir.join("shot.png");
    let _ = std::fs::remove_file(&png);
    run_chromium(
        page,
        &[
            format!("--screenshot={}", png.display()),
            format!("--window-size={SHOT_WIDTH},{height}"),
        ],
    );
    let file = std::fs::File::open(&png).expect("chromium wrote the screenshot");
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let step = info.color_type.samples();
    assert!(step >= 3, "{:?}", info.color_type);
    let (w, h) = (info.width as usize, info.height as usize);
    let rgb = (0..h)
        .flat_map(|y| {
            let row = &buf[y * info.line_size..];
            (0..w).map(move |x| [row[x * step], row[x * step + 1], row[x * step + 2]])
        })
        .collect();
    Shot { w, h, rgb }
}

/// Non-white share and the colours (4 bits a channel) seen on at least 12 pixels in the
/// rectangle.
fn content(s: &Shot, x0: usize, y0: usize, x1: usize, y1: usize) -> (f64, usize) {
    let mut counts = std::collections::HashMap::new();
    let mut ink = 0usize;
    for y in y0..y1.min(s.h) {
        for x in x0..x1.min(s.w) {
            let c = s.px(x, y);
            if !white(c) {
                ink += 1;
            }
            *counts.entry(c.map(|v| v >> 4)).or_insert(0usize) += 1;
        }
    }
    let area = ((x1.min(s.w) - x0) * (y1.min(s.h) - y0)).max(1);
    (
        ink as f64 / area as f64,
        counts.values().filter(|n| **n >= 12).count(),
    )
}

/// Everything this test asks of one report; the embedded data of its plots and the
/// screenshot with where each figure lies in it.
fn check_in_browser(
    name: &str,
    report: &Path,
) -> (Vec<reports::Figure>, Shot, Vec<serde_json::Value>) {
    check_in_browser_with(name, report, &|_, _| {})
}

/// [`check_in_browser`], and `also` on every width's measured figures.
fn check_in_browser_with(
    name: &str,
    report: &Path,
    also: &dyn Fn(u32, &[serde_json::Value]),
) -> (Vec<reports::Figure>, Shot, Vec<serde_json::Value>) {
    let html = std::fs::read_to_string(report).unwrap();
    let figures = reports::check_plots(&html);
    assert!(!figures.is_empty(), "{name}: no plots");
    let tmp = tempdir();
    let dir = tmp.path();
    let mut height = 0;
    let mut taken = None;
    for width in WIDTHS {
        let l = layout(&html, width, dir);
        let list = |k: &str| l[k].as_array().unwrap().clone();
        assert_eq!(l["viewport"], width, "{name}");
        assert!(
            l["scroll_width"].as_u64().unwrap() <= u64::from(width),
            "{name} at {width} px: the page is {} px wide; too wide: {:?}",
            l["scroll_width"],
            list("overflow")
        );
        for k in ["overflow", "pre_cut", "cut_text", "overlaps", "narrow"] {
            assert!(
                list(k).is_empty(),
                "{name} at {width} px, {k}: {:?}",
                list(k)
            );
        }
        assert_eq!(
            list("figures").len(),
            figures.len(),
            "{name}: every figure laid out"
        );
        also(width, &list("figures"));
        if width == SHOT_WIDTH {
            height = l["height"].as_u64().unwrap() as u32;
            let shot = screenshot(report, height.min(30_000), dir);
            check_shot(name, &shot, &list("figures"));
            taken = Some((shot, list("figures")));
        }
    }
    println!(
        "{name}: {} plots, {} KB, {height} px tall at {SHOT_WIDTH} px: laid out at {WIDTHS:?} px without overflow, screenshot checked",
        figures.len(),
        html.len() / 1024
    );
    let (shot, placed) = taken.expect("a screenshot at SHOT_WIDTH");
    (figures, shot, placed)
}

/// The worst-|dg| plot's series colours (the models and the uncompensated unit) are
/// at least [`MIN_DELTA_E`] apart in every colour vision, and each is on the screen in
/// that plot.
fn check_model_colours(
    name: &str,
    (figures, shot, placed): &(Vec<reports::Figure>, Shot, Vec<serde_json::Value>),
) {
    let fig = figures
        .iter()
        .find(|f| f.id == "max-dg")
        .unwrap_or_else(|| panic!("{name}: no worst-|dg| plot"));
    let mut colours: Vec<(String, [u8; 3])> = Vec::new();
    for s in fig.data["series"].as_array().unwrap() {
        let c = colour::parse_hex(s["color"].as_str().unwrap());
        let label = s["name"].as_str().unwrap().to_string();
        if !colours.iter().any(|x| x.1 == c) {
            colours.push((label, c));
        }
    }
    assert!(colours.len() >= 3, "{name}: {colours:?}");
    for (i, (na, a)) in colours.iter().enumerate() {
        for (nb, b) in &colours[i + 1..] {
            let (d, vision) = colour::worst_difference(*a, *b);
            assert!(
                d >= MIN_DELTA_E,
                "{name}: `{na}` {a:?} and `{nb}` {b:?} are {d:.1} apart in {vision} (CIEDE2000; at least {MIN_DELTA_E})"
            );
        }
    }
    let at = placed
        .iter()
        .find(|p| p["id"] == "max-dg")
        .expect("the plot laid out");
    let v = |k: &str| at[k].as_f64().unwrap().max(0.0) as usize;
    for (label, c) in &colours {
        let mut n = 0;
        for y in v("top")..(v("top") + v("height")).min(shot.h) {
            for x in v("left")..(v("left") + v("width")).min(shot.w) {
                let p = shot.px(x, y);
                n += usize::from((0..3).all(|k| p[k].abs_diff(c[k]) <= 6));
            }
        }
        assert!(n >= 30, "{name}: `{label}` {c:?} drawn on {n} pixels");
    }
    println!(
        "{name}: {} series colours in the worst-|dg| plot, every pair at least {MIN_DELTA_E} apart (CIEDE2000, normal and dichromat vision)",
        colours.len()
    );
}

/// The screenshot shows the page (not blank), in colour, every figure drawn, and white
/// margins at its bottom and right edge (the page is not cut).
fn check_shot(name: &str, s: &Shot, figures: &[serde_json::Value]) {
    assert_eq!(s.w, SHOT_WIDTH as usize, "{name}");
    let (ink, colours) = content(s, 0, 0, s.w, s.h);
    assert!(
        ink > 0.02,
        "{name}: the screenshot is blank ({:.1}% ink)",
        ink * 100.0
    );
    assert!(colours >= 8, "{name}: {colours} colours");
    let bottom = (s.h - 6..s.h).all(|y| (0..s.w).all(|x| white(s.px(x, y))));
    let right = (0..s.h).all(|y| (s.w - 6..s.w).all(|x| white(s.px(x, y))));
    assert!(
        bottom && right,
        "{name}: content runs to the edge (bottom {bottom}, right {right})"
    );
    for f in figures {
        let v = |k: &str| f[k].as_f64().unwrap().max(0.0) as usize;
        let (x0, y0) = (v("left"), v("top"));
        let (x1, y1) = (x0 + v("width"), y0 + v("height"));
        assert!(y1 <= s.h, "{name}: {} lies below the screenshot", f["id"]);
        let (ink, colours) = content(s, x0, y0, x1, y1);
        assert!(
            ink > 0.01 && colours >= 4,
            "{name}: {} looks blank ({:.1}% ink, {colours} colours)",
            f["id"],
            ink * 100.0
        );
    }
}

/// The smallest text a reader is asked to read on the plan's plot, px (as laid out:
/// the font size times the drawing's scale on the page).
const MIN_PLAN_TEXT_PX: f64 = 11.0;

/// The plan's page (issue 29 item 3): its one plot drawn at its own size, so that every
/// text on it reads at [`MIN_PLAN_TEXT_PX`] or more at every width, and every candidate
/// labelled on it (as in the table) with a label laid out inside the drawing, overlapping
/// nothing.
#[test]
fn the_plan_report_in_a_browser() {
    let tmp = tempdir();
    let dir = tmp.path();
    let report = dir.join("plan.html");
    let (code, out, err) = cli(&[
        "plan",
        "--target-mg",
        "0.1",
        "--out",
        dir.join("plan.csv").to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    let n = j["candidates"].as_array().unwrap().len();
    let want: Vec<String> = (0..n).map(host_fit::plan::Candidate::label).collect();
    check_in_browser_with("plan report", &report, &|width, figures| {
        let f = figures
            .iter()
            .find(|f| f["id"] == "plan-accuracy-hours")
            .expect("the plan's plot");
        let px = f["min_text_px"].as_f64().unwrap();
        assert!(
            px >= MIN_PLAN_TEXT_PX,
            "at {width} px its smallest text reads {px:.1} px (at least {MIN_PLAN_TEXT_PX})"
        );
        let mut labels: Vec<String> = f["point_labels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l.as_str().unwrap().to_string())
            .collect();
        labels.sort();
        assert_eq!(labels, want, "at {width} px");
        println!("plan report at {width} px: smallest text {px:.1} px, {n} candidates labelled");
    });
}

#[test]
fn the_demo_report_in_a_browser() {
    let dir = &tests::demo::demo().dir;
    let seen = check_in_browser("demo report", &dir.join("report.html"));
    check_model_colours("demo report", &seen);
}

/// A lab's recording (its own position names, four stops, T0 = 25 C; `tests::lab`)
/// with the twin's truth: the names in the headings, the truth as a reference line, the
/// held-out dwells ringed, laid out as every report.
#[test]
fn a_lab_s_report_in_a_browser() {
    let tmp = tempdir();
    let dir = tmp.path();
    let f = lab::write(dir, 1);
    let report = dir.join("lab.html");
    let (code, _, err) = cli(&[
        "report",
        f.recording.to_str().unwrap(),
        "--positions",
        f.positions.to_str().unwrap(),
        "--truth",
        f.truth.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let seen = check_in_browser("lab report (F1..F6, V1..V4)", &report);
    check_model_colours("lab report", &seen);
    let titles: Vec<&str> = seen
        .0
        .iter()
        .filter_map(|f| f.data["title"].as_str())
        .collect();
    assert!(
        titles.contains(&"worst |dg| over the verification positions V1..V4"),
        "{titles:?}"
    );
}

#[test]
fn a_diagnosis_report_with_findings_in_a_browser() {
    let tmp = tempdir();
    let dir = tmp.path();
    let case =
        host_fit::blind::Case::catalogue(vec![host_fit::diagnose::EffectId::TempRate], 1.0, 3);
    let sim = host_fit::simulate::simulate(&host_fit::blind::configure(&case), |_| {}).unwrap();
    let rec = dir.join("rec.csv");
    std::fs::write(&rec, sim.csv).unwrap();
    let report = dir.join("diagnosis.html");
    let (code, out, err) = cli(&[
        "diagnose",
        rec.to_str().unwrap(),
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("finding: temp_rate"), "{out}");
    check_in_browser("diagnosis report (simulated, temp_rate)", &report);
}

/// The wrist recording (11 k samples over 84 h, 1050 poses): its report stays small.
#[test]
fn the_wrist_recordings_diagnosis_report_in_a_browser() {
    let real = repo().join("../shared/real/ggir-wrist");
    if !real.exists() {
        eprintln!(
            "{} is missing: the wrist report is not checked",
            real.display()
        );
        return;
    }
    let tmp = tempdir();
    let dir = tmp.path();
    let report = dir.join("wrist.html");
    let (code, _, err) = cli(&[
        "diagnose",
        real.join("recording.csv").to_str().unwrap(),
        "--positions",
        real.join("positions.csv").to_str().unwrap(),
        "--unknown-orientations",
        "--report",
        report.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let size = std::fs::metadata(&report).unwrap().len();
    assert!(size < 600_000, "the wrist report is {size} bytes");
    check_in_browser("diagnosis report (ggir-wrist)", &report);
}

/// The trend report of 150 units in 6 lots (written through the store's own API; the x
/// offset moves by 3 sigma from lot 5 on, so that rules fire and their series are drawn).
#[test]
fn the_trend_report_in_a_browser() {
    use host_fit::store::record::{AtT0, Command, Record};
    let tmp = tempdir();
    let dir = tmp.path();
    let db = dir.join("line.sqlite");
    let mut store = host_fit::store::Store::open(&db).unwrap();
    let mut rng = host_fit::rng::Rng::new(4);
    let mut records = Vec::new();
    for lot in 1..=6 {
        for u in 0..25 {
            let serial = format!("L{lot}-{u:02}");
            let input = std::path::PathBuf::from(format!("L{lot}/{serial}.csv"));
            let mut r = Record::new(Command::Batch, None, &serial, &input).unwrap();
            let mut values = host_fit::simulate::PAPER_UNIT[2];
            for v in values.iter_mut() {
                *v += 1e-6 * rng.normal();
            }
            if lot >= 5 {
                values[9] += 3e-6;
            }
            r.lot = Some(format!("L{lot}"));
            r.input_sha256 = Some("0".repeat(64));
            r.output_unit = Some(host_fit::data::output_unit::OutputUnit::Volt);
            r.model = Some("poly4".into());
            r.at_t0 = Some(AtT0 {
                t0_c: 20.0,
                values,
                sigma: Some([1e-6; 12]),
            });
            r.blob = Some(vec![0; 64]);
            r.worst_dg_mg = Some(0.015 + 0.003 * rng.normal().abs());
            records.push(r);
        }
    }
    store.append(&mut records).unwrap();
    drop(store);
    let report = dir.join("trend.html");
    let (code, out, err) = cli(&[
        "trend",
        "--db",
        db.to_str().unwrap(),
        "--out",
        report.to_str().unwrap(),
        "--reference-first",
        "50",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("150 calibrations"), "{out}");
    check_in_browser("trend report", &report);
}
