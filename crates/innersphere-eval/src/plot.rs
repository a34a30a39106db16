//! Line charts as PNG files (plotters), for the paper's figures (`ist bench paper`).

use innersphere::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// The font the charts draw their text with (DejaVu Sans Mono, free licence in `assets/`),
/// bundled so that no system font library is needed.
static FONT: &[u8] = include_bytes!("../assets/DejaVuSansMono.ttf");

fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled font is valid; a failure would only lose the text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One line of a chart: a name for the legend and its points.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Points (x, y); non-finite or (on log axes) non-positive points are skipped.
    pub points: Vec<(f64, f64)>,
}

/// Axes of a chart.
#[derive(Debug, Clone)]
pub struct Chart<'a> {
    /// Title above the chart.
    pub title: &'a str,
    /// Label of the x axis.
    pub x_label: &'a str,
    /// Label of the y axis.
    pub y_label: &'a str,
    /// Logarithmic x axis.
    pub log_x: bool,
    /// Logarithmic y axis.
    pub log_y: bool,
}

const COLORS: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn plot_err<E: std::fmt::Display>(e: E) -> Error {
    Error::Output(format!("chart: {e}"))
}

/// A tick label: few digits, no trailing zeros.
fn short(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if a >= 1e4 {
        format!("{:.0}k", v / 1e3)
    } else if a >= 10.0 {
        format!("{v:.0}")
    } else if a >= 0.1 {
        format!("{v:.2}")
    } else {
        format!("{v:.1e}")
    }
}

/// Draws `series` as lines with markers into the PNG file `path` (900 × 600).
pub fn line_chart(path: &Path, chart: &Chart, series: &[Series]) -> Result<()> {
    register();
    let ok = |&(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (!chart.log_x || x > 0.0) && (!chart.log_y || y > 0.0)
    };
    let pts: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(ok)
        .collect();
    if pts.is_empty() {
        return Err(Error::Output(format!(
            "chart {}: no points to draw",
            chart.title
        )));
    }
    let (mut x0, mut x1, mut y0, mut y1) = pts.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), &(x, y)| (a.min(x), b.max(x), c.min(y), d.max(y)),
    );
    let pad = |lo: &mut f64, hi: &mut f64, log: bool| {
        if log {
            *lo /= 1.3;
            *hi *= 1.3;
        } else {
            let w = (*hi - *lo).max(hi.abs() * 1e-3).max(1e-12);
            *lo -= 0.05 * w;
            *hi += 0.05 * w;
            if *lo > 0.0 && *lo < 0.3 * *hi {
                *lo = 0.0;
            }
        }
    };
    pad(&mut x0, &mut x1, chart.log_x);
    pad(&mut y0, &mut y1, chart.log_y);
    let root = BitMapBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    macro_rules! draw {
        ($xr:expr, $yr:expr) => {{
            let mut c = ChartBuilder::on(&root)
                .caption(chart.title, ("sans-serif", 22))
                .margin(12)
                .x_label_area_size(48)
                .y_label_area_size(72)
                .build_cartesian_2d($xr, $yr)
                .map_err(plot_err)?;
            c.configure_mesh()
                .x_labels(8)
                .y_labels(8)
                .x_label_formatter(&|x| short(*x))
                .y_label_formatter(&|y| short(*y))
                .x_desc(chart.x_label)
                .y_desc(chart.y_label)
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(plot_err)?;
            for (i, s) in series.iter().enumerate() {
                let col = COLORS[i % COLORS.len()];
                let p: Vec<(f64, f64)> = s.points.iter().copied().filter(ok).collect();
                c.draw_series(LineSeries::new(p.clone(), col.stroke_width(2)))
                    .map_err(plot_err)?
                    .label(s.name.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], col.stroke_width(2))
                    });
                c.draw_series(p.into_iter().map(|q| Circle::new(q, 3, col.filled())))
                    .map_err(plot_err)?;
            }
            c.configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 14))
                .position(SeriesLabelPosition::UpperLeft)
                .draw()
                .map_err(plot_err)?;
        }};
    }
    match (chart.log_x, chart.log_y) {
        (false, false) => draw!(x0..x1, y0..y1),
        (true, false) => draw!((x0..x1).log_scale(), y0..y1),
        (false, true) => draw!(x0..x1, (y0..y1).log_scale()),
        (true, true) => draw!((x0..x1).log_scale(), (y0..y1).log_scale()),
    }
    root.present().map_err(plot_err)?;
    Ok(())
}

/// A haptic session's force (N), tool depth (mm) and tick time (µs) against time, three
/// panels one above the other (900 × 900 PNG).
pub fn haptic_chart(path: &Path, run: &crate::haptic::HapticRun) -> Result<()> {
    register();
    let root = BitMapBackend::new(path, (900, 900)).into_drawing_area();
    root.fill(&WHITE).map_err(plot_err)?;
    let panels = root.split_evenly((3, 1));
    let t_end = run.ticks.last().map_or(1.0, |r| r.t).max(1e-9);
    let t0 = run.ticks.first().map_or(0.0, |r| r.t);
    type Value = Box<dyn Fn(&crate::haptic::TickRecord) -> f64>;
    let series: [(&str, &str, Value); 3] = [
        (
            "force sent to the device",
            "N",
            Box::new(|r| r.tick.force.length()),
        ),
        (
            "tool penetration depth",
            "mm",
            Box::new(|r| r.tick.max_depth),
        ),
        (
            "tick compute time",
            "µs",
            Box::new(|r| r.tick.compute * 1e6),
        ),
    ];
    for (area, (title, unit, f)) in panels.iter().zip(series.iter()) {
        let pts: Vec<(f64, f64)> = run
            .ticks
            .iter()
            .map(|r| (r.t, f(r)))
            .filter(|p| p.1.is_finite())
            .collect();
        let ymax = pts.iter().map(|p| p.1).fold(0.0, f64::max).max(1e-9) * 1.1;
        let mut chart = ChartBuilder::on(area)
            .caption(*title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(t0..t_end, 0.0..ymax)
            .map_err(plot_err)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc(*unit)
            .y_label_formatter(&|v| short(*v))
            .draw()
            .map_err(plot_err)?;
        chart
            .draw_series(LineSeries::new(pts, COLORS[0].stroke_width(1)))
            .map_err(plot_err)?;
    }
    root.present().map_err(plot_err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_a_png() {
        let dir = std::env::temp_dir().join(format!("innersphere-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.png");
        let s = [Series {
            name: "a".into(),
            points: vec![(1.0, 2.0), (10.0, 5.0), (100.0, 4.0)],
        }];
        let c = Chart {
            title: "test",
            x_label: "x",
            y_label: "y",
            log_x: true,
            log_y: false,
        };
        line_chart(&path, &c, &s).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[1..4], b"PNG");
        let empty = [Series {
            name: "e".into(),
            points: vec![(f64::NAN, 1.0)],
        }];
        assert!(line_chart(&path, &c, &empty).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
