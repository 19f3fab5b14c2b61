//! The metrological model of model.md, formulas (1), (2), (5)-(8) and (13), written once.
//!
//! Coefficient order everywhere (blob tables, CSV columns, host fits) is
//! [`COEFF_NAMES`]: `kxx kyy kzz kxy kxz kyx kyz kzx kzy u0x u0y u0z`.
use crate::real::Real;

/// A 3-vector (acceleration in g, or voltages).
pub type Vec3<R> = [R; 3];
/// A 3x3 matrix, row-major: `m[i][j]` is row i, column j.
pub type Mat3<R> = [[R; 3]; 3];

/// Number of coefficients of the model.
pub const N_COEFFS: usize = 12;

/// Canonical names and order of the 12 coefficients (the paper's Tables 1-2 columns).
pub const COEFF_NAMES: [&str; N_COEFFS] = [
    "kxx", "kyy", "kzz", "kxy", "kxz", "kyx", "kyz", "kzx", "kzy", "u0x", "u0y", "u0z",
];

/// Where `K[i][j]` sits in the canonical order ([`COEFF_NAMES`]): the one definition of
/// the layout that blob tables, CSV columns and host fits all index by.
pub const K_INDEX: [[usize; 3]; 3] = [[0, 3, 4], [5, 1, 6], [7, 8, 2]];
/// Where `U0[i]` sits in the canonical order.
pub const U0_INDEX: [usize; 3] = [9, 10, 11];
/// Axis names, in the order of the model's vectors.
pub const AXES: [&str; 3] = ["x", "y", "z"];

/// The 12 coefficients: `U = K a + U0`.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Coeffs<R> {
    /// Scale factors (diagonal) and cross-sensitivities, output units per g.
    pub k: Mat3<R>,
    /// Zero offsets, output units.
    pub u0: Vec3<R>,
}

impl<R: Real> Coeffs<R> {
    /// From the canonical 12-array ([`COEFF_NAMES`] order).
    pub fn from_array(c: &[R; N_COEFFS]) -> Self {
        // Spelled out (not indexed through K_INDEX) so the firmware has no bounds checks;
        // the test `layout_constants_match_the_array_order` pins the two together.
        let [kxx, kyy, kzz, kxy, kxz, kyx, kyz, kzx, kzy, u0x, u0y, u0z] = *c;
        Coeffs {
            k: [[kxx, kxy, kxz], [kyx, kyy, kyz], [kzx, kzy, kzz]],
            u0: [u0x, u0y, u0z],
        }
    }

    /// To the canonical 12-array ([`COEFF_NAMES`] order).
    pub fn to_array(&self) -> [R; N_COEFFS] {
        let [[kxx, kxy, kxz], [kyx, kyy, kyz], [kzx, kzy, kzz]] = self.k;
        let [u0x, u0y, u0z] = self.u0;
        [kxx, kyy, kzz, kxy, kxz, kyx, kyz, kzx, kzy, u0x, u0y, u0z]
    }

    /// Formula (1): the output for specific force `a`.
    pub fn forward(&self, a: Vec3<R>) -> Vec3<R> {
        add3(mat_vec(&self.k, a), self.u0)
    }
}

/// `m v`.
#[inline]
pub fn mat_vec<R: Real>(m: &Mat3<R>, v: Vec3<R>) -> Vec3<R> {
    let [r0, r1, r2] = m;
    [dot(r0, &v), dot(r1, &v), dot(r2, &v)]
}

/// `a . b`.
#[inline]
pub fn dot<R: Real>(a: &Vec3<R>, b: &Vec3<R>) -> R {
    let [a0, a1, a2] = *a;
    let [b0, b1, b2] = *b;
    a0 * b0 + a1 * b1 + a2 * b2
}

/// `a + b`.
#[inline]
pub fn add3<R: Real>(a: Vec3<R>, b: Vec3<R>) -> Vec3<R> {
    let [a0, a1, a2] = a;
    let [b0, b1, b2] = b;
    [a0 + b0, a1 + b1, a2 + b2]
}

/// `a - b`.
#[inline]
pub fn sub3<R: Real>(a: Vec3<R>, b: Vec3<R>) -> Vec3<R> {
    let [a0, a1, a2] = a;
    let [b0, b1, b2] = b;
    [a0 - b0, a1 - b1, a2 - b2]
}

