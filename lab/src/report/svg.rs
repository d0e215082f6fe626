//! SVG line and scatter plots written by hand: a document ([`Svg`]), a plot area with its two
//! axes ([`Frame`] over linear or log [`Scale`]s) and what is drawn on it (ticks, reference
//! lines, curves, markers), legend entries, and text escaping. Layout positions are written as
//! computed; data points to 0.1 px.

use std::fmt::{self, Display, Write as _};

/// Colours of unnamed series, cycled in order.
pub const PALETTE: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf",
];

/// Escape text for SVG/XML content.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// An SVG document on a white background, written one line per [`Svg::add`].
pub struct Svg {
    s: String,
}

impl Svg {
    /// A `w` × `h` document in sans-serif at `font_size`.
    pub fn new(w: f64, h: f64, font_size: u32) -> Svg {
        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="{font_size}">"#
        );
        let _ = writeln!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
        Svg { s }
    }
    /// Append one line: an element, or several written together.
    pub fn add(&mut self, elements: impl Display) {
        let _ = writeln!(self.s, "{elements}");
    }
    /// The finished document.
    pub fn finish(mut self) -> String {
        self.s.push_str("</svg>\n");
        self.s
    }
}

/// How a line is drawn: colour, optional width and dash pattern.
#[derive(Debug, Clone, Copy)]
pub struct Stroke {
    colour: &'static str,
    width: Option<f64>,
    dashed: bool,
}

impl Stroke {
    /// A thin solid line of `colour`.
    pub const fn new(colour: &'static str) -> Stroke {
        Stroke {
            colour,
            width: None,
            dashed: false,
        }
    }
    /// The same line `width` wide.
    pub const fn width(self, width: f64) -> Stroke {
        Stroke {
            width: Some(width),
            ..self
        }
    }
    /// The same line dashed (4 on, 3 off).
    pub const fn dashed(self) -> Stroke {
        Stroke {
            dashed: true,
            ..self
        }
    }
}

impl Display for Stroke {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, r#"stroke="{}""#, self.colour)?;
        if let Some(w) = self.width {
            write!(f, r#" stroke-width="{w}""#)?;
        }
        if self.dashed {
            f.write_str(r#" stroke-dasharray="4 3""#)?;
        }
        Ok(())
    }
}

/// A point marker: a filled dot or an empty ring.
#[derive(Debug, Clone, Copy)]
pub enum Marker {
    /// A filled dot.
    Dot {
        /// Radius (px).
        r: f64,
        /// Fill colour.
        colour: &'static str,
    },
    /// An empty ring.
    Ring {
        /// Radius (px).
        r: f64,
        /// Line colour.
        colour: &'static str,
    },
}

impl Display for Marker {
    /// The circle's attributes after its centre.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Marker::Dot { r, colour } => write!(f, r#" r="{r}" fill="{colour}""#),
            Marker::Ring { r, colour } => write!(f, r#" r="{r}" fill="none" stroke="{colour}""#),
        }
    }
}

/// A straight line from (x1, y1) to (x2, y2).
pub fn line(x1: f64, y1: f64, x2: f64, y2: f64, stroke: Stroke) -> String {
    format!(r#"<line x1="{x1}" y1="{y1}" x2="{x2}" y2="{y2}" {stroke}/>"#)
}

/// A text element at (x, y), escaped; see [`text`].
pub struct Text<'a> {
    x: f64,
    y: f64,
    content: &'a str,
    anchor: Option<&'static str>,
    size: Option<u32>,
    bold: bool,
    fill: Option<&'static str>,
}

/// Text starting at (x, y) on its baseline.
pub fn text(x: f64, y: f64, content: &str) -> Text<'_> {
    Text {
        x,
        y,
        content,
        anchor: None,
        size: None,
        bold: false,
        fill: None,
    }
}

impl Text<'_> {
    /// Centred on x.
    pub fn middle(self) -> Self {
        Text {
            anchor: Some("middle"),
            ..self
        }
    }
    /// Ending at x.
    pub fn end(self) -> Self {
        Text {
            anchor: Some("end"),
            ..self
        }
    }
    /// In another font size.
    pub fn size(self, size: u32) -> Self {
        Text {
            size: Some(size),
            ..self
        }
    }
    /// In bold.
    pub fn bold(self) -> Self {
        Text { bold: true, ..self }
    }
    /// In another colour.
    pub fn fill(self, colour: &'static str) -> Self {
        Text {
            fill: Some(colour),
            ..self
        }
    }
}

