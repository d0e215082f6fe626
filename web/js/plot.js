// The dashboard's one plotting module: an interactive SVG line plot of our own (no
// third-party code; docs/dashboard.md says why). Every plot of every page is a `Plot`.
//
// - series toggled from the legend (real buttons, aria-pressed); Shift-click shows only one
// - hover (mouse, touch or keyboard arrows): a crosshair and every visible series' value at
//   that time, with units
// - drag across the plot to zoom on time; the wheel zooms around the cursor once the plot
//   is focused (click it) or with Ctrl; Shift-drag, Shift-wheel, a horizontal wheel or
//   PageUp / PageDown pan; double-click, Escape or "Reset zoom" reset; + / − zoom from the
//   keyboard
// - labelled horizontal reference lines (wave speeds)
// - live: `push`/`setData` then the plot redraws once on the next animation frame
// - many points are reduced to first/min/max/last per pixel column before drawing
//
// The pure parts (ticks, zoom and pan transforms, nearest sample, thinning, legend state,
// hover rows) are exported and tested in web/test/plot.test.mjs.

import { h, num, replace, si, siPrefix, saveBlob } from './util.js';
import { standaloneSvg, svgToPng, plotFileName } from './download.js';

/** Colour-blind-safe palette (Okabe & Ito) plus a few extra hues. */
export const PALETTE = ['#0072B2', '#D55E00', '#009E73', '#CC79A7', '#E69F00', '#56B4E9', '#7F3C8D', '#4D4D4D', '#A6761D', '#1B9E77'];
export const DASHES = ['', '6 3', '2 3', '8 3 2 3'];

const M = { left: 58, right: 16, top: 12, bottom: 38 };
let plotCounter = 0;

function esc(s) {
  return String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
}

/** Vertical distance (px) two reference-line labels in one column keep (11 px text with its halo). */
export const LABEL_GAP_PX = 14;
/** Width of one label character (px), an estimate for the 11 px font. */
const LABEL_CHAR_PX = 6.3;

/**
 * Place reference-line labels ({y, text}, y in px) in `columns` columns: each label keeps
 * its line's y in the first column where it is at least `gap` below the column's last
 * label; when no column has room it goes to the column whose last label is highest, pushed
 * down to `gap` below it. Returns [{y, text, column}] sorted by y (the input is not changed).
 */
export function placeLabels(labels, columns, gap) {
  const last = new Array(Math.max(1, columns)).fill(-Infinity);
  return labels.map((l) => ({ ...l })).sort((a, b) => a.y - b.y).map((l) => {
    let c = last.findIndex((y) => l.y - y >= gap);
    let y = l.y;
    if (c < 0) {
      c = last.indexOf(Math.min(...last));
      y = last[c] + gap;
    }
    last[c] = y;
    return { ...l, y, column: c };
  });
}

/** About `n` "nice" ticks (1, 2, 2.5, 5 × 10^k) covering [lo, hi]. */
export function niceTicks(lo, hi, n = 5) {
  if (!(hi > lo)) return [lo];
  const raw = (hi - lo) / Math.max(1, n);
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
  const out = [];
  const k0 = Math.ceil(lo / step - 1e-9);
  for (let k = k0; k * step <= hi + step * 1e-9 && out.length <= 50; k++) {
    out.push(k === 0 ? 0 : Number((k * step).toPrecision(12)));
  }
  return out;
}

/** Index of the sample of sorted `xs` nearest to x (-1 when empty; ties go left). */
export function nearestIndex(xs, x) {
  let lo = 0, hi = xs.length - 1;
  if (hi < 0) return -1;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (xs[mid] < x) lo = mid; else hi = mid;
  }
  return Math.abs(xs[lo] - x) <= Math.abs(xs[hi] - x) ? lo : hi;
}

/** First index with xs[i] >= x (xs ascending). */
export function lowerBound(xs, x) {
  let lo = 0, hi = xs.length;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (xs[mid] < x) lo = mid + 1; else hi = mid;
  }
  return lo;
}

/** Smallest shown span, as a fraction of the full range (deeper zooms stop there). */
export const MIN_SPAN = 1e-6;

/**
 * Zoom the shown range `[x0, x1]` by `factor` around `center` (factor < 1 zooms in). With
 * the full range `full` ([lo, hi] or null): a result that covers it is `null` (unzoomed),
 * one that sticks out is shifted back inside, and no span gets below MIN_SPAN of it.
 */
export function zoomAround([x0, x1], center, factor, full = null) {
  if (!(factor > 0) || !(x1 > x0)) return [x0, x1];
  const c = Math.min(Math.max(center, x0), x1);
  let a = c - (c - x0) * factor, b = c + (x1 - c) * factor;
  if (!full) return [a, b];
  const fs = full[1] - full[0];
  if (b - a >= fs) return null;
  const min = fs * MIN_SPAN;
  if (b - a < min) { const f = (c - a) / (b - a); a = c - f * min; b = a + min; }
  return clampInside([a, b], full);
}