/// `a - b` elementwise for matrices.
pub fn mat_sub<R: Real>(a: &Mat3<R>, b: &Mat3<R>) -> Mat3<R> {
    let [a0, a1, a2] = *a;
    let [b0, b1, b2] = *b;
    [sub3(a0, b0), sub3(a1, b1), sub3(a2, b2)]
}

/// `a b`.
pub fn mat_mul<R: Real>(a: &Mat3<R>, b: &Mat3<R>) -> Mat3<R> {
    let [[b00, b01, b02], [b10, b11, b12], [b20, b21, b22]] = *b;
    let c0 = [b00, b10, b20];
    let c1 = [b01, b11, b21];
    let c2 = [b02, b12, b22];
    let row = |r: &Vec3<R>| [dot(r, &c0), dot(r, &c1), dot(r, &c2)];
    let [a0, a1, a2] = a;
    [row(a0), row(a1), row(a2)]
}

/// Scale the rows of `m` by `d` (`diag(d) m`).
pub fn diag_mul<R: Real>(d: Vec3<R>, m: &Mat3<R>) -> Mat3<R> {
    let [d0, d1, d2] = d;
    let [m0, m1, m2] = *m;
    let s = |k: R, r: Vec3<R>| {
        let [x, y, z] = r;
        [k * x, k * y, k * z]
    };
    [s(d0, m0), s(d1, m1), s(d2, m2)]
}

/// The diagonal of `m`.
pub fn diagonal<R: Real>(m: &Mat3<R>) -> Vec3<R> {
    let [[m00, _, _], [_, m11, _], [_, _, m22]] = *m;
    [m00, m11, m22]
}

/// Euclidean norm.
#[inline]
pub fn norm3<R: Real>(v: &Vec3<R>) -> R {
    dot(v, v).sqrt()
}

/// The largest magnitude of the three components (NaN components are skipped).
#[inline]
fn max_abs3<R: Real>(v: &Vec3<R>) -> R {
    let [x, y, z] = *v;
    let m = |a: R, b: R| if b.abs() > a { b.abs() } else { a };
    m(m(x.abs(), y), z)
}

/// True when all three components are finite.
#[inline]
pub fn all_finite<R: Real>(v: &Vec3<R>) -> bool {
    let [a, b, c] = *v;
    a.is_finite() && b.is_finite() && c.is_finite()
}

/// `N = K^-1` by the adjugate, or `None` when K is singular or not finite.
///
/// Singular means `|det K| <= 64 eps |k0| |k1| |k2|` (rows' max-norms), i.e. the rows
/// are parallel to within a few hundred ulps: no physical accelerometer is near that.
/// Max-norms, not Euclidean ones: no square root on the update path (and no libm
/// `sqrtf` in the firmware), and no squares that overflow f32 for outputs in raw counts.
///
/// Error bound (held by the tests): for the diagonally dominant K of a real unit
/// (`|K_ij| <= 0.05 |K_ii|`) every element of the result is within
/// `16 eps max|N|` of the exact inverse of the given (rounded) K.
pub fn invert<R: Real>(k: &Mat3<R>) -> Option<Mat3<R>> {
    let [[a, b, c], [d, e, f], [g, h, i]] = *k;
    let c00 = e * i - f * h;
    let c01 = f * g - d * i;
    let c02 = d * h - e * g;
    let det = a * c00 + b * c01 + c * c02;
    let [r0, r1, r2] = *k;
    let scale = max_abs3(&r0) * max_abs3(&r1) * max_abs3(&r2);
    let sixty_four = R::from_f32(64.0);
    if !det.is_finite() || !scale.is_finite() || det.abs() <= sixty_four * R::EPSILON * scale {
        return None;
    }
    let inv = R::ONE / det;
    let n = [
        [c00 * inv, (c * h - b * i) * inv, (b * f - c * e) * inv],
        [c01 * inv, (a * i - c * g) * inv, (c * d - a * f) * inv],
        [c02 * inv, (b * g - a * h) * inv, (a * e - b * d) * inv],
    ];
    let [n0, n1, n2] = n;
    if all_finite(&n0) && all_finite(&n1) && all_finite(&n2) {
        Some(n)
    } else {
        None
    }
}

