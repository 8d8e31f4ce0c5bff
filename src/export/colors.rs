//! Colours of per-vertex fields in the glTF results: a blue–white–red map centred
//! on the field's median.

use serde_json::{json, Value};

/// How a field is coloured: `t = (x − center)/half_range` through the blue–white–red
/// map, so the median is white and the 98th percentile of the deviations from it
/// reaches the map's ends; the half range is at least 5 % of `|center|`, so that a
/// near-constant field (a circle's curvature) is near-white with its variation
/// still visible as faint tints, and a field of any sign keeps white at its median.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ColorScale {
    /// The attribute of the coloured field (`_CURVATURE`, `_NORMAL_VELOCITY`).
    field: String,
    center: f64,
    half_range: f64,
}

impl ColorScale {
    pub(super) fn of(values: &[f64], field: &str) -> ColorScale {
        let field = field.to_string();
        let mut a: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if a.is_empty() {
            return ColorScale { field, center: 0.0, half_range: 1.0 };
        }
        let mid = (a.len() - 1) / 2;
        let center = *a.select_nth_unstable_by(mid, f64::total_cmp).1;
        let mut dev: Vec<f64> = a.iter().map(|x| (x - center).abs()).collect();
        let i = ((dev.len() - 1) as f64 * 0.98).round() as usize;
        let spread = *dev.select_nth_unstable_by(i, f64::total_cmp).1;
        ColorScale { field, center, half_range: spread.max(0.05 * center.abs()).max(1e-12) }
    }

    pub(super) fn color(&self, x: f64) -> [f32; 3] {
        colormap((x - self.center) / self.half_range)
    }

    /// The record of the map in a node's extras.
    pub(super) fn extras(&self) -> Value {
        json!({"field": self.field, "map": "blue-white-red", "white": self.center,
               "blue": self.center - self.half_range, "red": self.center + self.half_range})
    }
}

/// Blue (−1) – white (0) – red (+1), linear RGB in [0, 1].
fn colormap(t: f64) -> [f32; 3] {
    let t = if t.is_finite() { t.clamp(-1.0, 1.0) } else { 0.0 };
    let (blue, white, red) = ([0.23, 0.30, 0.75], [0.87, 0.87, 0.87], [0.71, 0.02, 0.15]);
    let (a, b, s) = if t < 0.0 { (white, blue, -t) } else { (white, red, t) };
    std::array::from_fn(|k| (a[k] + (b[k] - a[k]) * s) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A near-constant field (a circle's curvature, 2 ± 1 %) is near-white with its
    /// variation visible; a varying one spans the map from its median.
    #[test]
    fn colors_show_variation_around_the_median() {
        let circle: Vec<f64> = (0..100).map(|k| 2.0 + 0.02 * ((k as f64) * 0.3).sin()).collect();
        let s = ColorScale::of(&circle, "_CURVATURE");
        assert!((s.center - 2.0).abs() < 0.02 && (s.half_range - 0.05 * s.center).abs() < 1e-12, "{s:?}");
        let white = colormap(0.0);
        let c = s.color(2.02);
        assert!(c != white && (c[1] - white[1]).abs() < 0.2, "{c:?}");
        let varied: Vec<f64> = (0..101).map(|k| k as f64 - 50.0).collect();
        let s = ColorScale::of(&varied, "_CURVATURE");
        assert_eq!(s.center, 0.0);
        assert!((s.half_range - 49.0).abs() < 1.0, "{s:?}");
        assert_eq!(s.color(50.0), colormap(1.0));
        assert_eq!(s.extras()["white"], 0.0);
    }
}