/** Shift `[x0, x1]` by `dx`, kept inside `full` when given (the span does not change). */
export function panBy([x0, x1], dx, full = null) {
  const r = [x0 + dx, x1 + dx];
  return full ? clampInside(r, full) : r;
}

function clampInside([a, b], [lo, hi]) {
  if (b - a >= hi - lo) return [lo, hi];
  if (a < lo) return [lo, lo + (b - a)];
  if (b > hi) return [hi - (b - a), hi];
  return [a, b];
}

/**
 * The data range selected by a drag from pixel `p0` to `p1` on an axis whose plot area
 * runs from pixel `left` over `width` pixels showing `[x0, x1]`; the drag is clipped to the
 * area; `null` when it spans `minPx` pixels or fewer (a click, not a zoom).
 */
export function dragRange(p0, p1, { left, width, x0, x1 }, minPx = 5) {
  const a = Math.max(left, Math.min(p0, p1)), b = Math.min(left + width, Math.max(p0, p1));
  if (!(b - a > minPx)) return null;
  const ix = (p) => x0 + ((p - left) / width) * (x1 - x0);
  return [ix(a), ix(b)];
}

/**
 * Indices of the samples `a … b-1` to draw when `col(x)` gives the pixel column of x: all
 * of them when there are at most two per column, else per column the first, lowest,
 * highest and last (so spikes stay visible); a non-finite y (a gap) is always kept.
 */
export function thinIndices(xs, ys, a, b, col, columns) {
  const out = [];
  if (b - a <= 2 * columns) { for (let i = a; i < b; i++) out.push(i); return out; }
  let c = null, first, last, mnI, mxI;
  const flush = () => {
    if (c === null) return;
    for (const i of [...new Set([first, mnI, mxI, last])].sort((p, q) => p - q)) out.push(i);
    c = null;
  };
  for (let i = a; i < b; i++) {
    const y = ys[i];
    if (!Number.isFinite(y)) { flush(); out.push(i); continue; }
    const k = Math.floor(col(xs[i]));
    if (k !== c) { flush(); c = k; first = last = mnI = mxI = i; continue; }
    last = i;
    if (y < ys[mnI]) mnI = i;
    if (y > ys[mxI]) mxI = i;
  }
  flush();
  return out;
}

/**
 * Legend state after a click on `key`: `visible` maps keys to booleans (not changed). A
 * plain click flips that series; `solo` (Shift-click) shows only it, or all again when it
 * already was the only one shown.
 */
export function legendToggle(visible, key, solo = false) {
  const next = { ...visible };
  if (!solo) { next[key] = !visible[key]; return next; }
  const only = Object.keys(visible).every((k) => (k === key) === Boolean(visible[k]));
  for (const k of Object.keys(next)) next[k] = only || k === key;
  return next;
}

/**
 * Centred moving mean over a time window `w`: each finite sample becomes the mean of the
 * finite samples within ±w/2 of its time (xs ascending); non-finite samples stay gaps.
 * Only the outputs from index `from` on are computed, into `out` (so a live series
 * recomputes just its tail). `w <= 0` returns `ys` itself. Linear in the samples computed.
 */
export function movingMean(xs, ys, w, from = 0, out = new Array(xs.length)) {
  if (!(w > 0)) return ys;
  out.length = xs.length;
  let a = from < xs.length ? lowerBound(xs, xs[from] - w / 2) : 0, b = a, sum = 0, n = 0;
  for (let i = from; i < xs.length; i++) {
    while (b < xs.length && xs[b] <= xs[i] + w / 2) { if (Number.isFinite(ys[b])) { sum += ys[b]; n++; } b++; }
    while (xs[a] < xs[i] - w / 2) { if (Number.isFinite(ys[a])) { sum -= ys[a]; n--; } a++; }
    out[i] = Number.isFinite(ys[i]) && n > 0 ? sum / n : NaN;
  }
  return out;
}

/** A value rounded to 1, 2 or 5 × 10^k. */
function nice125(v) {
  const mag = 10 ** Math.floor(Math.log10(v));
  const m = v / mag;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * mag;
}

/** The filter windows offered for a time span: none, then about 1/200, 1/80, 1/40, 1/20 of it. */
export function filterWindows(span) {
  if (!(span > 0) || !Number.isFinite(span)) return [0];
  return [0, ...new Set([200, 80, 40, 20].map((d) => nice125(span / d)))];
}

/**
 * The hover rows at data x: for each visible series with samples, its sample nearest to x
 * ({key, name, color, t, y}).
 */
export function hoverRows(series, x) {
  const rows = [];
  for (const s of series) {
    if (!s.visible || !s.xs.length) continue;
    const i = nearestIndex(s.xs, x);
    rows.push({ key: s.key, name: s.name, color: s.color, dash: s.dash, t: s.xs[i], y: s.ys[i] });
  }
  return rows;
}

