//! The defaults of spec fields that serde fills in (`#[serde(default = …)]`).

pub(super) fn one() -> f64 {
    1.0
}

pub(super) fn film_mode() -> u32 {
    1
}

pub(super) fn film_resolution() -> usize {
    128
}

pub(super) fn origin2() -> [f64; 2] {
    [0.0, 0.0]
}

pub(super) fn origin3() -> [f64; 3] {
    [0.0, 0.0, 0.0]
}

pub(super) fn curve_resolution() -> usize {
    128
}

pub(super) fn sphere_resolution() -> u32 {
    4
}

pub(super) fn box_resolution() -> f64 {
    8.0
}

pub(super) fn torus_resolution() -> usize {
    64
}
