//! The parameters of the twin's physics beyond the catalogue ([`crate::simulate::beyond`]
//! plays them): the IEEE Std 1293 second-order terms, a turn-on transient sized by the
//! temperature, the turn-on repeatability, relaxations after events, the tilter's
//! repeatability and a two-level bias; as read from TOML (`effects.*`).
use serde::{Deserialize, Serialize};

/// The IEEE Std 1293 second-order terms of each output: a quadratic form of the specific
/// force, `U_i += sum_k q[i][k] m_k(a)` with `m = [a_x^2, a_y^2, a_z^2, a_x a_y, a_x a_z,
/// a_y a_z]`, V/g^2 (row i: output x, y, z). On output y, `a_y^2` is its own K2, `a_x a_y`
/// and `a_y a_z` its cross-coupling Kip and Kio, `a_x^2`, `a_z^2` its cross-axis squares
/// Kpp, Koo, and `a_x a_z` its Kpo.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Quadratic {
    /// Per output (x, y, z): the coefficients of `a_x^2, a_y^2, a_z^2, a_x a_y, a_x a_z,
    /// a_y a_z`, V/g^2.
    pub value: [[f64; 6]; 3],
}

/// An exponential relaxation of the output after an event: `d exp(-(t - t_event) / tau)`
/// from the event on, reset at each new event.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Relaxation {
    /// Its size at the event, per axis, V.
    pub d_v: [f64; 3],
    /// Its time constant, s.
    pub tau_s: f64,
}

/// A turn-on transient whose size is proportional to the element's distance from T0:
/// `U0_i += k_i (T - T0) exp(-(t - t_on) / tau)`, from every power-on.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TempWarmup {
    /// Size per C from T0, per axis, V/C.
    pub v_per_c: [f64; 3],
    /// Its time constant, s.
    pub tau_s: f64,
}

/// Turn-on to turn-on repeatability of the bias: after the n-th power-off (in time order)
/// the bias is offset by `value[n-1]` from its value at the first power-on (entries beyond
/// the list: the last one).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TurnOn {
    /// The bias after each power-off relative to the first power-on, per axis, V.
    pub value: Vec<[f64; 3]>,
}

/// The tilter's position repeatability: each time it comes to rest, the unit stops a
/// small random rotation (two angles, normal, 1 sigma each) away from the position's
/// nominal orientation, fresh at every stop of the tilter.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Repeatability {
    /// 1 sigma of each of the two angles, rad.
    pub sigma_rad: f64,
}

/// A bias jumping between two levels (0 and `value`) at random times, each level held for
/// an exponentially distributed time of mean `mean_s` (random telegraph noise).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Telegraph {
    /// The upper level, per axis, V.
    pub value: [f64; 3],
    /// Mean time in each level, s.
    pub mean_s: f64,
}