/** A short line in a series' colour and dash, for the legend and the readout. */
function swatchSvg(color, dash) {
  return `<svg width="22" height="10"><line x1="1" x2="21" y1="5" y2="5" stroke="${esc(color)}" stroke-width="2.5"${dash ? ` stroke-dasharray="${esc(dash)}"` : ''}/></svg>`;
}

export class Plot {
  /**
   * @param {HTMLElement} parent where the plot's <figure> is appended
   * @param {object} o title, xLabel, xUnit {factor, unit} (display = value / factor),
   *   yLabel, yUnit (base unit, SI prefix chosen automatically unless yPrefix === false),
   *   yZero (keep 0 in range), refLines [{y, label}], height, empty (text when no data)
   */
  constructor(parent, o = {}) {
    this.M = { ...M };
    this.o = { height: 260, xLabel: 'time', xUnit: { factor: 1, unit: 's' }, yUnit: '', yPrefix: true, yZero: false, empty: 'No data yet', ...o };
    this.series = [];
    this.refLines = o.refLines || [];
    // optional moving-mean filter (o.filter: index of the default window in filterWindows)
    this.window = 0;
    this.filterSelect = null;
    if (o.filter !== undefined) {
      this.filterSelect = h('select', { class: 'plot-filter', 'aria-label': `${o.title || 'plot'}: moving-mean filter`, title: 'Show a moving mean over a time window (the readout then shows the filtered values)', onchange: () => { this.window = Number(this.filterSelect.value) || 0; this.filterIndex = this.filterSelect.selectedIndex; this.update(); } });
      this.filterIndex = o.filter;
    }
    this.zoom = null;
    this.cursorX = null; // hovered data x, or null
    this.cursorPy = null; // pointer's y in px over the plot, or null
    this.frame = 0;
    this.id = `plot${++plotCounter}`;
    this.reset = h('button', { type: 'button', class: 'small plot-reset', hidden: true, onclick: () => this.resetZoom() }, 'Reset zoom');
    this.svgHost = h('div', {
      class: 'plot-area', tabindex: 0, role: 'group', 'aria-roledescription': 'interactive plot',
      'aria-label': `${o.title || 'plot'}: drag, the wheel or + and − zoom on time, Shift-drag or Page Up and Page Down pan, double-click or Escape reset, arrow keys read values`,
    });
    // a fixed-size, contained box: redrawing a plot does not lay out the rest of the page
    this.svgHost.style.height = `${this.o.height}px`;
    this.tip = h('div', { class: 'plot-tip', hidden: true, 'aria-live': 'polite', id: `${this.id}-tip` });
    this.svgHost.setAttribute('aria-describedby', this.tip.id);
    this.legend = h('div', { class: 'legend', role: 'group', 'aria-label': `${o.title || 'plot'} series` });
    this.root = h('figure', { class: 'plot', id: o.id || this.id },
      h('figcaption', { class: 'plot-head' }, h('span', { class: 'plot-title' }, o.title || ''),
        h('span', { class: 'plot-tools' }, this.reset, this.filterSelect,
          h('button', { type: 'button', class: 'small secondary plot-dl', 'data-format': 'svg', title: 'Download this plot as SVG (with its legend)', 'aria-label': `${o.title || 'plot'}: download as SVG`, onclick: () => this.download('svg') }, 'SVG'),
          h('button', { type: 'button', class: 'small secondary plot-dl', 'data-format': 'png', title: 'Download this plot as PNG (twice the size on screen)', 'aria-label': `${o.title || 'plot'}: download as PNG`, onclick: () => this.download('png') }, 'PNG'),
          h('span', { class: 'plot-hint', 'aria-hidden': 'true', title: 'Drag: zoom on time · wheel (click the plot first, or hold Ctrl): zoom · Shift-drag or Shift-wheel: pan · double-click or Escape: reset · legend: show/hide (Shift-click: only this one)' }, '?'))),
      h('div', { class: 'plot-wrap' }, this.svgHost, this.tip),
      this.legend);
    parent.append(this.root);
    this.bindEvents();
    this.ro = new ResizeObserver(() => {
      const w = this.svgHost.clientWidth;
      if (w !== this.lastWidth) this.update();
    });
    this.ro.observe(this.svgHost);
    this.update();
  }

  /** The first part of downloaded file names (the run's or the page's name). */
  setFileStem(stem) { this.o.fileStem = stem; }

  /** The plot as a standalone SVG document (styles inline, title and legend included). */
  svgText() {
    if (this.frame || !this.svg) { cancelAnimationFrame(this.frame); this.frame = 0; this.render(); }
    const bg = getComputedStyle(this.root).backgroundColor;
    return standaloneSvg(this.svg, {
      background: bg && bg !== 'rgba(0, 0, 0, 0)' ? bg : '#ffffff',
      title: this.o.title || '',
      legend: this.series.filter((x) => x.visible && x.xs.length).map((x) => ({ name: x.name, color: x.color, dash: x.dash })),
    });
  }

  /** A Blob of the plot: `svg`, or `png` at twice the size. */
  async blob(format) {
    const text = this.svgText();
    return format === 'png' ? svgToPng(text, 2) : new Blob([text], { type: 'image/svg+xml' });
  }

