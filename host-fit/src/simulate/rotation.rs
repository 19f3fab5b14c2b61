//! A small rotation of an orientation: how a tilter face off its nominal orientation (a
//! fixture error) or a tilter that stops a little off (its repeatability) turns the
//! specific force the unit feels.

/// `a` turned by two small angles about two axes perpendicular to it, rad, then
/// normalised.
pub(super) fn rotate(a: [f64; 3], angles: [f64; 2]) -> [f64; 3] {
    // Two axes perpendicular to `a`, then a small rotation about each.
    let helper = if a[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let cross = |u: [f64; 3], v: [f64; 3]| {
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    };
    let norm = |v: [f64; 3]| {
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|x| x / n)
    };
    let e1 = norm(cross(a, helper));
    let e2 = cross(a, e1);
    let v: [f64; 3] = std::array::from_fn(|i| a[i] + angles[0] * e2[i] - angles[1] * e1[i]);
    norm(v)
}
