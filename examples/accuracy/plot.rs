//! SVG plots, written by hand (no plotting dependency).

use std::fmt::Write as _;

use crate::volume::{MeshReport, Row};

pub(crate) const FAMILIES: [(&str, &str); 4] = [
    ("resolution", "#1f77b4"),
    ("supersampling", "#ff7f0e"),
    ("combine", "#2ca02c"),
    ("spacing", "#d62728"),
];

pub(crate) struct Panel<'a> {
    pub(crate) x_label: &'a str,
    pub(crate) x: fn(&Row) -> f64,
}

pub(crate) fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

pub(crate) fn nice_label(v: f64) -> String {
    if v >= 1e9 {
        format!("{:.0}G", v / 1e9)
    } else if v >= 1e6 {
        format!("{:.0}M", v / 1e6)
    } else if v >= 1e3 {
        format!("{:.0}k", v / 1e3)
    } else if v >= 1.0 {
        format!("{v:.0}")
    } else if v >= 0.01 {
        format!("{v:.2}")
    } else {
        format!("{v:.0e}")
    }
}

/// Three panels (error against bake cost, asset bytes, render cost), log x, linear y.
/// The costs are load-independent counts — bake instructions (wall seconds where they
/// could not be counted) and fragments shaded per view — not times of a shared machine.
pub(crate) fn plot(mesh: &MeshReport) -> String {
    let counted = mesh.rows.iter().all(|r| r.bake_instr.is_some());
    let bake = if counted {
        Panel {
            x_label: "bake instructions (callgrind, one thread)",
            x: |r| r.bake_instr.unwrap_or(0) as f64,
        }
    } else {
        Panel {
            x_label: "bake time (s)",
            x: |r| r.bake_s,
        }
    };
    let panels = [
        bake,
        Panel {
            x_label: "asset size (bytes)",
            x: |r| r.bytes as f64,
        },
        Panel {
            x_label: "fragments shaded per view (CPU slicer)",
            x: |r| r.fragments,
        },
    ];
    let (pw, ph) = (380.0, 300.0);
    let (ml, mr, mt, mb) = (56.0, 14.0, 40.0, 46.0);
    let width = 3.0 * pw;
    let height = ph + 40.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(
        s,
        r#"<rect width="100%" height="100%" fill="white"/><text x="{}" y="18" font-size="14" text-anchor="middle">{}: mean RMSE (premultiplied RGBA, 1×/4×/16× views) against cost — lower left is better</text>"#,
        width / 2.0,
        esc(&mesh.name)
    );
    let y_max = mesh
        .rows
        .iter()
        .map(|r| r.mean.rmse)
        .fold(mesh.raster.rmse, f64::max)
        * 1.1;
    for (pi, p) in panels.iter().enumerate() {
        let x0 = pi as f64 * pw;
        let (ax, ay, aw, ah) = (x0 + ml, mt, pw - ml - mr, ph - mt - mb + 20.0);
        let xs: Vec<f64> = mesh.rows.iter().map(|r| (p.x)(r).max(1e-6)).collect();
        let lo = xs.iter().copied().fold(f64::INFINITY, f64::min).log10();
        let hi = xs.iter().copied().fold(0.0, f64::max).log10();
        let (lo, hi) = (lo - 0.15, hi + 0.15);
        let px = |v: f64| ax + (v.max(1e-6).log10() - lo) / (hi - lo) * aw;
        let py = |v: f64| ay + ah - v / y_max * ah;
        let _ = writeln!(
            s,
            r##"<rect x="{ax}" y="{ay}" width="{aw}" height="{ah}" fill="none" stroke="#888"/>"##
        );
        // x ticks at 1, 2, 5 × 10^k.
        for k in (lo.floor() as i32)..=(hi.ceil() as i32) {
            for m in [1.0, 2.0, 5.0] {
                let v = m * 10f64.powi(k);
                let l = v.log10();
                if l < lo || l > hi {
                    continue;
                }
                let x = px(v);
                let _ = writeln!(
                    s,
                    r##"<line x1="{x:.1}" y1="{ay}" x2="{x:.1}" y2="{:.1}" stroke="#eee"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
                    ay + ah,
                    ay + ah + 14.0,
                    nice_label(v)
                );
            }
        }
        for i in 0..=4 {
            let v = y_max * f64::from(i) / 4.0;
            let y = py(v);
            let _ = writeln!(
                s,
                r##"<line x1="{ax}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#eee"/><text x="{:.1}" y="{:.1}" text-anchor="end">{v:.3}</text>"##,
                ax + aw,
                ax - 4.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text>"#,
            ax + aw / 2.0,
            ay + ah + 32.0,
            esc(p.x_label)
        );
        if pi == 0 {
            let _ = writeln!(
                s,
                r#"<text transform="translate({:.1},{:.1}) rotate(-90)" text-anchor="middle">mean RMSE</text>"#,
                x0 + 14.0,
                ay + ah / 2.0
            );
        }
        // The mesh drawn with 1 sample per pixel.
        let y = py(mesh.raster.rmse);
        let _ = writeln!(
            s,
            r##"<line x1="{ax}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#555" stroke-dasharray="5,4"/><text x="{:.1}" y="{:.1}" text-anchor="end" fill="#555">mesh, 1 spp (no AA)</text>"##,
            ax + aw,
            ax + aw - 4.0,
            y - 4.0
        );
        for (family, colour) in FAMILIES {
            let pts: Vec<(f64, f64, &str)> = mesh
                .rows
                .iter()
                .filter(|r| r.config.family == family)
                .map(|r| (px((p.x)(r)), py(r.mean.rmse), r.config.label.as_str()))
                .collect();
            let path: Vec<String> = pts
                .iter()
                .map(|(x, y, _)| format!("{x:.1},{y:.1}"))
                .collect();
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-opacity="0.5"/>"#,
                path.join(" ")
            );
            for (x, y, label) in pts {
                let _ = writeln!(
                    s,
                    r#"<circle cx="{x:.1}" cy="{y:.1}" r="3.5" fill="{colour}"/><text x="{:.1}" y="{:.1}" font-size="9" fill="{colour}">{}</text>"#,
                    x + 5.0,
                    y - 4.0,
                    esc(label)
                );
            }
        }
    }
    // Legend.
    for (i, (family, colour)) in FAMILIES.iter().enumerate() {
        let x = 60.0 + i as f64 * 150.0;
        let y = height - 10.0;
        let _ = writeln!(
            s,
            r#"<circle cx="{x}" cy="{:.1}" r="4" fill="{colour}"/><text x="{:.1}" y="{y:.1}">{family}</text>"#,
            y - 4.0,
            x + 8.0
        );
    }
    s.push_str("</svg>\n");
    s
}

