// Plots as files: a standalone SVG (the plot's own SVG with its computed styles written
// inline, so it renders the same outside the dashboard's stylesheet) and a PNG (that SVG
// drawn on a canvas at twice its size). File names come from the run name and plot title.
// The pure parts (`slug`, `plotFileName`) are tested in web/test/download.test.mjs.

/** Style properties copied from the page onto every element of an exported SVG. */
export const SVG_STYLE_PROPS = [
  'fill', 'fill-opacity', 'stroke', 'stroke-width', 'stroke-opacity', 'stroke-dasharray',
  'stroke-linejoin', 'stroke-linecap', 'paint-order', 'opacity', 'visibility',
  'font-family', 'font-size', 'font-weight', 'font-style',
];

/**
 * A file-name-safe piece: lower case, ASCII letters and digits with single dashes between
 * words (accents dropped, Greek letters and symbols such as √ removed), at most `max`
 * characters, never empty ('plot').
 */
export function slug(text, max = 60) {
  const s = String(text ?? '')
    .normalize('NFKD').replace(/[\u0300-\u036f]/g, '')
    .toLowerCase()
    .replace(/[^a-z0-9]+/g, '-')
    .replace(/^-+|-+$/g, '')
    .slice(0, max)
    .replace(/-+$/g, '');
  return s || 'plot';
}

/** `{run}-{title}.{ext}`, e.g. plotFileName('edge crack', 'Crack-tip speed', 'svg') → `edge-crack-crack-tip-speed.svg`. */
export function plotFileName(run, title, ext) {
  const parts = [run, title].filter((p) => p !== undefined && p !== null && String(p).trim() !== '').map((p) => slug(p));
  return `${parts.length ? parts.join('-') : 'plot'}.${ext}`;
}

/**
 * The text of a standalone SVG document of `svg` (an element on the page): a copy with
 * every element's computed style written into its `style` attribute, a background of
 * `background` behind everything, `title` above the plot when given (the figure's caption
 * lives outside the SVG), the visible series' `legend` ([{name, color, dash}]) below it,
 * and the parts that only make sense on the page (hover crosshair, drag selection) left out.
 */
export function standaloneSvg(svg, { background = '#ffffff', title = '', legend = [] } = {}) {
  const copy = svg.cloneNode(true);
  const src = [svg, ...svg.querySelectorAll('*')];
  const dst = [copy, ...copy.querySelectorAll('*')];
  src.forEach((el, i) => {
    const cs = getComputedStyle(el);
    const style = SVG_STYLE_PROPS.map((p) => [p, cs.getPropertyValue(p)])
      .filter(([, v]) => v && v !== 'normal' && v !== 'auto')
      .map(([p, v]) => `${p}:${v}`).join(';');
    if (style) dst[i].setAttribute('style', style);
  });
  for (const el of copy.querySelectorAll('.hover, .sel')) el.remove();
  copy.removeAttribute('aria-hidden');
  copy.removeAttribute('focusable');
  copy.setAttribute('xmlns', 'http://www.w3.org/2000/svg');
  const ns = 'http://www.w3.org/2000/svg';
  const w = Number(svg.getAttribute('width')) || svg.clientWidth || 600;
  const hgt = Number(svg.getAttribute('height')) || svg.clientHeight || 260;
  const head = title ? 22 : 0;
  const items = legendLayout(legend, w);
  const foot = items.length ? items[items.length - 1].y + 12 : 0;
  // the plot moves down by the title's line; the document grows by as much
  const g = document.createElementNS(ns, 'g');
  g.setAttribute('transform', `translate(0 ${head})`);
  while (copy.firstChild) g.append(copy.firstChild);
  const bg = document.createElementNS(ns, 'rect');
  Object.entries({ x: 0, y: 0, width: w, height: hgt + head + foot, fill: background }).forEach(([k, v]) => bg.setAttribute(k, String(v)));
  copy.append(bg);
  if (title) {
    const t = document.createElementNS(ns, 'text');
    Object.entries({ x: w / 2, y: 15, 'text-anchor': 'middle' }).forEach(([k, v]) => t.setAttribute(k, String(v)));
    const cs = getComputedStyle(svg);
    t.setAttribute('style', `font-family:${cs.getPropertyValue('font-family')};font-size:13px;font-weight:600;fill:${cs.getPropertyValue('color') || '#000'}`);
    t.textContent = title;
    copy.append(t);
  }
  copy.append(g);
  const font = getComputedStyle(svg).getPropertyValue('font-family');
  const fg = getComputedStyle(svg).getPropertyValue('color') || '#000';
  for (const it of items) {
    const y = hgt + head + it.y;
    const line = document.createElementNS(ns, 'line');
    Object.entries({ x1: it.x, x2: it.x + 20, y1: y - 4, y2: y - 4, stroke: it.color, 'stroke-width': 2, 'stroke-dasharray': it.dash || 'none' })
      .forEach(([k, v]) => line.setAttribute(k, String(v)));
    const t = document.createElementNS(ns, 'text');
    t.setAttribute('x', String(it.x + 25));
    t.setAttribute('y', String(y));
    t.setAttribute('style', `font-family:${font};font-size:11px;fill:${fg}`);
    t.textContent = it.name;
    copy.append(line, t);
  }
  const total = hgt + head + foot;
  copy.setAttribute('width', String(w));
  copy.setAttribute('height', String(total));
  copy.setAttribute('viewBox', `0 0 ${w} ${total}`);
  return `<?xml version="1.0" encoding="UTF-8"?>\n${new XMLSerializer().serializeToString(copy)}\n`;
}

/**
 * Legend entries laid out left to right in rows of `width` px (an 11 px font, about 6.3 px
 * a character; each entry: a 20 px line sample, 5 px, its name, 16 px gap): [{name, color,
 * dash, x, y}] with y the baseline below the plot (first row at 16).
 */
export function legendLayout(legend, width, charPx = 6.3) {
  const out = [];
  let x = 10, y = 16;
  for (const it of legend || []) {
    const w = 25 + String(it.name).length * charPx + 16;
    if (x > 10 && x + w > width - 10) { x = 10; y += 16; }
    out.push({ ...it, x, y });
    x += w;
  }
  return out;
}

/** A PNG Blob of SVG text drawn at `scale` × its size (resolves once drawn). */
export function svgToPng(svgText, scale = 2) {
  return new Promise((resolve, reject) => {
    const url = URL.createObjectURL(new Blob([svgText], { type: 'image/svg+xml' }));
    const img = new Image();
    img.onload = () => {
      try {
        const c = document.createElement('canvas');
        c.width = Math.round(img.naturalWidth * scale);
        c.height = Math.round(img.naturalHeight * scale);
        const ctx = c.getContext('2d');
        ctx.scale(scale, scale);
        ctx.drawImage(img, 0, 0);
        URL.revokeObjectURL(url);
        c.toBlob((b) => (b ? resolve(b) : reject(new Error('the canvas gave no PNG'))), 'image/png');
      } catch (e) {
        URL.revokeObjectURL(url);
        reject(e);
      }
    };
    img.onerror = () => { URL.revokeObjectURL(url); reject(new Error('the SVG could not be drawn')); };
    img.src = url;
  });
}
