//! An RGB pixel buffer with the few drawing operations the legends need: filled rectangles,
//! thick lines, and text in the embedded 5×7 font (`_` starts a subscript run).

use super::font;

pub(super) struct Canvas {
    pub w: usize,
    pub h: usize,
    pub px: Vec<u8>,
}

impl Canvas {
    pub fn new(w: usize, h: usize, bg: [u8; 3]) -> Canvas {
        let mut px = vec![0u8; w * h * 3];
        for p in px.chunks_exact_mut(3) {
            p.copy_from_slice(&bg);
        }
        Canvas { w, h, px }
    }

    pub fn set(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = (y as usize * self.w + x as usize) * 3;
            self.px[i..i + 3].copy_from_slice(&c);
        }
    }

    pub fn rect(&mut self, x: i64, y: i64, w: i64, h: i64, c: [u8; 3]) {
        for yy in y..y + h {
            for xx in x..x + w {
                self.set(xx, yy, c);
            }
        }
    }

    /// A line of half-width `r` pixels (a square brush: 2r + 1 pixels wide).
    pub fn line(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), c: [u8; 3], r: i64) {
        let n = ((x1 - x0).abs().max((y1 - y0).abs()).ceil() as usize).clamp(1, 1_000_000);
        for i in 0..=n {
            let t = i as f64 / n as f64;
            let x = (x0 + t * (x1 - x0)).floor() as i64;
            let y = (y0 + t * (y1 - y0)).floor() as i64;
            self.rect(x - r, y - r, 2 * r + 1, 2 * r + 1, c);
        }
    }

    /// Draw `s` with its top-left corner at (x, y), each font pixel `scale` pixels square.
    /// `_` makes the following letters and digits a subscript (smaller, lowered).
    pub fn text(&mut self, x: i64, y: i64, s: &str, scale: i64, c: [u8; 3]) {
        let mut cx = x;
        for (ch, sub) in runs(s) {
            let sc = if sub { sub_scale(scale) } else { scale };
            let mut dy = if sub { SUB_DROP * scale } else { 0 };
            if font::descends(ch) {
                dy += font::DESCENT * sc;
            }
            for (row, bits) in font::glyph(ch).iter().enumerate() {
                for col in 0..font::W {
                    if bits & (0x10 >> col) != 0 {
                        self.rect(cx + col * sc, y + dy + row as i64 * sc, sc, sc, c);
                    }
                }
            }
            cx += font::ADVANCE * sc;
        }
    }
}

/// Width in pixels of `s` as [`Canvas::text`] draws it.
pub(super) fn text_width(s: &str, scale: i64) -> i64 {
    runs(s)
        .map(|(_, sub)| font::ADVANCE * if sub { sub_scale(scale) } else { scale })
        .sum()
}

/// Height in pixels of a line of text (descenders and subscripts included).
pub(super) fn text_height(scale: i64) -> i64 {
    (font::H + font::DESCENT + SUB_DROP) * scale
}

/// Font pixels a subscript is lowered by.
const SUB_DROP: i64 = 3;

/// Subscripts keep the size of the text (a smaller bitmap font would not be legible), lowered.
fn sub_scale(scale: i64) -> i64 {
    scale
}

/// The characters of `s` to draw, each flagged whether it is a subscript.
fn runs(s: &str) -> impl Iterator<Item = (char, bool)> + '_ {
    let mut sub = false;
    s.chars().filter_map(move |ch| {
        if ch == '_' {
            sub = true;
            return None;
        }
        if !ch.is_alphanumeric() {
            sub = false;
        }
        Some((ch, sub))
    })
}

/// The text with subscript marks removed (`σ_xx` → `σxx`), for reports.
pub(super) fn plain(s: &str) -> String {
    s.chars().filter(|c| *c != '_').collect()
}