/// Formula (1) inverted: `a = N (U - U0)`.
#[inline]
pub fn apply<R: Real>(n: &Mat3<R>, u: Vec3<R>, u0: Vec3<R>) -> Vec3<R> {
    mat_vec(n, sub3(u, u0))
}

/// Formulas (6)/(7): the full temperature error `N(T0) (dK a + dU0)`.
pub fn temperature_error_full<R: Real>(
    n0: &Mat3<R>,
    dk: &Mat3<R>,
    du0: Vec3<R>,
    a: Vec3<R>,
) -> Vec3<R> {
    mat_vec(n0, add3(mat_vec(dk, a), du0))
}

/// Formula (8): the simplified temperature error, keeping only the diagonal of `N(T0)`.
///
/// Departs from the full model by `(N0 - diag N0)(dK a + dU0)`: first order in the
/// cross-sensitivities (a few % of the scale factors) times the temperature error.
pub fn temperature_error_simplified<R: Real>(
    n0: &Mat3<R>,
    dk: &Mat3<R>,
    du0: Vec3<R>,
    a: Vec3<R>,
) -> Vec3<R> {
    let [d0, d1, d2] = diagonal(n0);
    let [x, y, z] = add3(mat_vec(dk, a), du0);
    [d0 * x, d1 * y, d2 * z]
}

/// Formula (13): `|a| - 1` in g.
#[inline]
pub fn dg<R: Real>(a: &Vec3<R>) -> R {
    norm3(a) - R::ONE
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_round_trip_keeps_canonical_order() {
        let c: [f64; 12] = core::array::from_fn(|i| i as f64);
        let m = Coeffs::from_array(&c);
        assert_eq!(m.k[0][1], 3.0); // kxy
        assert_eq!(m.k[2][1], 8.0); // kzy
        assert_eq!(m.u0[1], 10.0);
        assert_eq!(m.to_array(), c);
    }

    #[test]
    fn layout_constants_match_the_array_order() {
        let c: [f64; 12] = core::array::from_fn(|i| i as f64);
        let m = Coeffs::from_array(&c);
        for i in 0..3 {
            for j in 0..3 {
                assert_eq!(m.k[i][j], c[K_INDEX[i][j]]);
                let name = COEFF_NAMES[K_INDEX[i][j]];
                assert_eq!(&name[1..], format!("{}{}", AXES[i], AXES[j]));
            }
            assert_eq!(m.u0[i], c[U0_INDEX[i]]);
            assert_eq!(COEFF_NAMES[U0_INDEX[i]], format!("u0{}", AXES[i]));
        }
    }

    #[test]
    fn invert_is_inverse_and_refuses_singular() {
        let k = [
            [-0.55, 0.01, 0.016],
            [-0.013, -0.548, -0.0007],
            [-0.0147, -0.0004, -0.5486],
        ];
        let n = invert(&k).unwrap();
        let p = mat_mul(&n, &k);
        for (i, row) in p.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-14, "{i}{j} {v}");
            }
        }
        let s = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 1.0, 1.0]];
        assert!(invert(&s).is_none());
        // parallel to within a few ulps: refused; a real unit in raw 24-bit counts
        // (K ~ 8e6 counts/g, det ~ 5e20) accepted in f32
        let near: [[f32; 3]; 3] = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.000001], [0.0, 1.0, 1.0]];
        assert!(invert(&near).is_none());
        let counts: [[f32; 3]; 3] = [[8.1e6, 1.2e4, -3e3], [2e3, -7.9e6, 5e3], [-1e4, 4e3, 8.0e6]];
        let n = invert(&counts).unwrap();
        let p = mat_mul(&n, &counts);
        for (i, row) in p.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                let want = if i == j { 1.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-6, "{i}{j} {v}");
            }
        }
        assert!(invert(&[[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
    }

    #[test]
    fn simplified_error_equals_full_for_diagonal_k() {
        let n0 = [[2.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 4.0]];
        let dk = [[0.1, 0.2, 0.3], [0.0, 0.1, 0.0], [0.05, 0.0, 0.1]];
        let a = [0.3, -0.4, 0.866];
        let du0 = [0.01, 0.02, -0.03];
        assert_eq!(
            temperature_error_full(&n0, &dk, du0, a),
            temperature_error_simplified(&n0, &dk, du0, a)
        );
    }
}
