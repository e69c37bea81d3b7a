//! Charts for reports, as SVG (plotters' SVG backend: text, no fonts to
//! ship, opens in any browser): lines over an index (values per mission),
//! and grouped bars with intervals (a measure per group and series).

use anyhow::{Result, anyhow};
use plotters::prelude::*;

/// Colours of the series, in order (the picture legend's palette).
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("drawing a chart: {e}")
}

/// One line: a name and its points `(x, y)`; points with a non-finite `y`
/// break the line.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend.
    pub name: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
}

/// A line chart, `width × height` pixels; with `log_y` a logarithmic `y`
/// axis (non-positive values are left out).
pub fn lines(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    log_y: bool,
    size: (u32, u32),
) -> Result<String> {
    let finite = |y: f64| y.is_finite() && (!log_y || y > 0.0);
    let pts = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| finite(p.1));
    let (mut x0, mut x1, mut y0, mut y1) =
        (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, if log_y { 0.1 } else { 0.0 }, 1.0);
    }
    if x1 <= x0 {
        x1 = x0 + 1.0;
    }
    if log_y {
        (y0, y1) = (y0 / 1.5, y1 * 1.5);
    } else {
        let pad = ((y1 - y0) * 0.08).max(1e-9 * y1.abs().max(1.0));
        (y0, y1) = (if y0 >= 0.0 { (y0 - pad).max(0.0) } else { y0 - pad }, y1 + pad);
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let mut b = ChartBuilder::on(&root);
        b.caption(title, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(64);
        macro_rules! draw {
            ($chart:expr) => {{
                let mut chart = $chart;
                chart
                    .configure_mesh()
                    .x_desc(x_label)
                    .y_desc(y_label)
                    .light_line_style(RGBColor(235, 235, 235))
                    .draw()
                    .map_err(err)?;
                for (k, s) in series.iter().enumerate() {
                    let c = PALETTE[k % PALETTE.len()];
                    let mut run: Vec<(f64, f64)> = Vec::new();
                    let mut first = true;
                    for &(x, y) in s
                        .points
                        .iter()
                        .chain(std::iter::once(&(f64::NAN, f64::NAN)))
                    {
                        if finite(y) && x.is_finite() {
                            run.push((x, y));
                            continue;
                        }
                        if !run.is_empty() {
                            let line = chart
                                .draw_series(LineSeries::new(run.clone(), c.stroke_width(2)))
                                .map_err(err)?;
                            if first {
                                line.label(s.name.clone()).legend(move |(x, y)| {
                                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                                });
                                first = false;
                            }
                            chart
                                .draw_series(run.iter().map(|&p| Circle::new(p, 3, c.filled())))
                                .map_err(err)?;
                            run.clear();
                        }
                    }
                }
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(RGBColor(200, 200, 200))
                    .draw()
                    .map_err(err)?;
            }};
        }
        if log_y {
            draw!(b.build_cartesian_2d(x0..x1, (y0..y1).log_scale()).map_err(err)?);
        } else {
            draw!(b.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?);
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// One bar: the value and its interval (`low..high`; NaN for none).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bar {
    /// The value.
    pub value: f64,
    /// Lower end of its interval.
    pub low: f64,
    /// Upper end of its interval.
    pub high: f64,
}

/// How [`bars_with`] lays a chart out.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BarOptions {
    /// Top of the `y` axis; whiskers above it are cut at it. `None`: from
    /// the data (bars and whiskers), with headroom for a legend inside.
    pub y_max: Option<f64>,
    /// Width of a legend column right of the plot, pixels; `None`: the
    /// legend inside the plot, upper right.
    pub legend_px: Option<u32>,
}

/// Grouped bars: for each group (x axis) one bar per series, in the
/// palette's colours, with its interval as a whisker; the legend inside
/// the plot ([`bars_with`] with the default options).
pub fn bars(
    title: &str,
    y_label: &str,
    groups: &[String],
    series: &[String],
    values: &[Vec<Bar>],
    size: (u32, u32),
) -> Result<String> {
    bars_with(
        title,
        y_label,
        groups,
        series,
        values,
        size,
        BarOptions::default(),
    )
}

/// Grouped bars as [`bars`], laid out by `opts`. Each bar is one
/// `<rect>` from `y = 0` up to its value, in its series' colour, drawn
/// group by group in series order (tests read them back).
pub fn bars_with(
    title: &str,
    y_label: &str,
    groups: &[String],
    series: &[String],
    values: &[Vec<Bar>],
    size: (u32, u32),
    opts: BarOptions,
) -> Result<String> {
    let data_top = values
        .iter()
        .flatten()
        .flat_map(|b| [b.value, b.high])
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    let n = series.len().max(1) as f64;
    let top = match (opts.y_max, opts.legend_px) {
        (Some(t), _) if t > 0.0 && t.is_finite() => t,
        (_, Some(_)) if data_top > 0.0 => data_top * 1.05,
        _ => {
            // Headroom for the legend (about 20 px a row in the upper
            // right) above the tallest bar, so that it never hides one.
            let plot_px = f64::from(size.1.saturating_sub(36 + 24 + 30)).max(60.0);
            let legend = ((20.0 * n + 16.0) / plot_px).min(0.6);
            if data_top > 0.0 {
                data_top * 1.05 / (1.0 - legend)
            } else {
                1.0
            }
        }
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (plot_area, legend_area) = match opts.legend_px {
            Some(px) if px < size.0 => {
                let (a, b) = root.split_horizontally(size.0 - px);
                (a, Some(b))
            }
            _ => (root.clone(), None),
        };
        let mut chart = ChartBuilder::on(&plot_area)
            .caption(title, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(0f64..groups.len() as f64, 0f64..top)
            .map_err(err)?;
        let names = groups.to_vec();
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(groups.len() * 2 + 1)
            .x_label_formatter(&|x: &f64| {
                let k = x.floor() as usize;
                if (x - k as f64 - 0.5).abs() < 1e-6 {
                    names.get(k).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .y_desc(y_label)
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(err)?;
        for (s, name) in series.iter().enumerate() {
            let c = PALETTE[s % PALETTE.len()];
            let width = 0.8 / n;
            let mut first = true;
            for (g, row) in values.iter().enumerate() {
                let Some(b) = row.get(s) else { continue };
                if !b.value.is_finite() {
                    continue;
                }
                let x0 = g as f64 + 0.1 + s as f64 * width;
                let bar = chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x0, 0.0), (x0 + width * 0.9, b.value.min(top))],
                        c.filled(),
                    )))
                    .map_err(err)?;
                if first && legend_area.is_none() {
                    bar.label(name.clone())
                        .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], c.filled()));
                    first = false;
                }
                if b.low.is_finite() && b.high.is_finite() {
                    let xm = x0 + width * 0.45;
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            vec![(xm, b.low.clamp(0.0, top)), (xm, b.high.clamp(0.0, top))],
                            BLACK.stroke_width(1),
                        )))
                        .map_err(err)?;
                }
            }
        }
        match &legend_area {
            None => chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(200, 200, 200))
                .draw()
                .map_err(err)?,
            Some(area) => {
                for (s, name) in series.iter().enumerate() {
                    let c = PALETTE[s % PALETTE.len()];
                    let y = 48 + 22 * s as i32;
                    area.draw(&Rectangle::new([(4, y - 6), (16, y + 6)], c.filled()))
                        .map_err(err)?;
                    area.draw(&Text::new(name.clone(), (22, y - 7), ("sans-serif", 13)))
                        .map_err(err)?;
                }
            }
        }
        root.present().map_err(err)?;
    }
    Ok(svg)
}