  /**
   * Download the plot as `svg` or `png` (`{run}-{title}.{ext}`); the file's name and size
   * are left on the figure (`data-download`: `name bytes`) for tests and scripts.
   */
  async download(format) {
    try {
      const b = await this.blob(format);
      const name = plotFileName(this.o.fileStem, this.o.title, format);
      this.root.dataset.download = `${name} ${b.size}`;
      saveBlob(b, name);
    } catch (e) {
      this.root.dataset.download = `failed ${e.message}`;
      console.warn('plot download failed', e);
    }
  }

  /** Stop observing (call when the view goes away). */
  destroy() {
    this.ro.disconnect();
    cancelAnimationFrame(this.frame);
  }

  /** Find or add a series. New series get the next palette colour unless given one. */
  ensure(key, { name = key, color, dash = '', visible = true } = {}) {
    let s = this.series.find((x) => x.key === key);
    if (!s) {
      s = { key, name, color: color || PALETTE[this.series.length % PALETTE.length], dash, visible, xs: [], ys: [] };
      this.series.push(s);
      this.legendDirty = true;
      this.update();
    }
    return s;
  }

  /** Replace a series' samples (xs ascending). */
  setData(key, xs, ys, style) {
    const s = this.ensure(key, style);
    s.xs = xs;
    s.ys = ys;
    this.update();
  }

  /** Append one sample (ignored unless x is after the last one). */
  push(key, x, y, style) {
    const s = this.ensure(key, style);
    const n = s.xs.length;
    if (n && x <= s.xs[n - 1]) return;
    s.xs.push(x);
    s.ys.push(y);
    this.update();
  }

  /**
   * Order the series (and so the legend) by `rank(key)`, lowest first; equal ranks keep
   * their order. The legend is redrawn only if the order changed.
   */
  orderBy(rank) {
    const before = this.series.map((s) => s.key).join('\n');
    this.series = this.series.map((s, i) => [s, i])
      .sort((a, b) => (rank(a[0].key) - rank(b[0].key)) || (a[1] - b[1]))
      .map(([s]) => s);
    if (this.series.map((s) => s.key).join('\n') !== before) { this.legendDirty = true; this.update(); }
  }

  setRefLines(lines) { this.refLines = lines || []; this.update(); }
  setXUnit(u) { this.o.xUnit = u; this.update(); }
  /** Fix the unzoomed time axis to [t0, t1] (widened if data fall outside). */
  setXDomain(t0, t1) {
    this.o.xDomain = Number.isFinite(t0) && Number.isFinite(t1) && t1 > t0 ? [t0, t1] : null;
    this.updateFilterChoices();
    this.update();
  }

  /** Offer filter windows for the time span (the chosen position in the list is kept). */
  updateFilterChoices() {
    const sel = this.filterSelect;
    if (!sel) return;
    const full = this.fullRange();
    const ws = filterWindows(full ? full[1] - full[0] : 0);
    const key = ws.join(',');
    if (key === this.filterKey) return;
    this.filterKey = key;
    sel.replaceChildren(...ws.map((w) => h('option', { value: String(w) }, w ? `mean over ${si(w, 's', 3)}` : 'unfiltered')));
    const i = Math.min(this.filterIndex, ws.length - 1);
    sel.selectedIndex = i;
    this.window = ws[i];
  }

  /** The series as drawn: filtered when a window is chosen (cached per series). */
  viewSeries() {
    const w = this.window;
    if (!(w > 0)) return this.series;
    return this.series.map((s) => {
      const c = s.filtered;
      const n = s.ys.length;
      if (c && c.w === w && c.src === s.ys && c.n < n) {
        // samples were appended: only outputs within w/2 of the new ones change
        movingMean(s.xs, s.ys, w, lowerBound(s.xs, s.xs[c.n] - w / 2), c.ys);
        c.n = n;
      } else if (!c || c.w !== w || c.src !== s.ys || c.n !== n) {
        s.filtered = { w, src: s.ys, n, ys: movingMean(s.xs, s.ys, w) };
      }
      return { ...s, ys: s.filtered.ys };
    });
  }
  clear() { this.series = []; this.legendDirty = true; this.update(); }

  resetZoom() {
    this.zoom = null;
    this.update();
  }

  /** Schedule a redraw on the next animation frame. */
  update() {
    if (this.frame) return;
    this.frame = requestAnimationFrame(() => { this.frame = 0; this.render(); });
  }

  // ---- layout ---------------------------------------------------------------------------

  dataXRange() {
    let lo = Infinity, hi = -Infinity;
    for (const s of this.series) {
      if (!s.visible || !s.xs.length) continue;
      lo = Math.min(lo, s.xs[0]);
      hi = Math.max(hi, s.xs[s.xs.length - 1]);
    }
    return lo <= hi ? [lo, hi] : null;
  }

