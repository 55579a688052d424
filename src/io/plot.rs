//! X–Y line plots (load–displacement curves, convergence histories, ...)
//! rendered to SVG with `plotters`.
//!
//! Computed series are drawn as lines with filled circle markers (thinned to
//! at most [`MAX_MARKERS`] per series), reference series (analytical or
//! published data) as open circles only. Colours cycle through the
//! ten-colour "tab10" palette. The legend is put in the plot corner that
//! contains the fewest data points.

use std::io;
use std::path::Path;

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;

use super::atomic::write_atomic;

/// Maximum number of markers drawn on one computed series; longer series
/// get markers on every k-th point only (the line uses all points).
pub const MAX_MARKERS: usize = 60;

/// Largest |log10| of a value on a logarithmic axis.
const MAX_DECADE: f64 = 300.0;

/// Width and height of the SVG image in pixels.
const SIZE: (u32, u32) = (900, 620);

/// One curve of an X–Y plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend label (an empty name gives no legend entry).
    pub name: String,
    /// Data points `(x, y)`, drawn in the given order.
    pub points: Vec<(f64, f64)>,
    /// `true` for reference data (markers only), `false` for computed
    /// results (line with markers).
    pub reference: bool,
}

/// Colours of the "tab10" palette (matplotlib default cycle).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Renders an X–Y plot and writes it to `path` as SVG, atomically (see
/// [`write_atomic`]).
///
/// Axis ranges are taken from the data with a 5 % margin (in decades on a
/// logarithmic axis). With `log_x` / `log_y` the respective axis is
/// logarithmic and all data on it must be strictly positive.
///
/// # Errors
/// [`io::ErrorKind::InvalidInput`] if there are no data points at all, a
/// coordinate is NaN or infinite, a value on a log axis is `<= 0`, or the
/// data range cannot be plotted (a linear span overflowing `f64`, log data
/// outside `1e-300..1e300` or spanning more than 300 decades, for which
/// `plotters` would hang); rendering and I/O errors otherwise.
pub fn plot_xy(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_x: bool,
    log_y: bool,
) -> io::Result<()> {
    let svg = plot_xy_svg(title, x_label, y_label, series, log_x, log_y)
        .map_err(|e| io::Error::new(e.kind(), format!("cannot plot '{}': {e}", path.display())))?;
    write_atomic(path, svg.as_bytes())
}

/// Renders the plot described in [`plot_xy`] and returns the SVG document.
///
/// # Errors
/// As [`plot_xy`], without the file I/O.
pub fn plot_xy_svg(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_x: bool,
    log_y: bool,
) -> io::Result<String> {
    validate(series, log_x, log_y).map_err(|m| io::Error::new(io::ErrorKind::InvalidInput, m))?;
    let invalid = |m| io::Error::new(io::ErrorKind::InvalidInput, m);
    let (x0, x1) = axis_range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        log_x,
        "x",
    )
    .map_err(invalid)?;
    let (y0, y1) = axis_range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        log_y,
        "y",
    )
    .map_err(invalid)?;
    let legend_pos = legend_position(series, (x0, x1, log_x), (y0, y1, log_y));

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        let labels = Labels {
            title,
            x_label,
            y_label,
            legend_pos,
        };
        let log_axis = |a: f64, b: f64| {
            let (bold, light) = log_key_points(a, b);
            (a..b)
                .log_scale()
                .with_key_points(bold)
                .with_light_points(light)
        };
        let res = match (log_x, log_y) {
            (false, false) => draw(&root, &labels, series, x0..x1, y0..y1, false, false),
            (true, false) => draw(
                &root,
                &labels,
                series,
                log_axis(x0, x1),
                y0..y1,
                true,
                false,
            ),
            (false, true) => draw(
                &root,
                &labels,
                series,
                x0..x1,
                log_axis(y0, y1),
                false,
                true,
            ),
            (true, true) => draw(
                &root,
                &labels,
                series,
                log_axis(x0, x1),
                log_axis(y0, y1),
                true,
                true,
            ),
        };
        res.and_then(|()| root.present().map_err(|e| e.to_string()))
            .map_err(|e| io::Error::other(format!("plot rendering failed: {e}")))?;
    }
    Ok(svg)
}

