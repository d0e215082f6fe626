// Pure helpers of the sweep pages (no DOM): crack-tip histories gathered per job and tip as
// rows arrive (polling with ?since= may repeat rows), sweep summaries and series names.

/** The states of a job, in the order a sweep summary lists them. */
export const SWEEP_STATES = ['completed', 'running', 'queued', 'failed', 'cancelled'];

/** Whether a sweep (or a job) still has work queued or running. */
export function isActive(s) {
  if (!s) return false;
  if (s.status === 'queued' || s.status === 'running') return true;
  const c = s.counts || {};
  return (c.queued || 0) + (c.running || 0) > 0;
}

/** `3 jobs: 2 completed, 1 running` from a sweep's `total` and `counts`. */
export function countsText(s) {
  const c = (s && s.counts) || {};
  const parts = SWEEP_STATES.filter((k) => c[k] > 0).map((k) => `${c[k]} ${k}`);
  const n = (s && s.total) || 0;
  return `${n} job${n === 1 ? '' : 's'}${parts.length ? `: ${parts.join(', ')}` : ''}`;
}

/** `toughness: 25, 100, 250` lines of a sweep's parameters (short name = last segments). */
export function parameterText(parameters) {
  return (parameters || []).map((p) => `${p.path}: ${(p.values || []).map((v) => (typeof v === 'string' ? v : JSON.stringify(v))).join(', ')}`);
}

/**
 * Crack-tip histories of one job, per tip ("crack/tip" → {t: [], v: [], l: []}: time,
 * speed, crack length), fed with rows
 * as they arrive. Rows at or before a tip's last time are ignored, so overlapping polls do
 * not double points.
 */
export class TipHistory {
  constructor() {
    this.tips = new Map();
    this.multiCrack = false;
    this.maxSpeed = 0;
  }

  /** Add rows; returns how many were new. */
  add(rows) {
    let n = 0;
    for (const r of rows || []) {
      const t = Number(r && r.time);
      if (!Number.isFinite(t)) continue;
      const key = `${r.crack}/${r.tip}`;
      let s = this.tips.get(key);
      if (!s) {
        s = { crack: Number(r.crack), tip: Number(r.tip), t: [], v: [], l: [] };
        this.tips.set(key, s);
      }
      if (s.t.length && t <= s.t[s.t.length - 1]) continue;
      const v = r.speed === null || r.speed === undefined ? NaN : Number(r.speed);
      s.t.push(t);
      s.v.push(v);
      s.l.push(r.length === null || r.length === undefined ? NaN : Number(r.length));
      if (Number(r.crack) > 0) this.multiCrack = true;
      if (Number.isFinite(v)) this.maxSpeed = Math.max(this.maxSpeed, Math.abs(v));
      n++;
    }
    return n;
  }

  /** The `since` for the next poll: the earliest of the tips' last times (undefined: all). */
  since() {
    if (!this.tips.size) return undefined;
    return Math.min(...[...this.tips.values()].map((s) => s.t[s.t.length - 1]));
  }

  /** Number of samples over all tips. */
  get size() {
    let n = 0;
    for (const s of this.tips.values()) n += s.t.length;
    return n;
  }
}

/** Legend name of a job's tip series: the job's label, plus the tip when it has several. */
export function seriesName(label, tip, tipCount, multiCrack) {
  if (tipCount <= 1) return label;
  const end = tip.tip === 0 ? 'start tip' : 'end tip';
  return `${label}, ${multiCrack ? `crack ${tip.crack} ${end}` : end}`;
}

/**
 * The values of a sweep parameter typed as `25, 100, 250`: each comma-separated item as
 * JSON when it is JSON (numbers, true/false, null, "quoted text", [arrays] kept whole),
 * else as text. Throws on an empty list or an empty item.
 */
export function parseSweepValues(text) {
  const items = [];
  let depth = 0, quote = false, cur = '';
  for (const ch of String(text ?? '')) {
    if (quote) { cur += ch; if (ch === '"') quote = false; continue; }
    if (ch === '"') quote = true;
    if (ch === '[' || ch === '{') depth++;
    if (ch === ']' || ch === '}') depth--;
    if (ch === ',' && depth === 0) { items.push(cur); cur = ''; continue; }
    cur += ch;
  }
  items.push(cur);
  const out = items.map((s) => s.trim());
  if (out.length === 1 && out[0] === '') throw new Error('give at least one value');
  if (out.some((s) => s === '')) throw new Error('a value between commas is empty');
  return out.map((s) => { try { return JSON.parse(s); } catch { return s; } });
}

/**
 * The `parameters` object of `POST /api/v1/sweeps` from form rows [{path, values}] (values as
 * typed), in the rows' order; rows with neither are skipped. Throws naming the bad row.
 */
export function sweepParameters(rows) {
  const out = {};
  (rows || []).forEach((r, i) => {
    const path = String(r.path ?? '').trim();
    const values = String(r.values ?? '').trim();
    if (!path && !values) return;
    if (!path) throw new Error(`parameter ${i + 1}: give its path (e.g. cracks.0.propagation.toughness)`);
    if (path in out) throw new Error(`parameter ${i + 1}: ${path} is given twice`);
    try {
      out[path] = parseSweepValues(values);
    } catch (e) {
      throw new Error(`parameter ${i + 1} (${path}): ${e.message}`);
    }
  });
  if (!Object.keys(out).length) throw new Error('give at least one parameter with its values');
  return out;
}

/**
 * Dot paths of the numeric values of a scene (`cracks.0.propagation.toughness`,
 * `materials.plate.youngs_modulus`, …), for suggestions; at most `max`, vectors (arrays of
 * numbers, such as points) left out.
 */
export function numericPaths(scene, max = 200) {
  const out = [];
  const walk = (v, path) => {
    if (out.length >= max) return;
    if (typeof v === 'number') { out.push(path.join('.')); return; }
    if (Array.isArray(v)) {
      if (v.every((x) => typeof x === 'number')) return;
      v.forEach((x, i) => walk(x, [...path, String(i)]));
    } else if (v && typeof v === 'object') {
      for (const [k, x] of Object.entries(v)) walk(x, [...path, k]);
    }
  };
  walk(scene, []);
  return out;
}
