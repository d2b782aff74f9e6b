//! The hand-written SVG plots of the Pareto sweep: one panel per cost (bake instructions
//! or time, bytes, fragments) against the error, log axes, the front of each panel marked.

use std::fmt::Write;

use billow::presets::pareto_front;

use super::{costs, Point, COLOURS};

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn tick_label(v: f64) -> String {
    if v >= 1e9 {
        format!("{}G", v / 1e9)
    } else if v >= 1e6 {
        format!("{}M", v / 1e6)
    } else if v >= 1e3 {
        format!("{}k", v / 1e3)
    } else if v >= 1.0 {
        format!("{v}")
    } else {
        format!("{v:.2}")
    }
}

/// Panels of error (linear) against each cost (log), every point drawn, the Pareto front
/// of each panel joined by a black step line with its points ringed and labelled.
pub fn svg(title: &str, points: &[Point]) -> String {
    let (pw, ph) = (430.0, 330.0);
    let (ml, mr, mt, mb) = (60.0, 14.0, 44.0, 50.0);
    let panels = costs(points);
    let width = pw * panels.len() as f64;
    let groups: Vec<String> = {
        let mut g: Vec<String> = Vec::new();
        for p in points {
            if !g.contains(&p.group) {
                g.push(p.group.clone());
            }
        }
        g
    };
    let height = ph + 40.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(
        s,
        r#"<rect width="100%" height="100%" fill="white"/><text x="{}" y="18" font-size="14" text-anchor="middle">{}</text>"#,
        width / 2.0,
        esc(title)
    );
    let y_max = points.iter().map(|p| p.mean.rmse).fold(0.0, f64::max) * 1.08;
    let y_min = points
        .iter()
        .map(|p| p.mean.rmse)
        .fold(f64::INFINITY, f64::min)
        * 0.92;
    let all = points;
    for (ci, (x_label, cost)) in panels.iter().enumerate() {
        // A log axis cannot show a zero cost (a cloud whose atlas starved: no fragments).
        let points: Vec<Point> = all.iter().filter(|p| cost(p) > 0.0).cloned().collect();
        let points = points.as_slice();
        let x0 = ci as f64 * pw;
        let (ax, ay, aw, ah) = (x0 + ml, mt, pw - ml - mr, ph - mt - mb + 20.0);
        let xs: Vec<f64> = points.iter().map(|p| cost(p).max(1e-9)).collect();
        let lo = xs.iter().copied().fold(f64::INFINITY, f64::min).log10() - 0.1;
        let hi = xs.iter().copied().fold(0.0, f64::max).log10() + 0.1;
        let px = |v: f64| ax + (v.max(1e-9).log10() - lo) / (hi - lo).max(1e-9) * aw;
        let py = |v: f64| ay + ah - (v - y_min) / (y_max - y_min).max(1e-12) * ah;
        let _ = writeln!(
            s,
            r##"<rect x="{ax}" y="{ay}" width="{aw}" height="{ah}" fill="none" stroke="#888"/>"##
        );
        for k in (lo.floor() as i32)..=(hi.ceil() as i32) {
            for m in [1.0, 2.0, 5.0] {
                let v = m * 10f64.powi(k);
                if !(lo..=hi).contains(&v.log10()) {
                    continue;
                }
                let x = px(v);
                let _ = writeln!(
                    s,
                    r##"<line x1="{x:.1}" y1="{ay}" x2="{x:.1}" y2="{:.1}" stroke="#eee"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
                    ay + ah,
                    ay + ah + 14.0,
                    tick_label(v)
                );
            }
        }
        for i in 0..=5 {
            let v = y_min + (y_max - y_min) * f64::from(i) / 5.0;
            let y = py(v);
            let _ = writeln!(
                s,
                r##"<line x1="{ax}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#eee"/><text x="{:.1}" y="{:.1}" text-anchor="end">{v:.4}</text>"##,
                ax + aw,
                ax - 4.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text transform="translate({:.1},{:.1}) rotate(-90)" text-anchor="middle">mean RMSE (1×, 4×, 16×)</text>"#,
            ax + aw / 2.0,
            ay + ah + 32.0,
            esc(x_label),
            x0 + 14.0,
            ay + ah / 2.0
        );
        for p in points {
            let g = groups.iter().position(|g| *g == p.group).unwrap_or(0);
            let c = COLOURS[g % COLOURS.len()];
            let fill = if p.hollow { "white" } else { c };
            let _ = writeln!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3" fill="{fill}" stroke="{c}" stroke-width="1.2"><title>{}</title></circle>"#,
                px(cost(p)),
                py(p.mean.rmse),
                esc(&p.label)
            );
        }
        let pts: Vec<(f64, f64)> = points.iter().map(|p| (cost(p), p.mean.rmse)).collect();
        let front = pareto_front(&pts);
        // A step line: the best error reachable at each cost.
        let mut path = Vec::new();
        for (k, &i) in front.iter().enumerate() {
            let (x, y) = (px(pts[i].0), py(pts[i].1));
            if k > 0 {
                let yp = py(pts[front[k - 1]].1);
                path.push(format!("{x:.1},{yp:.1}"));
            }
            path.push(format!("{x:.1},{y:.1}"));
        }
        let _ = writeln!(
            s,
            r##"<polyline points="{}" fill="none" stroke="#000" stroke-width="1.3"/>"##,
            path.join(" ")
        );
        for (k, &i) in front.iter().enumerate() {
            let (x, y) = (px(pts[i].0), py(pts[i].1));
            let _ = writeln!(
                s,
                r##"<circle cx="{x:.1}" cy="{y:.1}" r="5.5" fill="none" stroke="#000"/><text x="{:.1}" y="{:.1}" font-size="8.5">{}</text>"##,
                x + 6.0,
                y - 5.0 - 9.0 * (k % 2) as f64,
                esc(&points[i].label)
            );
        }
    }
    for (i, g) in groups.iter().enumerate() {
        let x = 20.0 + i as f64 * 90.0;
        let y = height - 12.0;
        let _ = writeln!(
            s,
            r#"<circle cx="{x}" cy="{:.1}" r="4" fill="{}"/><text x="{:.1}" y="{y:.1}">{}</text>"#,
            y - 4.0,
            COLOURS[i % COLOURS.len()],
            x + 8.0,
            esc(g)
        );
    }
    let _ = writeln!(
        s,
        r##"<text x="{:.1}" y="{:.1}" fill="#333">black line and rings: the Pareto front of each panel; hollow markers: {}</text>"##,
        20.0 + groups.len() as f64 * 90.0,
        height - 12.0,
        if points.iter().any(|p| p.label.contains('ε')) {
            "N 100 (filled: N 500)"
        } else {
            "BC7 (filled: raw RGBA8)"
        }
    );
    s.push_str("</svg>\n");
    s
}