fn validate(series: &[Series], log_x: bool, log_y: bool) -> Result<(), String> {
    if series.iter().all(|s| s.points.is_empty()) {
        return Err("no data points to plot".to_string());
    }
    for s in series {
        for (i, &(x, y)) in s.points.iter().enumerate() {
            if !x.is_finite() || !y.is_finite() {
                return Err(format!(
                    "series '{}' has a non-finite point ({x}, {y}) at index {i}",
                    s.name
                ));
            }
            if (log_x && x <= 0.0) || (log_y && y <= 0.0) {
                return Err(format!(
                    "series '{}' has a non-positive value on a logarithmic axis: ({x}, {y}) at index {i}",
                    s.name
                ));
            }
        }
    }
    Ok(())
}

/// Data range with a 5 % margin; in log10 space for a log axis. A
/// degenerate range (single value, or a span below floating-point
/// resolution) is widened so that it is visible.
///
/// Returns an error if a linear range is not finite (e.g. data near
/// `±f64::MAX`) or log data lie outside `1e-300..1e300` or span more than
/// 300 decades: `plotters` would loop forever computing ticks for such
/// ranges.
fn axis_range(
    values: impl Iterator<Item = f64>,
    log: bool,
    axis: &str,
) -> Result<(f64, f64), String> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        let v = if log { v.log10() } else { v };
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let span = hi - lo;
    let scale = lo.abs().max(hi.abs());
    let pad = if span > 1e-12 * scale {
        0.05 * span
    } else if log {
        0.5
    } else if scale > 0.0 {
        0.05 * scale
    } else {
        1.0
    };
    if log {
        // plotters' log ticks loop forever if a bound overflows to infinity.
        if lo < -MAX_DECADE || hi > MAX_DECADE {
            return Err(format!(
                "{axis} data range [{:e}, {:e}] exceeds the plottable range 1e-{MAX_DECADE}..1e{MAX_DECADE} of a log axis",
                10f64.powf(lo),
                10f64.powf(hi)
            ));
        }
        let a = (lo - pad).max(-MAX_DECADE);
        let b = (hi + pad).min(MAX_DECADE);
        // ... and if the ratio of the bounds overflows.
        if b - a > MAX_DECADE {
            return Err(format!(
                "{axis} data range [{:e}, {:e}] spans more than {MAX_DECADE} decades",
                10f64.powf(lo),
                10f64.powf(hi)
            ));
        }
        Ok((10f64.powf(a), 10f64.powf(b)))
    } else {
        let (a, b) = (lo - pad, hi + pad);
        if !(b - a).is_finite() {
            return Err(format!(
                "{axis} data range [{lo:e}, {hi:e}] is too large to plot"
            ));
        }
        Ok((a, b))
    }
}

/// Picks the chart corner with the fewest data points for the legend.
fn legend_position(
    series: &[Series],
    (x0, x1, log_x): (f64, f64, bool),
    (y0, y1, log_y): (f64, f64, bool),
) -> SeriesLabelPosition {
    let norm = |v: f64, a: f64, b: f64, log: bool| {
        if log {
            (v.log10() - a.log10()) / (b.log10() - a.log10())
        } else {
            (v - a) / (b - a)
        }
    };
    // Corner boxes: 40 % of the width, 35 % of the height.
    let mut counts = [0usize; 4]; // UR, UL, LR, LL
    for s in series {
        for &(x, y) in &s.points {
            let (u, v) = (norm(x, x0, x1, log_x), norm(y, y0, y1, log_y));
            let (right, left) = (u > 0.6, u < 0.4);
            let (upper, lower) = (v > 0.65, v < 0.35);
            if upper && right {
                counts[0] += 1;
            }
            if upper && left {
                counts[1] += 1;
            }
            if lower && right {
                counts[2] += 1;
            }
            if lower && left {
                counts[3] += 1;
            }
        }
    }
    let positions = [
        SeriesLabelPosition::UpperRight,
        SeriesLabelPosition::UpperLeft,
        SeriesLabelPosition::LowerRight,
        SeriesLabelPosition::LowerLeft,
    ];
    // First minimum wins, so ties prefer the upper right corner.
    let best = (0..4).min_by_key(|&i| counts[i]).unwrap_or(0);
    positions[best].clone()
}

