// Small DOM and formatting helpers shared by the views.

/**
 * Create an element: h('a', {href: '#/', class: 'x', onclick: fn}, 'text', child, ...).
 * Attributes starting with "on" become listeners; `null`/`false` attributes are skipped;
 * children may be strings, nodes, arrays, null.
 */
export function h(tag, attrs = {}, ...children) {
  const ns = attrs && attrs.svg ? 'http://www.w3.org/2000/svg' : null;
  const el = ns ? document.createElementNS(ns, tag) : document.createElement(tag);
  for (const [k, v] of Object.entries(attrs || {})) {
    if (k === 'svg' || v === null || v === undefined || v === false) continue;
    if (k.startsWith('on') && typeof v === 'function') el.addEventListener(k.slice(2), v);
    else if (k === 'class') el.setAttribute('class', v);
    else if (k === 'text') el.textContent = v;
    else if (k in el && !ns && k !== 'list' && k !== 'form') el[k] = v;
    else el.setAttribute(k, v === true ? '' : String(v));
  }
  append(el, children);
  return el;
}

function append(el, children) {
  for (const c of children) {
    if (c === null || c === undefined || c === false) continue;
    if (Array.isArray(c)) append(el, c);
    else el.append(c instanceof Node ? c : String(c));
  }
}

/** Remove all children of `el` and append the given ones. */
export function replace(el, ...children) {
  el.replaceChildren();
  append(el, children);
  return el;
}

const PREFIXES = [
  [1e9, 'G'], [1e6, 'M'], [1e3, 'k'], [1, ''], [1e-3, 'm'], [1e-6, 'µ'], [1e-9, 'n'], [1e-12, 'p'],
];

/** Engineering prefix for a magnitude: {factor, prefix} with value/factor in [1, 1000). */
export function siPrefix(maxAbs) {
  if (!(maxAbs > 0) || !Number.isFinite(maxAbs)) return { factor: 1, prefix: '' };
  for (const [f, p] of PREFIXES) if (maxAbs >= f * 0.9995) return { factor: f, prefix: p };
  return { factor: 1e-12, prefix: 'p' };
}

/** A number with `digits` significant digits, without exponent clutter for ordinary sizes. */
export function num(v, digits = 4) {
  if (v === null || v === undefined || Number.isNaN(v)) return '–';
  if (!Number.isFinite(v)) return v > 0 ? '∞' : '−∞';
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e6 || a < 1e-3) return v.toExponential(digits - 1).replace('e+', 'e');
  return String(Number(v.toPrecision(digits)));
}

/** A value with an SI prefix and unit, e.g. si(2.5e-5, 's') → "25 µs". */
export function si(v, unit, digits = 4) {
  if (v === null || v === undefined || Number.isNaN(v)) return '–';
  const { factor, prefix } = siPrefix(Math.abs(v));
  return `${num(v / factor, digits)} ${prefix}${unit}`;
}

/** Compact count: 1234567 → "1.23 M". */
export function count(v) {
  if (v === null || v === undefined || Number.isNaN(v)) return '–';
  if (Math.abs(v) < 1000) return String(Math.round(v));
  return si(v, '', 3).trim();
}

/** Duration in seconds → "1 h 02 min", "3 min 05 s", "12.3 s". */
export function duration(s) {
  if (s === null || s === undefined || !Number.isFinite(s)) return '–';
  if (s < 60) return `${num(s, 3)} s`;
  const m = Math.floor(s / 60), sec = Math.round(s - 60 * m);
  if (m < 60) return `${m} min ${String(sec).padStart(2, '0')} s`;
  const hr = Math.floor(m / 60);
  return `${hr} h ${String(m - 60 * hr).padStart(2, '0')} min`;
}

/**
 * Seconds left of a run that has done `fraction` (0–1] of its simulated time in `elapsed`
 * seconds, assuming the rate so far holds; null while too little is done to tell (< 1 %).
 */
export function etaSeconds(fraction, elapsed) {
  if (!(Number.isFinite(fraction) && Number.isFinite(elapsed)) || fraction < 0.01 || elapsed < 0) return null;
  if (fraction >= 1) return 0;
  return elapsed * (1 - fraction) / fraction;
}

/**
 * Name of a crack-tip row's series: `end tip`, `crack 1 start tip`, or for a cohesive
 * interface's row (crack index past the scene's cracks, run-output.md) `interface 0 front`.
 */
export function tipLabel(crack, tip, multiCrack, nCracks = Infinity) {
  const c = Number(crack);
  if (c >= nCracks) return `interface ${c - nCracks} front`;
  const end = Number(tip) === 0 ? 'start tip' : 'end tip';
  return multiCrack ? `crack ${c} ${end}` : end;
}

/**
 * The "from cache" note of a job answered from a completed run of the same scene and solver
 * version (`cached_from`, docs/service.md "Cache"): `{text, title, of}`, or null for a job
 * that ran.
 */
export function cacheNote(job) {
  const of = job && typeof job.cached_from === 'string' && job.cached_from ? job.cached_from : null;
  if (!of) return null;
  return { text: 'from cache', title: `Not run again: the results of run ${of} (same scene, same solver version)`, of };
}

