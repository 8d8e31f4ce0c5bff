//! A wetting layer: the film stands on it as a mushroom.

use super::*;

/// Width of the gas at height `y` over one period: the film surface (the component
/// that winds around the cylinder, gas on its left as it runs in `+x`) crosses the
/// line `y`; the gas lies right of each downward crossing up to the next crossing.
fn gas_width(c: &CurveMesh, y: f64) -> f64 {
    let l = c.period().unwrap();
    let (surface, shift) =
        c.lifted_cycles().into_iter().zip(c.windings()).find(|(_, w)| *w != 0).map(|(p, _)| p).unwrap();
    let n = surface.len();
    let mut hits: Vec<(f64, bool)> = Vec::new();
    for k in 0..n {
        let (a, b) = (surface[k], if k + 1 == n { surface[0] + shift } else { surface[k + 1] });
        if (a.y - y) * (b.y - y) < 0.0 {
            let x = a.x + (y - a.y) / (b.y - a.y) * (b.x - a.x);
            hits.push((x.rem_euclid(l), b.y < a.y));
        }
    }
    hits.sort_by(|p, q| p.0.total_cmp(&q.0));
    (0..hits.len())
        .filter(|&i| hits[i].1)
        .map(|i| if i + 1 < hits.len() { hits[i + 1].0 - hits[i].0 } else { hits[0].0 + l - hits[i].0 })
        .sum()
}

/// How much wider the gas is somewhere below a height than at it: `max w(y₁) − w(y₂)`
/// over `y₁ < y₂` (0 for a graph). Positive: the film overhangs the gas (its caps
/// reach over a wider foot), a mushroom.
fn undercut(c: &CurveMesh) -> f64 {
    let ys: Vec<f64> = c.positions().iter().map(|p| p.y).collect();
    let (lo, hi) = (ys.iter().copied().fold(f64::INFINITY, f64::min), ys.iter().copied().fold(0.0, f64::max));
    let mut narrowest_above = f64::INFINITY;
    let mut best = 0.0f64;
    for k in (0..400).rev() {
        let w = gas_width(c, lo + (hi - lo) * (k as f64 + 0.5) / 400.0);
        narrowest_above = narrowest_above.min(w);
        best = best.max(w - narrowest_above);
    }
    best
}

/// With a wetting layer (`problem.wetting_layer`, an addition) the groove that
/// reaches the substrate spreads along the layer instead of ending the run: a thin
/// film (H = 0.4, γ = 0.15, 64 vertices) stands on it as a mushroom whose caps
/// overhang the channel. Measured: the crack reaches the layer at t = 0.0034; at
/// t = 0.012 the gas at the foot is 0.121 wider than at the neck.
#[test]
fn with_a_wetting_layer_the_film_stands_on_it_as_a_mushroom() {
    let spec = r#"{"problem": {"type": "stressed_film", "length": 1.0, "gamma": 0.15, "wetting_layer": 0.02},
        "initial": {"shape": "film", "height": 0.4, "amplitude": 0.02, "mode": 1, "resolution": 64},
        "flow": {"tau": 1e-5, "end_time": 0.012, "max_iterations": 1000000, "tolerance": 0}}"#;
    let job = job(spec);
    let mut flow = managed_flow(&job);
    let area0 = flow.mesh().enclosed_measure();
    let (mut lowest, mut on_layer, mut drift) = (f64::INFINITY, None, 0.0f64);
    loop {
        let r = flow.step().unwrap();
        if r.stop == Some(shapeflow::flow::StopReason::EndTime) {
            break;
        }
        assert!(r.stop.is_none(), "stopped {:?} at t = {}", r.stop, flow.time());
        let low = flow.mesh().positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        lowest = lowest.min(low);
        if low < 0.0201 && on_layer.is_none() {
            on_layer = Some(flow.time());
        }
        drift = drift.max((flow.mesh().enclosed_measure() / area0 - 1.0).abs());
    }
    let u = undercut(flow.mesh());
    println!(
        "on the layer from t = {on_layer:?}; lowest vertex {lowest}; largest area drift {drift:e}; undercut at t = {}: {u}",
        flow.time()
    );
    // the per-step correction keeps the area; what is left comes from the slivers
    // that reconnections at the crack tip drop (measured 1.3e-3), and the correction
    // offsets the surface on the layer by ~1e-4 (measured lowest 0.01986)
    assert!(drift < 2e-3, "film area drift {drift:e}");
    assert!(lowest > 0.0198, "below the wetting layer: {lowest}");
    assert!(on_layer.is_some_and(|t| t < 0.008), "the groove never reached the layer: {on_layer:?}");
    assert!(void_areas(flow.mesh()).is_empty(), "the channel closed");
    assert!(u > 0.08, "no overhang: {u}");
}