/// One line of points `(x, y, label)` on a [`Chart`].
pub(crate) struct Series {
    pub(crate) name: String,
    pub(crate) colour: &'static str,
    pub(crate) points: Vec<(f64, f64, String)>,
    pub(crate) dashed: bool,
}

/// One panel: axes (log or linear) and its series.
pub(crate) struct Chart {
    pub(crate) x_label: String,
    pub(crate) y_label: String,
    pub(crate) log_x: bool,
    pub(crate) log_y: bool,
    pub(crate) series: Vec<Series>,
}

/// Panels side by side with a shared title and a legend of the first panel's series.
pub(crate) fn charts_svg(title: &str, charts: &[Chart]) -> String {
    let (pw, ph) = (420.0, 300.0);
    let (ml, mr, mt, mb) = (62.0, 14.0, 40.0, 46.0);
    let width = pw * charts.len() as f64;
    let height = ph + 56.0;
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
    for (ci, c) in charts.iter().enumerate() {
        let x0 = ci as f64 * pw;
        let (ax, ay, aw, ah) = (x0 + ml, mt, pw - ml - mr, ph - mt - mb + 20.0);
        let pts = c.series.iter().flat_map(|s| s.points.iter());
        let f = |v: f64, log: bool| if log { v.max(1e-9).log10() } else { v };
        let (mut xl, mut xh, mut yl, mut yh) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for p in pts {
            xl = xl.min(f(p.0, c.log_x));
            xh = xh.max(f(p.0, c.log_x));
            yl = yl.min(f(p.1, c.log_y));
            yh = yh.max(f(p.1, c.log_y));
        }
        if !xl.is_finite() {
            continue;
        }
        let pad = |lo: f64, hi: f64, log: bool| {
            let d = if hi > lo { hi - lo } else { 1.0 };
            if log {
                (lo - 0.08 * d - 0.05, hi + 0.08 * d + 0.05)
            } else if lo >= 0.0 {
                (0.0, hi + 0.08 * d)
            } else {
                (lo - 0.08 * d, hi + 0.08 * d)
            }
        };
        let (xl, xh) = pad(xl, xh, c.log_x);
        let (yl, yh) = pad(yl, yh, c.log_y);
        let px = |v: f64| ax + (f(v, c.log_x) - xl) / (xh - xl) * aw;
        let py = |v: f64| ay + ah - (f(v, c.log_y) - yl) / (yh - yl) * ah;
        let _ = writeln!(
            s,
            r##"<rect x="{ax}" y="{ay}" width="{aw}" height="{ah}" fill="none" stroke="#888"/>"##
        );
        let ticks = |lo: f64, hi: f64, log: bool| -> Vec<f64> {
            if log {
                let mut t = Vec::new();
                for k in (lo.floor() as i32)..=(hi.ceil() as i32) {
                    for m in [1.0, 2.0, 5.0] {
                        let v = m * 10f64.powi(k);
                        if (lo..=hi).contains(&v.log10()) {
                            t.push(v);
                        }
                    }
                }
                t
            } else {
                // A 1, 2 or 5 × 10^k step giving at most 6 ticks.
                let raw = (hi - lo) / 5.0;
                let k = 10f64.powf(raw.log10().floor());
                let step = [1.0, 2.0, 5.0, 10.0]
                    .iter()
                    .map(|m| m * k)
                    .find(|st| *st >= raw)
                    .unwrap_or(10.0 * k);
                let mut t = Vec::new();
                let mut v = (lo / step).ceil() * step;
                while v <= hi + 1e-9 * step {
                    t.push(v);
                    v += step;
                }
                t
            }
        };
        let lin_label = |v: f64| {
            if v == 0.0 || v.abs() >= 1.0 && v.fract() == 0.0 {
                format!("{v:.0}")
            } else if v.abs() >= 0.01 {
                format!("{v:.3}")
            } else {
                format!("{v:.1e}")
            }
        };
        for v in ticks(xl, xh, c.log_x) {
            let x = px(v);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{ay}" x2="{x:.1}" y2="{:.1}" stroke="#eee"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
                ay + ah,
                ay + ah + 14.0,
                if c.log_x { nice_label(v) } else { lin_label(v) }
            );
        }
        for v in ticks(yl, yh, c.log_y) {
            let y = py(v);
            let _ = writeln!(
                s,
                r##"<line x1="{ax}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#eee"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
                ax + aw,
                ax - 4.0,
                y + 4.0,
                if c.log_y {
                    format!("{v:.0e}")
                } else {
                    lin_label(v)
                }
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{}</text><text transform="translate({:.1},{:.1}) rotate(-90)" text-anchor="middle">{}</text>"#,
            ax + aw / 2.0,
            ay + ah + 32.0,
            esc(&c.x_label),
            x0 + 14.0,
            ay + ah / 2.0,
            esc(&c.y_label)
        );
        for se in &c.series {
            let path: Vec<String> = se
                .points
                .iter()
                .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
                .collect();
            let dash = if se.dashed {
                r#" stroke-dasharray="5,4""#
            } else {
                ""
            };
            let _ = writeln!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{}" stroke-opacity="0.6"{dash}/>"#,
                path.join(" "),
                se.colour
            );
            for p in &se.points {
                let _ = writeln!(
                    s,
                    r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{c}"/><text x="{:.1}" y="{:.1}" font-size="9" fill="{c}">{}</text>"#,
                    px(p.0),
                    py(p.1),
                    px(p.0) + 5.0,
                    py(p.1) - 4.0,
                    esc(&p.2),
                    c = se.colour
                );
            }
        }
    }
    // A legend under each panel.
    for (ci, c) in charts.iter().enumerate() {
        for (i, se) in c.series.iter().enumerate() {
            let x = ci as f64 * pw + 20.0 + (i % 3) as f64 * 135.0;
            let y = height - 22.0 + (i / 3) as f64 * 13.0;
            let _ = writeln!(
                s,
                r#"<circle cx="{x}" cy="{:.1}" r="4" fill="{}"/><text x="{:.1}" y="{y:.1}" font-size="10">{}</text>"#,
                y - 4.0,
                se.colour,
                x + 8.0,
                esc(&se.name)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}
