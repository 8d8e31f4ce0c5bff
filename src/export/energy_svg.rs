//! The energy history as an SVG plot: energy over iterations on a logarithmic axis
//! (decade grid lines and labels). Energies that are not all positive are shown as
//! `J − min J` (shifted, and said so in the axis label).

use crate::flow::Progress;
use std::fmt::Write;

const W: f64 = 720.0;
const H: f64 = 420.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 20.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 50.0;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// SVG document plotting `energy` against `iteration`, titled `title`.
pub fn energy_svg(history: &[Progress], title: &str) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">"#
    );
    let _ = write!(s, r#"<rect width="{W}" height="{H}" fill="white"/>"#);
    let _ = write!(s, r#"<text x="{}" y="24" text-anchor="middle" font-size="15">{}</text>"#, W / 2.0, escape(title));
    let pts: Vec<(f64, f64)> =
        history.iter().filter(|p| p.energy.is_finite()).map(|p| (p.iteration as f64, p.energy)).collect();
    if pts.is_empty() {
        let _ = write!(s, r#"<text x="{}" y="{}" text-anchor="middle">no history yet</text></svg>"#, W / 2.0, H / 2.0);
        return s;
    }
    let min = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
    let max = pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let shifted = min <= 0.0;
    let floor = if shifted { ((max - min) * 1e-6).max(f64::MIN_POSITIVE) } else { 0.0 };
    let val = |e: f64| if shifted { e - min + floor } else { e };
    let (lo, hi) =
        (pts.iter().map(|p| val(p.1)).fold(f64::INFINITY, f64::min), pts.iter().map(|p| val(p.1)).fold(0.0, f64::max));
    let (mut d0, mut d1) = (lo.log10().floor(), hi.log10().ceil());
    if d1 <= d0 {
        d1 = d0 + 1.0;
    }
    if d1 - d0 > 12.0 {
        d0 = d1 - 12.0;
    }
    let it_max = pts.last().map_or(1.0, |p| p.0.max(1.0));
    let x = |it: f64| LEFT + (W - LEFT - RIGHT) * it / it_max;
    let y = |v: f64| {
        let l = v.max(10f64.powf(d0)).log10();
        TOP + (H - TOP - BOTTOM) * (d1 - l) / (d1 - d0)
    };
    // grid: decades
    let mut d = d0;
    while d <= d1 + 1e-9 {
        let yy = y(10f64.powf(d));
        let _ = write!(s, r##"<line x1="{LEFT}" y1="{yy:.1}" x2="{:.1}" y2="{yy:.1}" stroke="#ddd"/>"##, W - RIGHT);
        let _ = write!(s, r#"<text x="{:.1}" y="{:.1}" text-anchor="end">1e{}</text>"#, LEFT - 6.0, yy + 4.0, d as i64);
        d += 1.0;
    }
    // x ticks
    for k in 0..=5 {
        let it = it_max * k as f64 / 5.0;
        let xx = x(it);
        let _ = write!(
            s,
            r##"<line x1="{xx:.1}" y1="{:.1}" x2="{xx:.1}" y2="{:.1}" stroke="#999"/>"##,
            H - BOTTOM,
            H - BOTTOM + 5.0
        );
        let _ = write!(
            s,
            r#"<text x="{xx:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            H - BOTTOM + 18.0,
            it.round() as i64
        );
    }
    let _ = write!(
        s,
        r##"<rect x="{LEFT}" y="{TOP}" width="{:.1}" height="{:.1}" fill="none" stroke="#333"/>"##,
        W - LEFT - RIGHT,
        H - TOP - BOTTOM
    );
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">iteration</text>"#,
        (LEFT + W - RIGHT) / 2.0,
        H - 12.0
    );
    let label = if shifted { format!("energy − ({min:.6e})") } else { "energy".to_string() };
    let _ = write!(
        s,
        r#"<text x="18" y="{:.1}" text-anchor="middle" transform="rotate(-90 18 {:.1})">{}</text>"#,
        (TOP + H - BOTTOM) / 2.0,
        (TOP + H - BOTTOM) / 2.0,
        escape(&label)
    );
    s.push_str(r##"<polyline fill="none" stroke="#1f5fbf" stroke-width="1.6" points=""##);
    for (i, (it, e)) in pts.iter().enumerate() {
        if i > 0 {
            s.push(' ');
        }
        let _ = write!(s, "{:.1},{:.1}", x(*it), y(val(*e)));
    }
    s.push_str(r#""/></svg>"#);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_every_point_on_a_log_axis() {
        let h: Vec<Progress> = (0..50)
            .map(|i| Progress {
                iteration: i,
                time: 0.0,
                tau: 0.0,
                energy: 10f64.powf(-(i as f64) / 10.0),
                vertices: 3,
                components: 1,
                surgery: None,
            })
            .collect();
        let svg = energy_svg(&h, "job <1>");
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>"));
        assert!(svg.contains("job &lt;1&gt;"));
        let pts = svg.split("points=\"").nth(1).unwrap().split('"').next().unwrap();
        assert_eq!(pts.split(' ').count(), 50);
        assert!(svg.contains(">1e0<") && svg.contains(">1e-5<"));
    }
}