/** The ETA text of a running job (`about 2 min 05 s left`), or '' when it cannot be told. */
export function etaText(job, now = Date.now()) {
  if (!job || job.status !== 'running' || !job.started_at || !job.progress) return '';
  const eta = etaSeconds(Number(job.progress.fraction), (now - Date.parse(job.started_at)) / 1000);
  return eta === null ? '' : `about ${duration(eta)} left`;
}

/** RFC 3339 → local "2026-11-23 14:05:09" (title attribute keeps the UTC original). */
export function dateTime(iso) {
  if (!iso) return '–';
  const d = new Date(iso);
  if (Number.isNaN(d.getTime())) return iso;
  const p = (n) => String(n).padStart(2, '0');
  return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}`;
}

/** A <time> element for an RFC 3339 timestamp. */
export function timeEl(iso) {
  return iso ? h('time', { datetime: iso, title: iso }, dateTime(iso)) : '–';
}

/** Time unit suited to a simulated time span: {factor, unit} (s, ms, µs, ns). */
export function timeUnit(span) {
  const { factor, prefix } = siPrefix(Math.abs(span || 0));
  const f = Math.min(1, factor);
  const p = f === 1 ? '' : prefix;
  return { factor: f, unit: `${p}s` };
}

/** Status badge. */
export function statusBadge(status) {
  return h('span', { class: `badge status-${status}` }, status);
}

/** Parse "a:b, c:d" (or a=b) into {a: 'b', c: 'd'}. */
export function parseLabels(text) {
  const out = {};
  for (const part of (text || '').split(',')) {
    const t = part.trim();
    if (!t) continue;
    const i = t.search(/[:=]/);
    if (i <= 0) throw new Error(`label "${t}" is not key:value`);
    out[t.slice(0, i).trim()] = t.slice(i + 1).trim();
  }
  return out;
}

/** Query string of a hash route: "#/compare?ids=a,b" → URLSearchParams. */
export function hashQuery() {
  const i = location.hash.indexOf('?');
  return new URLSearchParams(i >= 0 ? location.hash.slice(i + 1) : '');
}

/** Trigger a download of a Blob under a file name. */
export function saveBlob(blob, name) {
  const url = URL.createObjectURL(blob);
  const a = h('a', { href: url, download: name, hidden: true });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

/** Announce a message in the global live region (screen readers) and the toast area. */
export function notify(message, kind = 'info') {
  const area = document.getElementById('toasts');
  if (!area) return;
  const t = h('div', { class: `toast toast-${kind}`, role: kind === 'error' ? 'alert' : 'status' }, message);
  area.append(t);
  setTimeout(() => t.remove(), kind === 'error' ? 8000 : 4000);
}

/**
 * JSON with two-space indentation, but short arrays of numbers/strings (points, vectors,
 * field lists) kept on one line, the way scenes are written by hand.
 */
export function prettyJson(value, indent = '') {
  if (value === null || typeof value !== 'object') return JSON.stringify(value) ?? 'null';
  const inner = `${indent}  `;
  if (Array.isArray(value)) {
    if (value.length === 0) return '[]';
    const flat = value.every((v) => v === null || typeof v !== 'object' || (Array.isArray(v) && v.every((w) => w === null || typeof w !== 'object')));
    if (flat) {
      const one = `[${value.map((v) => (Array.isArray(v) ? `[${v.map((w) => JSON.stringify(w)).join(', ')}]` : JSON.stringify(v))).join(', ')}]`;
      if (one.length <= 72) return one;
    }
    return `[\n${value.map((v) => inner + prettyJson(v, inner)).join(',\n')}\n${indent}]`;
  }
  const keys = Object.keys(value).filter((k) => value[k] !== undefined);
  if (keys.length === 0) return '{}';
  return `{\n${keys.map((k) => `${inner}${JSON.stringify(k)}: ${prettyJson(value[k], inner)}`).join(',\n')}\n${indent}}`;
}

const SCENE_ORDER = ['name', 'description', 'analysis', 'thickness', 'grid', 'materials', 'bodies', 'cracks', 'boundary_conditions', 'loads', 'damping', 'time', 'output'];
const FIRST_KEYS = ['model', 'material', 'region', 'points', 'cell_size', 'criterion', 'law', 'kind', 'end'];

/**
 * A scene with its keys in the order of scene-format.md (servers may hand them back sorted
 * alphabetically), and `model`, `material`, `region`… first in nested objects. Values are
 * unchanged.
 */
export function orderScene(scene) {
  const rank = (order) => (k) => { const i = order.indexOf(k); return i < 0 ? order.length : i; };
  const walk = (v, top) => {
    if (Array.isArray(v)) return v.map((x) => walk(x, false));
    if (!v || typeof v !== 'object') return v;
    const r = rank(top ? SCENE_ORDER : FIRST_KEYS);
    const keys = Object.keys(v).sort((a, b) => r(a) - r(b));
    const out = {};
    for (const k of keys) out[k] = walk(v[k], false);
    return out;
  };
  return walk(scene, true);
}