/// Exactly rounded `m * 10^k`.
fn pow10(m: u32, k: i32) -> f64 {
    format!("{m}e{k}").parse().unwrap_or(f64::NAN)
}

/// Tick positions `(labelled, grid-only)` for a log axis over `[lo, hi]`
/// (`0 < lo < hi`, both finite): 1-2-5 ticks within about two decades, one
/// per decade up to ten decades, every k-th decade beyond. (plotters' own
/// log ticks are very sparse, e.g. two labels over 60 decades.)
fn log_key_points(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let d0 = lo.log10().floor() as i32;
    let d1 = hi.log10().ceil() as i32;
    let ndec = d1 - d0;
    let inside = |v: &f64| *v >= lo && *v <= hi;
    let decade_mult = |mults: &[u32], step: i32| -> Vec<f64> {
        (d0..=d1)
            .filter(|k| k.rem_euclid(step) == 0)
            .flat_map(|k| mults.iter().map(move |&m| pow10(m, k)))
            .filter(inside)
            .collect()
    };
    let all = [1, 2, 3, 4, 5, 6, 7, 8, 9];
    let (mut bold, light) = if ndec <= 2 {
        (decade_mult(&[1, 2, 5], 1), decade_mult(&all, 1))
    } else if ndec <= 10 {
        let light = if ndec <= 6 {
            decade_mult(&all, 1)
        } else {
            decade_mult(&[1], 1)
        };
        (decade_mult(&[1], 1), light)
    } else {
        let step = (ndec + 9) / 10;
        (decade_mult(&[1], step), decade_mult(&[1], 1))
    };
    if bold.len() < 3 {
        bold = decade_mult(&all, 1);
    }
    if bold.len() < 3 {
        // Within a narrow range (about a factor of two): evenly spaced ticks.
        bold = (0..=4)
            .map(|i| lo + (hi - lo) * (0.1 + 0.2 * i as f64))
            .collect();
    }
    (bold, light)
}

/// Tick label for a logarithmic axis: plain for moderate magnitudes,
/// exponent notation otherwise.
fn log_tick(v: &f64) -> String {
    let a = v.abs();
    if (1e-3..1e4).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        let s = format!("{v:.2e}");
        match s.split_once('e') {
            Some((m, e)) => {
                let m = if m.contains('.') {
                    m.trim_end_matches('0').trim_end_matches('.')
                } else {
                    m
                };
                format!("{m}e{e}")
            }
            None => s,
        }
    }
}

struct Labels<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    legend_pos: SeriesLabelPosition,
}

