//! How far apart two colours look, to people with normal colour vision and with each of
//! the three dichromacies: CIEDE2000 colour difference (Sharma, Wu and Dalal 2005) in
//! CIELAB (sRGB, D65), after simulating protanopia, deuteranopia or tritanopia with the
//! matrices of Machado, Oliveira and Fernandes (2009, severity 1) in linear RGB.
//! Exact to the published test pairs' 4 decimals (test below).

/// The ways of seeing compared.
pub const VISIONS: [&str; 4] = ["normal", "protanopia", "deuteranopia", "tritanopia"];

/// Machado et al. (2009), severity 1.0, in linear RGB.
const MACHADO: [[[f64; 3]; 3]; 3] = [
    [
        [0.152286, 1.052583, -0.204868],
        [0.114503, 0.786281, 0.099216],
        [-0.003882, -0.048116, 1.051998],
    ],
    [
        [0.367322, 0.860646, -0.227968],
        [0.280085, 0.672501, 0.047413],
        [-0.011820, 0.042940, 0.968881],
    ],
    [
        [1.255528, -0.076749, -0.178779],
        [-0.078411, 0.930809, 0.147602],
        [0.004733, 0.691367, 0.303900],
    ],
];

fn linear(c: f64) -> f64 {
    let c = c / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// CIELAB (D65) of linear RGB.
fn lab_of_linear(l: [f64; 3]) -> [f64; 3] {
    let l = l.map(|v| v.clamp(0.0, 1.0));
    let x = (0.4124 * l[0] + 0.3576 * l[1] + 0.1805 * l[2]) / 0.95047;
    let y = 0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2];
    let z = (0.0193 * l[0] + 0.1192 * l[1] + 0.9505 * l[2]) / 1.08883;
    let d: f64 = 6.0 / 29.0;
    let f = |t: f64| {
        if t > d.powi(3) {
            t.cbrt()
        } else {
            t / (3.0 * d * d) + 4.0 / 29.0
        }
    };
    let (fx, fy, fz) = (f(x), f(y), f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// CIELAB of an sRGB colour as seen with `vision` (an index of [`VISIONS`]).
pub fn lab(rgb: [u8; 3], vision: usize) -> [f64; 3] {
    let l = rgb.map(|c| linear(f64::from(c)));
    let seen = match vision.checked_sub(1).and_then(|k| MACHADO.get(k)) {
        None => l,
        Some(m) => std::array::from_fn(|i| (0..3).map(|j| m[i][j] * l[j]).sum()),
    };
    lab_of_linear(seen)
}

/// CIEDE2000 difference of two CIELAB colours (kL = kC = kH = 1).
pub fn delta_e2000(p: [f64; 3], q: [f64; 3]) -> f64 {
    let (l1, a1, b1) = (p[0], p[1], p[2]);
    let (l2, a2, b2) = (q[0], q[1], q[2]);
    let c_bar = (a1.hypot(b1) + a2.hypot(b2)) / 2.0;
    let g = 0.5 * (1.0 - (c_bar.powi(7) / (c_bar.powi(7) + 25f64.powi(7))).sqrt());
    let (a1p, a2p) = ((1.0 + g) * a1, (1.0 + g) * a2);
    let (c1p, c2p) = (a1p.hypot(b1), a2p.hypot(b2));
    let hue = |a: f64, b: f64| {
        if a == 0.0 && b == 0.0 {
            0.0
        } else {
            b.atan2(a).to_degrees().rem_euclid(360.0)
        }
    };
    let (h1, h2) = (hue(a1p, b1), hue(a2p, b2));
    let dl = l2 - l1;
    let dc = c2p - c1p;
    let dh = if c1p * c2p == 0.0 {
        0.0
    } else if (h2 - h1).abs() <= 180.0 {
        h2 - h1
    } else if h2 - h1 > 180.0 {
        h2 - h1 - 360.0
    } else {
        h2 - h1 + 360.0
    };
    let dh_big = 2.0 * (c1p * c2p).sqrt() * (dh / 2.0).to_radians().sin();
    let l_bar = (l1 + l2) / 2.0;
    let cp_bar = (c1p + c2p) / 2.0;
    let h_bar = if c1p * c2p == 0.0 {
        h1 + h2
    } else if (h1 - h2).abs() <= 180.0 {
        (h1 + h2) / 2.0
    } else if h1 + h2 < 360.0 {
        (h1 + h2 + 360.0) / 2.0
    } else {
        (h1 + h2 - 360.0) / 2.0
    };
    let cos = |d: f64| d.to_radians().cos();
    let t =
        1.0 - 0.17 * cos(h_bar - 30.0) + 0.24 * cos(2.0 * h_bar) + 0.32 * cos(3.0 * h_bar + 6.0)
            - 0.20 * cos(4.0 * h_bar - 63.0);
    let d_theta = 30.0 * (-((h_bar - 275.0) / 25.0).powi(2)).exp();
    let rc = 2.0 * (cp_bar.powi(7) / (cp_bar.powi(7) + 25f64.powi(7))).sqrt();
    let sl = 1.0 + 0.015 * (l_bar - 50.0).powi(2) / (20.0 + (l_bar - 50.0).powi(2)).sqrt();
    let sc = 1.0 + 0.045 * cp_bar;
    let sh = 1.0 + 0.015 * cp_bar * t;
    let rt = -(2.0 * d_theta).to_radians().sin() * rc;
    ((dl / sl).powi(2) + (dc / sc).powi(2) + (dh_big / sh).powi(2) + rt * (dc / sc) * (dh_big / sh))
        .sqrt()
}

/// The smallest CIEDE2000 difference of two sRGB colours over [`VISIONS`], and where.
pub fn worst_difference(a: [u8; 3], b: [u8; 3]) -> (f64, &'static str) {
    (0..VISIONS.len())
        .map(|v| (delta_e2000(lab(a, v), lab(b, v)), VISIONS[v]))
        .fold((f64::INFINITY, ""), |m, x| if x.0 < m.0 { x } else { m })
}

/// `#RRGGBB` as bytes.
pub fn parse_hex(s: &str) -> [u8; 3] {
    let h = s.trim_start_matches('#');
    assert_eq!(h.len(), 6, "not a colour: {s}");
    std::array::from_fn(|i| u8::from_str_radix(&h[2 * i..2 * i + 2], 16).unwrap())
}

#[test]
fn ciede2000_gives_the_published_test_pairs() {
    // Sharma, Wu and Dalal (2005), Table 1, pairs 1, 7, 17, 25 and 5
    for (p, q, want) in [
        ([50.0, 2.6772, -79.7751], [50.0, 0.0, -82.7485], 2.0425),
        ([50.0, 0.0, 0.0], [50.0, -1.0, 2.0], 2.3669),
        ([50.0, 2.5, 0.0], [73.0, 25.0, -18.0], 27.1492),
        (
            [60.2574, -34.0099, 36.2677],
            [60.4626, -34.1751, 39.4387],
            1.2644,
        ),
        ([50.0, 2.5, 0.0], [50.0, 0.0, -2.5], 4.3065),
    ] {
        let got = delta_e2000(p, q);
        assert!(
            (got - want).abs() < 5e-5,
            "{p:?} {q:?}: {got} (want {want})"
        );
        assert!((delta_e2000(q, p) - got).abs() < 1e-12, "symmetric");
    }
    // white is L 100; the dichromat simulations keep greys grey
    assert!((lab([255, 255, 255], 0)[0] - 100.0).abs() < 0.01);
    for v in 1..VISIONS.len() {
        let g = lab([128, 128, 128], v);
        assert!(
            g[1].abs() < 0.5 && g[2].abs() < 0.5,
            "{}: {g:?}",
            VISIONS[v]
        );
    }
    // Okabe and Ito's vermillion and orange, which a deuteranope hardly tells apart
    let (d, how) = worst_difference([213, 94, 0], [230, 159, 0]);
    assert!(d < 15.0 && how == "deuteranopia", "{d} {how}");
}