impl Display for Text<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, r#"<text x="{}" y="{}""#, self.x, self.y)?;
        if let Some(a) = self.anchor {
            write!(f, r#" text-anchor="{a}""#)?;
        }
        if let Some(s) = self.size {
            write!(f, r#" font-size="{s}""#)?;
        }
        if self.bold {
            f.write_str(r#" font-weight="bold""#)?;
        }
        if let Some(c) = self.fill {
            write!(f, r#" fill="{c}""#)?;
        }
        write!(f, ">{}</text>", escape(self.content))
    }
}

/// Text centred on (x, y), reading upwards: the label of a y axis.
pub fn vertical_text(x: f64, y: f64, content: &str) -> String {
    format!(
        r#"<text transform="translate({x},{y}) rotate(-90)" text-anchor="middle">{}</text>"#,
        escape(content)
    )
}

/// A legend entry at (x, y): a 20 px stroke sample (with `marker` on its middle), then the
/// label.
pub fn legend_entry(x: f64, y: f64, stroke: Stroke, marker: Option<Marker>, label: &str) -> String {
    let mut s = line(x, y, x + 20.0, y, stroke);
    if let Some(m) = marker {
        let _ = write!(s, r#"<circle cx="{}" cy="{y}"{m}/>"#, x + 10.0);
    }
    let _ = write!(s, "{}", text(x + 24.0, y + 4.0, label));
    s
}

/// One axis: a linear range or a range of decades, mapping a value to a fraction of the axis.
#[derive(Debug, Clone, Copy)]
pub struct Scale {
    /// The ends of the axis, in its units (values, or decades: log10 of values).
    lo: f64,
    hi: f64,
    log: bool,
    /// Pin values outside the range to the axis ends.
    clamp: bool,
}

impl Scale {
    /// A linear axis from `lo` to `hi`.
    pub fn linear(lo: f64, hi: f64) -> Scale {
        Scale {
            lo,
            hi,
            log: false,
            clamp: false,
        }
    }
    /// A log axis over the whole decades covering [min, max] (values > 0), at least one
    /// decade wide.
    pub fn log_covering(min: f64, max: f64) -> Scale {
        let (mut lo, mut hi) = (min.log10().floor(), max.log10().ceil());
        if hi <= lo {
            lo -= 0.5;
            hi += 0.5;
        }
        Scale {
            lo,
            hi,
            log: true,
            clamp: false,
        }
    }
    /// The same axis, with values outside it drawn at its ends.
    pub fn clamped(self) -> Scale {
        Scale {
            clamp: true,
            ..self
        }
    }
    /// Where `v` lies along the axis: 0 at its start, 1 at its end.
    pub fn fraction(&self, v: f64) -> f64 {
        let u = if self.log { v.log10() } else { v };
        let f = (u - self.lo) / (self.hi - self.lo);
        if self.clamp { f.clamp(0.0, 1.0) } else { f }
    }
    /// Ticks every `step` axis units (decades on a log axis) from the start to the end: each
    /// as (position in axis units, value).
    fn ticks(&self, step: f64) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        let mut u = self.lo;
        while u <= self.hi + 1e-9 {
            out.push((u, if self.log { 10f64.powf(u) } else { u }));
            u += step;
        }
        out
    }
}

/// A decade tick label: 10^d with a unit, as a decimal within 10^±3.
pub fn decade_label(d: f64, unit: &str) -> String {
    let v = 10f64.powf(d);
    if (-3.0..=3.0).contains(&d) {
        let decimals = (-d).max(0.0) as usize;
        format!("{v:.decimals$} {unit}")
    } else {
        format!("1e{d:.0} {unit}")
    }
}

/// How ticks are drawn.
#[derive(Debug, Clone, Copy)]
pub enum TickStyle {
    /// A grid line across the whole plot area.
    Grid(&'static str),
    /// A mark outside the axis.
    Mark {
        /// Length (px).
        len: f64,
        /// Colour.
        colour: &'static str,
    },
}

/// The plot area of one panel: its position on the page and its two axes. Data values map to
/// page positions through [`Frame::px`] and [`Frame::py`] (y grows upwards).
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// Left edge (px).
    pub left: f64,
    /// Top edge (px).
    pub top: f64,
    /// Width (px).
    pub width: f64,
    /// Height (px).
    pub height: f64,
    /// The horizontal axis.
    pub x: Scale,
    /// The vertical axis.
    pub y: Scale,
}

impl Frame {
    /// Right edge (px).
    pub fn right(&self) -> f64 {
        self.left + self.width
    }
    /// Bottom edge (px).
    pub fn bottom(&self) -> f64 {
        self.top + self.height
    }
    /// Page x of data x.
    pub fn px(&self, x: f64) -> f64 {
        self.left + self.x.fraction(x) * self.width
    }
    /// Page y of data y.
    pub fn py(&self, y: f64) -> f64 {
        self.bottom() - self.y.fraction(y) * self.height
    }
    /// A rectangle around the plot area.
    pub fn outline(&self, colour: &'static str) -> String {
        format!(
            r#"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="{colour}"/>"#,
            self.left, self.top, self.width, self.height
        )
    }
    /// The left and bottom axis lines.
    pub fn axes(&self, colour: &'static str) -> String {
        format!(
            r#"<path d="M{},{} V{} H{}" fill="none" stroke="{colour}"/>"#,
            self.left,
            self.top,
            self.bottom(),
            self.right()
        )
    }
    /// Ticks along the x axis every `step` axis units, labelled `gap` px below the plot
    /// area by `label` of the tick's axis position; one line each.
    pub fn x_ticks(
        &self,
        svg: &mut Svg,
        step: f64,
        style: TickStyle,
        gap: f64,
        label: impl Fn(f64) -> String,
    ) {
        for (u, v) in self.x.ticks(step) {
            let x = self.px(v);
            let (y1, y2, s) = match style {
                TickStyle::Grid(c) => (self.top, self.bottom(), Stroke::new(c)),
                TickStyle::Mark { len, colour } => {
                    (self.bottom(), self.bottom() + len, Stroke::new(colour))
                }
            };
            let name = label(u);
            svg.add(format_args!(
                "{}{}",
                line(x, y1, x, y2, s),
                text(x, self.bottom() + gap, &name).middle()
            ));
        }
    }
    /// Ticks along the y axis every `step` axis units, labelled `gap` px left of the plot
    /// area; one line each.
    pub fn y_ticks(
        &self,
        svg: &mut Svg,
        step: f64,
        style: TickStyle,
        gap: f64,
        label: impl Fn(f64) -> String,
    ) {
        for (u, v) in self.y.ticks(step) {
            let y = self.py(v);
            let (x1, x2, s) = match style {
                TickStyle::Grid(c) => (self.left, self.right(), Stroke::new(c)),
                TickStyle::Mark { len, colour } => {
                    (self.left - len, self.left, Stroke::new(colour))
                }
            };
            let name = label(u);
            svg.add(format_args!(
                "{}{}",
                line(x1, y, x2, y, s),
                text(self.left - gap, y + 4.0, &name).end()
            ));
        }
    }
    /// A horizontal reference line at data y across the plot area, labelled at its left end
    /// (`dy` px below the line; negative: above).
    pub fn y_reference(&self, y: f64, stroke: Stroke, label: &str, dy: f64) -> String {
        let py = self.py(y);
        format!(
            "{}{}",
            line(self.left, py, self.right(), py, stroke),
            text(self.left + 6.0, py + dy, label).fill("#666")
        )
    }
    /// A curve through data points as a `polyline`.
    pub fn polyline(&self, points: &[[f64; 2]], stroke: Stroke) -> String {
        let pts: Vec<String> = points
            .iter()
            .map(|p| format!("{:.1},{:.1}", self.px(p[0]), self.py(p[1])))
            .collect();
        format!(
            r#"<polyline points="{}" fill="none" {stroke}/>"#,
            pts.join(" ")
        )
    }
    /// A curve through data points as a `path`; `None` without points.
    pub fn path(&self, points: &[[f64; 2]], stroke: Stroke) -> Option<String> {
        let mut d = String::new();
        for (k, p) in points.iter().enumerate() {
            let _ = write!(
                d,
                "{}{:.1},{:.1}",
                if k == 0 { "M" } else { " L" },
                self.px(p[0]),
                self.py(p[1])
            );
        }
        (!d.is_empty()).then(|| format!(r#"<path d="{d}" fill="none" {stroke}/>"#))
    }
    /// A marker at a data point, with a hover `title` if given.
    pub fn marker(&self, p: [f64; 2], marker: Marker, title: Option<&str>) -> String {
        let (x, y) = (self.px(p[0]), self.py(p[1]));
        match title {
            Some(t) => format!(
                r#"<circle cx="{x:.1}" cy="{y:.1}"{marker}><title>{}</title></circle>"#,
                escape(t)
            ),
            None => format!(r#"<circle cx="{x:.1}" cy="{y:.1}"{marker}/>"#),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_map_their_ends() {
        let f = Frame {
            left: 10.0,
            top: 20.0,
            width: 100.0,
            height: 50.0,
            x: Scale::linear(0.0, 10.0).clamped(),
            y: Scale::log_covering(0.002, 0.3),
        };
        assert_eq!((f.px(0.0), f.px(10.0), f.px(20.0)), (10.0, 110.0, 110.0));
        assert_eq!((f.py(1e-3), f.py(1.0)), (70.0, 20.0));
        let half = Scale::log_covering(10.0, 10.0);
        // One decade, centred on the single value.
        let ticks: Vec<f64> = half.ticks(1.0).iter().map(|t| t.0).collect();
        assert_eq!(ticks, [0.5, 1.5]);
        assert_eq!(decade_label(-2.0, "s"), "0.01 s");
        assert_eq!(decade_label(5.0, "%"), "1e5 %");
    }

    #[test]
    fn elements_escape_their_text() {
        assert_eq!(
            text(1.0, 2.5, "a < b").middle().to_string(),
            r#"<text x="1" y="2.5" text-anchor="middle">a &lt; b</text>"#
        );
        assert_eq!(
            legend_entry(0.0, 10.0, Stroke::new("black").dashed(), None, "x"),
            r#"<line x1="0" y1="10" x2="20" y2="10" stroke="black" stroke-dasharray="4 3"/><text x="24" y="14">x</text>"#
        );
    }
}