#[allow(clippy::too_many_arguments)]
fn draw<X, Y>(
    root: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    labels: &Labels,
    series: &[Series],
    x_range: X,
    y_range: Y,
    log_x: bool,
    log_y: bool,
) -> Result<(), String>
where
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let e2s = |e: DrawingAreaErrorKind<_>| e.to_string();
    root.fill(&WHITE).map_err(e2s)?;
    let mut chart = ChartBuilder::on(root)
        .caption(labels.title, ("sans-serif", 24))
        .margin(15)
        .x_label_area_size(55)
        .y_label_area_size(80)
        .build_cartesian_2d(x_range, y_range)
        .map_err(e2s)?;

    {
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(labels.x_label)
            .y_desc(labels.y_label)
            .x_labels(10)
            .y_labels(10)
            .axis_desc_style(("sans-serif", 18))
            .label_style(("sans-serif", 14))
            .bold_line_style(BLACK.mix(0.15))
            .light_line_style(BLACK.mix(0.04));
        if log_x {
            mesh.x_label_formatter(&log_tick);
        }
        if log_y {
            mesh.y_label_formatter(&log_tick);
        }
        mesh.draw().map_err(e2s)?;
    }

    let mut any_label = false;
    for (i, s) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let pts = s.points.iter().copied();
        let anno = if s.reference {
            chart
                .draw_series(pts.map(|p| Circle::new(p, 5, color.stroke_width(2))))
                .map_err(e2s)?
        } else {
            let stride = s.points.len().div_ceil(MAX_MARKERS).max(1);
            chart
                .draw_series(
                    pts.clone()
                        .step_by(stride)
                        .map(|p| Circle::new(p, 3, color.filled())),
                )
                .map_err(e2s)?;
            chart
                .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                .map_err(e2s)?
        };
        if !s.name.is_empty() {
            any_label = true;
            // Same element type for both kinds: line (transparent for
            // reference data) plus a circle marker.
            let (line_style, marker_size, marker_style) = if s.reference {
                (ShapeStyle::from(&TRANSPARENT), 5, color.stroke_width(2))
            } else {
                (color.stroke_width(2), 3, color.filled())
            };
            anno.label(s.name.as_str()).legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (20, 0)], line_style)
                    + Circle::new((10, 0), marker_size, marker_style)
            });
        }
    }

    if any_label {
        chart
            .configure_series_labels()
            .position(labels.legend_pos.clone())
            .label_font(("sans-serif", 15))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .draw()
            .map_err(e2s)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn demo() -> Vec<Series> {
        vec![
            Series {
                name: "reference (Sze et al.)".into(),
                points: (0..=10)
                    .map(|i| (i as f64 * 0.1, (i as f64 * 0.1).sqrt()))
                    .collect(),
                reference: true,
            },
            Series {
                name: "plyshell 8x8".into(),
                points: (0..=200)
                    .map(|i| (i as f64 * 0.005, (i as f64 * 0.005).sqrt() * 0.97))
                    .collect(),
                reference: false,
            },
            Series {
                name: "plyshell 16x16".into(),
                points: (0..=20)
                    .map(|i| (i as f64 * 0.05, (i as f64 * 0.05).sqrt() * 0.99))
                    .collect(),
                reference: false,
            },
        ]
    }

    #[test]
    fn renders_linear_svg() {
        let svg = plot_xy_svg(
            "Tip load vs displacement",
            "u [mm]",
            "P [N]",
            &demo(),
            false,
            false,
        )
        .expect("render");
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains("Tip load vs displacement"));
        assert!(svg.contains("reference (Sze et al.)"));
        assert!(svg.contains("plyshell 16x16"));
        assert!(svg.contains("<polyline"));
        // Colours of the first three series are used.
        for c in ["#1F77B4", "#FF7F0E", "#2CA02C"] {
            assert!(svg.to_uppercase().contains(c), "{c}");
        }
    }

    #[test]
    fn renders_log_svg() {
        let conv = vec![Series {
            name: "residual".into(),
            points: (0..8)
                .map(|i| (i as f64 + 1.0, 10f64.powi(-2 * i)))
                .collect(),
            reference: false,
        }];
        let svg = plot_xy_svg("Newton convergence", "iteration", "|r|", &conv, false, true)
            .expect("render");
        assert!(svg.contains("1e-"));
        plot_xy_svg("loglog", "h", "err", &conv, true, true).expect("render log-log");
    }

    #[test]
    fn errors_instead_of_panics() {
        let kind = |r: io::Result<String>| r.expect_err("must fail").kind();
        assert_eq!(
            kind(plot_xy_svg("t", "x", "y", &[], false, false)),
            io::ErrorKind::InvalidInput
        );
        let empty = vec![Series {
            name: "e".into(),
            points: vec![],
            reference: false,
        }];
        assert_eq!(
            kind(plot_xy_svg("t", "x", "y", &empty, false, false)),
            io::ErrorKind::InvalidInput
        );
        let nan = vec![Series {
            name: "n".into(),
            points: vec![(0.0, 1.0), (1.0, f64::NAN)],
            reference: false,
        }];
        let err = plot_xy_svg("t", "x", "y", &nan, false, false).expect_err("nan");
        assert!(err.to_string().contains("'n'"), "{err}");
        let zero = vec![Series {
            name: "z".into(),
            points: vec![(0.0, 1.0), (1.0, 2.0)],
            reference: false,
        }];
        assert_eq!(
            kind(plot_xy_svg("t", "x", "y", &zero, true, false)),
            io::ErrorKind::InvalidInput
        );
        assert!(plot_xy_svg("t", "x", "y", &zero, false, true).is_ok());
        let p = std::env::temp_dir().join(format!("plyshell_plot_bad_{}.svg", std::process::id()));
        assert!(plot_xy(&p, "t", "x", "y", &nan, false, false).is_err());
        assert!(!p.exists());
    }

    #[test]
    fn degenerate_ranges() {
        let one = vec![Series {
            name: String::new(),
            points: vec![(1.0, 1.0)],
            reference: true,
        }];
        for (lx, ly) in [(false, false), (true, true)] {
            plot_xy_svg("single", "x", "y", &one, lx, ly).expect("single point");
        }
        let flat = vec![Series {
            name: "flat".into(),
            points: vec![(0.0, 0.0), (1.0, 0.0)],
            reference: false,
        }];
        plot_xy_svg("flat", "x", "y", &flat, false, false).expect("flat");
        let tiny = vec![Series {
            name: "tiny".into(),
            points: vec![(1.0, 1e-300), (2.0, 2e-300)],
            reference: false,
        }];
        plot_xy_svg("tiny", "x", "y", &tiny, false, false).expect("tiny");
        let near = vec![Series {
            name: "near".into(),
            points: vec![(1.0, 1.0), (2.0, 1.0 + 1e-15)],
            reference: false,
        }];
        plot_xy_svg("near", "x", "y", &near, false, false).expect("near-constant");
        plot_xy_svg("near", "x", "y", &near, false, true).expect("near-constant log");
        let wide = vec![Series {
            name: "wide".into(),
            points: vec![(1e-200, 1e-100), (1e50, 1e150)],
            reference: false,
        }];
        plot_xy_svg("wide", "x", "y", &wide, true, true).expect("250 decades");
        let wider = vec![Series {
            name: "wider".into(),
            points: vec![(1.0, 1e-300), (2.0, 1e300)],
            reference: false,
        }];
        let err = plot_xy_svg("wider", "x", "y", &wider, false, true).expect_err("600 decades");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        let sub = vec![Series {
            name: "sub".into(),
            points: vec![(1.0, 1e-310), (2.0, 1.0)],
            reference: false,
        }];
        let err =
            plot_xy_svg("sub", "x", "y", &sub, false, true).expect_err("subnormal on log axis");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(
            axis_range([2.0, 4.0].into_iter(), false, "x"),
            Ok((1.9, 4.1))
        );
        let (a, b) = axis_range([1.0, 100.0].into_iter(), true, "y").expect("range");
        assert!((a.log10() + 0.1).abs() < 1e-12 && (b.log10() - 2.1).abs() < 1e-12);
    }

    #[test]
    fn extreme_range_is_an_error() {
        let huge = vec![Series {
            name: "huge".into(),
            points: vec![(-f64::MAX, 1.0), (f64::MAX, 2.0)],
            reference: false,
        }];
        let err = plot_xy_svg("huge", "x", "y", &huge, false, false).expect_err("huge range");
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    }

    #[test]
    fn legend_avoids_data() {
        // Increasing curve: upper-left corner is empty.
        let s = vec![Series {
            name: "up".into(),
            points: (0..50).map(|i| (i as f64, i as f64)).collect(),
            reference: false,
        }];
        assert!(matches!(
            legend_position(&s, (0.0, 49.0, false), (0.0, 49.0, false)),
            SeriesLabelPosition::UpperLeft | SeriesLabelPosition::LowerRight
        ));
    }

    #[test]
    fn log_key_point_density() {
        let (b, _) = log_key_points(0.0148, 0.28);
        assert_eq!(b, vec![0.02, 0.05, 0.1, 0.2]);
        let (b, l) = log_key_points(1e-70, 3.0);
        assert!((5..=12).contains(&b.len()), "{b:?}");
        assert!(l.len() > 60);
        let (b, _) = log_key_points(1e-3, 1e3);
        assert_eq!(b.len(), 7);
        let (b, _) = log_key_points(2.0, 3.0);
        assert_eq!(b.len(), 5);
        let (b, _) = log_key_points(2.0, 9.5);
        assert_eq!(b, vec![2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    }

    #[test]
    fn log_ticks() {
        assert_eq!(log_tick(&1e-6), "1e-6");
        assert_eq!(log_tick(&0.01), "0.01");
        assert_eq!(log_tick(&100.0), "100");
        assert_eq!(log_tick(&2.5e7), "2.5e7");
    }
}