  /** The unzoomed time range: the data's, widened to the fixed domain if one is set. */
  fullRange() {
    const full = this.dataXRange();
    const d = this.o.xDomain;
    if (d) return full ? [Math.min(d[0], full[0]), Math.max(d[1], full[1])] : [d[0], d[1]];
    return full;
  }

  layout() {
    // room on the right for the reference-line labels
    const width = Math.max(240, this.svgHost.clientWidth || 600);
    const longest = Math.max(0, ...this.refLines.map((r) => `${r.label} ${num(r.y, 4)}`.length));
    // narrow (phone) plots keep the labels inside the frame instead of a wide margin
    this.labelsInside = width < 520;
    this.M.right = longest && !this.labelsInside ? Math.min(160, 10 + longest * 6.3) : 16;
    const height = this.o.height;
    // a known time span (0 … end time) keeps the axis still while a live run fills it
    const full = this.fullRange();
    let [x0, x1] = this.zoom || full || [0, 1];
    if (x1 <= x0) { const d = Math.abs(x0) * 0.05 || 1e-9; x0 -= d; x1 += d; }
    let y0 = Infinity, y1 = -Infinity;
    for (const s of this.view) {
      if (!s.visible) continue;
      const a = Math.max(0, lowerBound(s.xs, x0) - 1), b = Math.min(s.xs.length, lowerBound(s.xs, x1) + 1);
      for (let i = a; i < b; i++) {
        const v = s.ys[i];
        if (Number.isFinite(v)) { if (v < y0) y0 = v; if (v > y1) y1 = v; }
      }
    }
    const hasData = y0 <= y1;
    for (const r of this.refLines) { if (Number.isFinite(r.y)) { y0 = Math.min(y0, r.y); y1 = Math.max(y1, r.y); } }
    if (this.o.yZero || !(y0 <= y1)) { y0 = Math.min(y0, 0); y1 = Math.max(y1, 0); }
    if (!(y0 <= y1)) { y0 = 0; y1 = 1; }
    if (y1 - y0 < 1e-300 || (y1 - y0) < Math.abs(y1) * 1e-9) { const d = Math.abs(y1) * 0.1 || 1; y0 -= d; y1 += d; }
    const pad = (y1 - y0) * 0.05;
    y0 = y0 === 0 ? 0 : y0 - pad;
    y1 += pad;
    const pw = width - this.M.left - this.M.right, ph = height - this.M.top - this.M.bottom;
    const sx = (x) => this.M.left + ((x - x0) / (x1 - x0)) * pw;
    const sy = (y) => this.M.top + (1 - (y - y0) / (y1 - y0)) * ph;
    const ix = (px) => x0 + ((px - this.M.left) / pw) * (x1 - x0);
    return { width, height, x0, x1, y0, y1, pw, ph, sx, sy, ix, hasData };
  }

  // ---- drawing --------------------------------------------------------------------------