/// The chart made scalable for inline use: a `viewBox` of `size` on the
/// `<svg>` element (the page's CSS then sets its width), and `desc` — plain
/// text, escaped here — as its `<desc>` (what screen readers and tests
/// read).
pub fn scalable(svg: &str, size: (u32, u32), desc: &str) -> String {
    let Some(start) = svg.find("<svg") else {
        return svg.to_string();
    };
    let Some(end) = svg[start..].find('>').map(|k| start + k) else {
        return svg.to_string();
    };
    let (tag, rest) = (&svg[start..end], &svg[end + 1..]);
    let tag = if tag.contains("viewBox") {
        tag.to_string()
    } else {
        format!("{tag} viewBox=\"0 0 {} {}\"", size.0, size.1)
    };
    format!(
        "{}{tag}><desc>{}</desc>{rest}",
        &svg[..start],
        crate::page::html_escape(desc)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charts_are_svg_with_their_legends() {
        let s = lines(
            "f over missions",
            "mission",
            "throughput (1/s)",
            &[
                Series {
                    name: "f_auto".into(),
                    points: vec![(1.0, 0.008), (2.0, f64::NAN), (3.0, 0.009)],
                },
                Series {
                    name: "f_cont".into(),
                    points: vec![(1.0, 0.005), (2.0, 0.005), (3.0, 0.005)],
                },
            ],
            false,
            (640, 360),
        )
        .unwrap();
        assert!(s.starts_with("<svg") && s.contains("f_auto") && s.contains("f_cont"));
        let log = lines(
            "rates",
            "mission",
            "1/s",
            &[Series {
                name: "λ3".into(),
                points: vec![(1.0, 1e-3), (2.0, 0.0)],
            }],
            true,
            (640, 360),
        )
        .unwrap();
        assert!(log.contains("λ3"));
        let b = bars(
            "success",
            "share",
            &["empty".into(), "packed".into()],
            &["a".into(), "b".into()],
            &[
                vec![
                    Bar {
                        value: 1.0,
                        low: 0.9,
                        high: 1.0,
                    },
                    Bar {
                        value: 0.5,
                        low: 0.3,
                        high: 0.7,
                    },
                ],
                vec![
                    Bar {
                        value: 0.2,
                        low: f64::NAN,
                        high: f64::NAN,
                    },
                    Bar {
                        value: f64::NAN,
                        low: 0.0,
                        high: 0.0,
                    },
                ],
            ],
            (640, 360),
        )
        .unwrap();
        assert!(b.contains("<rect") && b.contains("packed"));
    }
}
