//! PNG figures of `diagnosis.md`, drawn with plotters' bitmap backend.
//!
//! Text needs a system font (plotters' `ttf` feature loads one through font-kit). On a
//! machine without fonts every figure is drawn again without text, so a report always
//! has its plots; [`Figure::draw`] says which way it went.

use std::path::Path;

use plotters::prelude::*;

use super::error::DiscrepancyError;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// Small translucent dots (clouds of samples).
    Dots,
    /// A line.
    Line,
    /// A thick line.
    Bold,
}

/// One series of an x–y figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points.
    pub points: Vec<(f64, f64)>,
    /// Drawing style.
    pub style: Style,
    /// Colour as RGB.
    pub rgb: (u8, u8, u8),
}

/// An x–y figure or a bar chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Title.
    pub title: String,
    /// x-axis description with unit.
    pub x_desc: String,
    /// y-axis description with unit.
    pub y_desc: String,
    /// Series (x–y figures).
    pub series: Vec<Series>,
    /// Bars `(label, value, highlighted)` (bar charts; `series` empty).
    pub bars: Vec<(String, f64, bool)>,
    /// Horizontal reference line (bar charts: the material floor).
    pub hline: Option<f64>,
}

/// Whether a figure has its text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Drawn {
    /// With title, labels and legend.
    WithText,
    /// Without text (no usable font).
    WithoutText,
}

fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() || !hi.is_finite() {
        return (0.0, 1.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        lo.abs().max(1.0) * 0.05
    };
    (lo - pad, hi + pad)
}

impl Figure {
    /// Draws the figure to `path` (PNG, 900 × 560), with text if a font can be loaded.
    ///
    /// # Errors
    /// [`DiscrepancyError::Write`] when neither way can be drawn or written.
    pub fn draw(&self, path: &Path) -> Result<Drawn, DiscrepancyError> {
        match self.render(path, true) {
            Ok(()) => Ok(Drawn::WithText),
            Err(first) => self
                .render(path, false)
                .map(|()| Drawn::WithoutText)
                .map_err(|second| DiscrepancyError::Write {
                    path: path.to_path_buf(),
                    reason: format!("{first}; without text: {second}"),
                }),
        }
    }

    fn render(&self, path: &Path, text: bool) -> Result<(), String> {
        let root = BitMapBackend::new(path, (900, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut builder = ChartBuilder::on(&root);
        builder.margin(16);
        if text {
            builder
                .caption(&self.title, ("sans-serif", 22))
                .x_label_area_size(44)
                .y_label_area_size(70);
        }
        if self.bars.is_empty() {
            let (x0, x1) = range(
                self.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.0)),
            );
            let (y0, y1) = range(
                self.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.1)),
            );
            let mut chart = builder
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(|e| e.to_string())?;
            let mut mesh = chart.configure_mesh();
            if text {
                mesh.x_desc(&self.x_desc).y_desc(&self.y_desc);
            } else {
                mesh.x_labels(0).y_labels(0);
            }
            mesh.draw().map_err(|e| e.to_string())?;
            for s in &self.series {
                let c = RGBColor(s.rgb.0, s.rgb.1, s.rgb.2);
                let anno = match s.style {
                    Style::Dots => chart
                        .draw_series(
                            s.points
                                .iter()
                                .map(|p| Circle::new(*p, 1, c.mix(0.35).filled())),
                        )
                        .map_err(|e| e.to_string())?,
                    Style::Line | Style::Bold => {
                        let w = if s.style == Style::Bold { 3 } else { 1 };
                        chart
                            .draw_series(LineSeries::new(
                                s.points.iter().copied(),
                                c.stroke_width(w),
                            ))
                            .map_err(|e| e.to_string())?
                    }
                };
                if text {
                    anno.label(&s.label).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
                    });
                }
            }
            if text {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| e.to_string())?;
            }
        } else {
            let n = self.bars.len();
            let (mut y0, mut y1) =
                range(self.bars.iter().map(|b| b.1).chain(self.hline).chain([0.0]));
            y0 = y0.min(0.0);
            y1 = y1.max(0.0);
            let mut chart = builder
                .build_cartesian_2d((0..n).into_segmented(), y0..y1)
                .map_err(|e| e.to_string())?;
            let names: Vec<String> = self.bars.iter().map(|b| b.0.clone()).collect();
            let fmt = move |x: &SegmentValue<usize>| match x {
                SegmentValue::CenterOf(i) | SegmentValue::Exact(i) => {
                    names.get(*i).cloned().unwrap_or_default()
                }
                SegmentValue::Last => String::new(),
            };
            let mut mesh = chart.configure_mesh();
            mesh.disable_x_mesh();
            if text {
                mesh.y_desc(&self.y_desc)
                    .x_desc(&self.x_desc)
                    .x_label_formatter(&fmt);
            } else {
                mesh.x_labels(0).y_labels(0);
            }
            mesh.draw().map_err(|e| e.to_string())?;
            chart
                .draw_series(self.bars.iter().enumerate().map(|(i, (_, v, hi))| {
                    let c = if *hi {
                        RGBColor(200, 60, 40)
                    } else {
                        RGBColor(90, 110, 160)
                    };
                    let mut r = Rectangle::new(
                        [
                            (SegmentValue::Exact(i), 0.0),
                            (SegmentValue::Exact(i + 1), *v),
                        ],
                        c.filled(),
                    );
                    r.set_margin(0, 0, 12, 12);
                    r
                }))
                .map_err(|e| e.to_string())?;
            if let Some(h) = self.hline {
                chart
                    .draw_series(LineSeries::new(
                        [(SegmentValue::Exact(0), h), (SegmentValue::Last, h)],
                        BLACK.stroke_width(2),
                    ))
                    .map_err(|e| e.to_string())?;
            }
        }
        root.present().map_err(|e| e.to_string())
    }
}