  render() {
    if (this.legendDirty) this.renderLegend();
    this.updateFilterChoices();
    this.view = this.viewSeries();
    const L = (this.L = this.layout());
    this.lastWidth = this.svgHost.clientWidth;
    const { width, height, x0, x1, y0, y1, pw, ph, sx, sy } = L;
    const xf = this.o.xUnit.factor;
    const yp = this.o.yPrefix ? siPrefix(Math.max(Math.abs(y0), Math.abs(y1))) : { factor: 1, prefix: '' };
    this.yp = yp;
    const parts = [];
    parts.push(`<svg xmlns="http://www.w3.org/2000/svg" width="${width}" height="${height}" viewBox="0 0 ${width} ${height}" aria-hidden="true" focusable="false">`);
    parts.push(`<defs><clipPath id="${this.id}-clip"><rect x="${this.M.left}" y="${this.M.top}" width="${pw}" height="${ph}"/></clipPath></defs>`);
    // grid and ticks
    const xt = niceTicks(x0 / xf, x1 / xf, Math.max(2, Math.floor(pw / 80)));
    const yt = niceTicks(y0 / yp.factor, y1 / yp.factor, Math.max(2, Math.floor(ph / 45)));
    parts.push('<g class="grid">');
    for (const t of xt) { const x = sx(t * xf).toFixed(1); parts.push(`<line x1="${x}" x2="${x}" y1="${this.M.top}" y2="${this.M.top + ph}"/>`); }
    for (const t of yt) { const y = sy(t * yp.factor).toFixed(1); parts.push(`<line x1="${this.M.left}" x2="${this.M.left + pw}" y1="${y}" y2="${y}"/>`); }
    parts.push('</g><g class="axis">');
    parts.push(`<rect class="frame" x="${this.M.left}" y="${this.M.top}" width="${pw}" height="${ph}"/>`);
    for (const t of xt) parts.push(`<text x="${sx(t * xf).toFixed(1)}" y="${this.M.top + ph + 14}" text-anchor="middle">${esc(num(t, 4))}</text>`);
    for (const t of yt) parts.push(`<text x="${this.M.left - 5}" y="${(sy(t * yp.factor) + 4).toFixed(1)}" text-anchor="end">${esc(num(t, 4))}</text>`);
    const xl = `${this.o.xLabel} (${this.o.xUnit.unit})`;
    const yl = `${this.o.yLabel || ''}${this.o.yUnit || yp.prefix ? ` (${yp.prefix}${this.o.yUnit})` : ''}`;
    parts.push(`<text class="label" x="${this.M.left + pw / 2}" y="${height - 4}" text-anchor="middle">${esc(xl)}</text>`);
    parts.push(`<text class="label" transform="translate(13 ${this.M.top + ph / 2}) rotate(-90)" text-anchor="middle">${esc(yl)}</text>`);
    parts.push('</g>');
    // reference lines, labels pushed apart so close values stay readable
    if (this.refLines.length) {
      parts.push(`<g class="ref" clip-path="url(#${this.id}-clip)">`);
      const labels = [];
      for (const r of this.refLines) {
        if (!Number.isFinite(r.y)) continue;
        const y = sy(r.y);
        parts.push(`<line x1="${this.M.left}" x2="${this.M.left + pw}" y1="${y.toFixed(1)}" y2="${y.toFixed(1)}"${r.color ? ` style="stroke:${r.color}"` : ''}/>`);
        labels.push({ y, text: `${r.label} ${num(r.y, 4)}` });
      }
      parts.push('</g><g class="ref-label">');
      // Staggered: a label that would touch the one above it (close speeds such as c_R and
      // c_S) goes to the other column, still at its own line, and inside the frame just
      // below it (away from the line above); only when both columns are taken is it
      // pushed down.
      const right = this.M.left + pw;
      const widest = Math.max(0, ...labels.map((l) => l.text.length * LABEL_CHAR_PX));
      const columns = this.labelsInside
        ? [{ x: right - 3, anchor: 'end', dy: -2.5 }, { x: right - 3 - widest - 12, anchor: 'end', dy: 10.5 }]
        : [{ x: right + 4, anchor: 'start', dy: 3.5 }, { x: right - 3, anchor: 'end', dy: 10.5 }];
      for (const l of placeLabels(labels, columns.length, LABEL_GAP_PX)) {
        const c = columns[l.column];
        parts.push(`<text x="${c.x.toFixed(1)}" y="${(l.y + c.dy).toFixed(1)}"${c.anchor === 'end' ? ' text-anchor="end"' : ''} data-column="${l.column}">${esc(l.text)}</text>`);
      }
      parts.push('</g>');
    }
    // series
    parts.push(`<g class="series" clip-path="url(#${this.id}-clip)">`);
    for (const s of this.view) {
      if (!s.visible || !s.xs.length) continue;
      const d = this.pathFor(s, L);
      if (d) parts.push(`<path d="${d}" stroke="${s.color}"${s.dash ? ` stroke-dasharray="${s.dash}"` : ''}/>`);
      if (s.xs.length === 1 && Number.isFinite(s.ys[0])) parts.push(`<circle cx="${sx(s.xs[0]).toFixed(1)}" cy="${sy(s.ys[0]).toFixed(1)}" r="2.5" fill="${s.color}"/>`);
    }
    parts.push('</g>');
    if (!L.hasData) parts.push(`<text class="empty" x="${this.M.left + pw / 2}" y="${this.M.top + ph / 2}" text-anchor="middle">${esc(this.o.empty)}</text>`);
    parts.push('<g class="hover"></g><rect class="sel" x="0" y="0" width="0" height="0" visibility="hidden"/>');
    parts.push('</svg>');
    this.svgHost.innerHTML = parts.join('');
    this.svg = this.svgHost.firstChild;
    this.reset.hidden = !this.zoom;
    // the shown range and the plot area, for tests and scripts
    Object.assign(this.root.dataset, { x0: String(x0), x1: String(x1), zoomed: String(Boolean(this.zoom)), areaLeft: String(this.M.left), areaTop: String(this.M.top), areaWidth: String(pw), areaHeight: String(ph) });
    this.renderHover();
  }

  pathFor(s, L) {
    const { x0, x1, sx, sy, pw } = L;
    const a = Math.max(0, lowerBound(s.xs, x0) - 1), b = Math.min(s.xs.length, lowerBound(s.xs, x1) + 1);
    const out = [];
    let pen = false;
    for (const i of thinIndices(s.xs, s.ys, a, b, sx, pw)) {
      const y = s.ys[i];
      if (!Number.isFinite(y)) { pen = false; continue; }
      out.push(`${pen ? 'L' : 'M'}${sx(s.xs[i]).toFixed(1)} ${sy(y).toFixed(1)}`);
      pen = true;
    }
    return out.join('');
  }

  /** Show or hide series by key (a legend click; `solo`: only this one, or all again). */
  toggle(key, solo = false) {
    const next = legendToggle(Object.fromEntries(this.series.map((s) => [s.key, s.visible])), key, solo);
    for (const s of this.series) s.visible = next[s.key];
    for (const b of this.legend.children) b.setAttribute('aria-pressed', String(next[b.dataset.key]));
    this.update();
  }

  renderLegend() {
    this.legendDirty = false;
    this.legend.replaceChildren();
    for (const s of this.series) {
      const swatch = h('span', { class: 'swatch', 'aria-hidden': 'true' });
      swatch.innerHTML = swatchSvg(s.color, s.dash);
      const b = h('button', {
        type: 'button', class: 'legend-item', 'aria-pressed': String(s.visible),
        title: 'Show or hide this series (Shift-click: only this one)',
        onclick: (ev) => this.toggle(s.key, ev.shiftKey),
      }, swatch, s.name);
      b.dataset.key = s.key;
      this.legend.append(b);
    }
  }

  renderHover() {
    const g = this.svg && this.svg.querySelector('.hover');
    if (!g) return;
    const L = this.L;
    if (this.cursorX === null || !L || !L.hasData) { g.innerHTML = ''; this.tip.hidden = true; return; }
    const x = this.cursorX;
    const xf = this.o.xUnit.factor;
    const rows = hoverRows(this.view || this.series, x);
    const marks = rows.filter((r) => Number.isFinite(r.y))
      .map((r) => `<circle cx="${L.sx(r.t).toFixed(1)}" cy="${L.sy(r.y).toFixed(1)}" r="3.5" fill="${r.color}" stroke="#fff"/>`);
    const px = Math.min(Math.max(L.sx(x), this.M.left), this.M.left + L.pw);
    // crosshair: the time line, and the pointer's height when a pointer is over the plot
    let cross = `<line x1="${px.toFixed(1)}" x2="${px.toFixed(1)}" y1="${this.M.top}" y2="${this.M.top + L.ph}"/>`;
    const cy = this.cursorPy;
    if (cy !== null && cy >= this.M.top && cy <= this.M.top + L.ph) {
      cross += `<line class="cross-y" x1="${this.M.left}" x2="${this.M.left + L.pw}" y1="${cy.toFixed(1)}" y2="${cy.toFixed(1)}"/>`;
    }
    g.innerHTML = cross + marks.join('');
    const unit = `${this.yp.prefix}${this.o.yUnit}`;
    const cursorY = cy !== null && cy >= this.M.top && cy <= this.M.top + L.ph ? L.y0 + (1 - (cy - this.M.top) / L.ph) * (L.y1 - L.y0) : null;
    replace(this.tip,
      h('div', { class: 'tip-x' }, `${this.o.xLabel} = ${num(x / xf, 5)} ${this.o.xUnit.unit}`),
      this.window > 0 ? h('div', { class: 'tip-filter muted' }, `mean over ${si(this.window, 's', 3)}`) : null,
      ...rows.map(({ key, name, color, dash, t, y }) => {
        const sw = h('span', { class: 'tip-swatch', 'aria-hidden': 'true' });
        sw.innerHTML = swatchSvg(color, dash);
        const row = h('div', { class: 'tip-row' }, sw,
          `${name}: `, h('b', {}, `${num(y / this.yp.factor, 4)}${unit ? ` ${unit}` : ''}`));
        // the raw sample, for tests and copy-paste: its time (s) and value (base unit)
        row.dataset.key = key;
        row.dataset.t = String(t);
        row.dataset.y = String(y);
        return row;
      }),
      cursorY === null ? null : h('div', { class: 'tip-cursor muted' }, `cursor: ${num(cursorY / this.yp.factor, 4)}${unit ? ` ${unit}` : ''}`),
    );
    this.tip.hidden = false;
    const left = px + 12;
    const w = this.tip.offsetWidth;
    this.tip.style.left = `${left + w > L.width ? Math.max(0, px - 12 - w) : left}px`;
    this.tip.style.top = `${this.M.top}px`;
  }

  // ---- interaction ----------------------------------------------------------------------

  eventPos(ev) {
    const r = this.svgHost.getBoundingClientRect();
    return [ev.clientX - r.left, ev.clientY - r.top];
  }

  /** Set the zoom (null: none) and redraw. */
  setZoom(z) {
    this.zoom = z;
    this.update();
  }

  /** The shown range (the zoom, or the full range). */
  shown() {
    return this.zoom || (this.L ? [this.L.x0, this.L.x1] : this.fullRange());
  }

  /** Zoom by `factor` around data x `c` (default: the middle). */
  zoomBy(factor, c) {
    const r = this.shown();
    if (!r) return;
    this.setZoom(zoomAround(r, c ?? (r[0] + r[1]) / 2, factor, this.fullRange()));
  }

  /** Pan by `frac` of the shown span (negative: earlier). */
  panFraction(frac) {
    const r = this.shown();
    const full = this.fullRange();
    if (!r || !full || !this.zoom) return;
    this.setZoom(panBy(r, frac * (r[1] - r[0]), full));
  }

  bindEvents() {
    const host = this.svgHost;
    let drag = null;
    const dataX = (px) => this.L.ix(Math.min(Math.max(px, this.M.left), this.M.left + this.L.pw));
    host.addEventListener('pointerdown', (ev) => {
      if (!this.L || (ev.button !== 0 && ev.button !== 1)) return;
      const [px] = this.eventPos(ev);
      // Shift-drag or the middle button pans (only a zoomed plot has room to pan)
      const pan = ev.button === 1 || ev.shiftKey;
      drag = { px, id: ev.pointerId, pan, range: this.shown() };
      if (pan) ev.preventDefault();
      host.setPointerCapture(ev.pointerId);
    });
    host.addEventListener('pointermove', (ev) => {
      if (!this.L) return;
      const [px, py] = this.eventPos(ev);
      this.cursorX = dataX(px);
      this.cursorPy = py;
      if (drag && drag.pan) {
        const full = this.fullRange();
        if (this.zoom && full) {
          const [a, b] = drag.range;
          this.zoom = panBy(drag.range, -((px - drag.px) / this.L.pw) * (b - a), full);
          this.update();
        }
        return;
      }
      if (drag && Math.abs(px - drag.px) > 3) {
        const sel = this.svg.querySelector('.sel');
        const a = Math.max(this.M.left, Math.min(drag.px, px)), b = Math.min(this.M.left + this.L.pw, Math.max(drag.px, px));
        sel.setAttribute('x', a); sel.setAttribute('width', Math.max(0, b - a));
        sel.setAttribute('y', this.M.top); sel.setAttribute('height', this.L.ph);
        sel.setAttribute('visibility', 'visible');
      }
      this.renderHover();
    });
    const end = (ev) => {
      if (!drag) return;
      const [px] = this.eventPos(ev);
      const d = drag;
      drag = null;
      if (host.hasPointerCapture(d.id)) host.releasePointerCapture(d.id);
      let changed = d.pan || Math.abs(px - d.px) > 3;
      if (!d.pan && this.L) {
        const r = dragRange(d.px, px, { left: this.M.left, width: this.L.pw, x0: this.L.x0, x1: this.L.x1 });
        if (r && r[1] > r[0]) { this.zoom = r; changed = true; }
      }
      // a plain click changes nothing: no redraw between the two clicks of a double click
      if (changed) this.update();
    };
    host.addEventListener('pointerup', end);
    host.addEventListener('pointercancel', () => { drag = null; this.update(); });
    host.addEventListener('pointerleave', (ev) => {
      if (drag) return;
      if (ev.pointerType === 'mouse') { this.cursorX = null; this.cursorPy = null; this.renderHover(); }
    });
    host.addEventListener('dblclick', () => this.resetZoom());
    host.addEventListener('blur', () => { this.cursorX = null; this.cursorPy = null; this.renderHover(); });
    host.addEventListener('keydown', (ev) => this.onKey(ev));
    // The wheel zooms only a focused plot (or with Ctrl), so that it still scrolls the page.
    host.addEventListener('wheel', (ev) => {
      if (!this.L || !(ev.ctrlKey || document.activeElement === host)) return;
      ev.preventDefault();
      const scale = ev.deltaMode === 1 ? 16 : ev.deltaMode === 2 ? 400 : 1;
      const dy = ev.deltaY * scale, dx = ev.deltaX * scale;
      if (ev.shiftKey || Math.abs(dx) > Math.abs(dy)) {
        this.panFraction(((ev.shiftKey ? dy || dx : dx) / this.L.pw));
      } else if (dy) {
        const [px] = this.eventPos(ev);
        this.zoomBy(Math.exp(Math.max(-1, Math.min(1, dy / 300))), dataX(px));
      }
    }, { passive: false });
  }

  onKey(ev) {
    const L = this.L;
    if (!L) return;
    const ref = this.series.find((s) => s.visible && s.xs.length);
    let handled = true;
    if (ev.key === 'ArrowLeft' || ev.key === 'ArrowRight') {
      if (ref) {
        const dir = ev.key === 'ArrowLeft' ? -1 : 1;
        let i = this.cursorX === null ? (dir > 0 ? lowerBound(ref.xs, L.x0) : lowerBound(ref.xs, L.x1) - 1) : nearestIndex(ref.xs, this.cursorX) + dir * (ev.shiftKey ? 10 : 1);
        i = Math.max(0, Math.min(ref.xs.length - 1, i));
        this.cursorX = ref.xs[i];
        this.cursorPy = null;
      }
    } else if (ev.key === '+' || ev.key === '=') {
      this.zoomBy(0.5, this.cursorX ?? undefined);
      return ev.preventDefault();
    } else if (ev.key === '-' || ev.key === '_') {
      this.zoomBy(2, this.cursorX ?? undefined);
      return ev.preventDefault();
    } else if (ev.key === 'PageUp' || ev.key === 'PageDown') {
      this.panFraction(ev.key === 'PageUp' ? -0.5 : 0.5);
      return ev.preventDefault();
    } else if (ev.key === 'Escape' || ev.key === '0' || ev.key === 'Home') {
      this.zoom = null;
      this.cursorX = null;
    } else handled = false;
    if (handled) { ev.preventDefault(); this.update(); }
  }
}
