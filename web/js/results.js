// The run page's "Results" tables, from the job's summary: one row per crack tip
// (`summary.tips`) and the comparison with reference values (`summary.references`). Pure
// (numbers → display strings); tested in web/test/results.test.mjs. Older runs have neither
// field: both functions then give nothing.

/** `v × factor` with `digits` significant digits, or '–' for null, undefined or NaN. */
export function scaled(v, factor, digits = 4) {
  if (v === null || v === undefined || v === '' || !Number.isFinite(Number(v))) return '–';
  const x = Number(v) * factor;
  if (x === 0) return '0';
  const a = Math.abs(x);
  if (a >= 1e6 || a < 1e-3) return x.toExponential(digits - 1).replace('e+', 'e');
  return String(Number(x.toPrecision(digits)));
}

/** The columns of the tip table: [key, heading, unit, factor from SI]. */
export const TIP_COLUMNS = [
  ['samples', 'Samples', '', 1],
  ['initiation_time', 'Initiation', 'µs', 1e6],
  ['growth', 'Growth', 'mm', 1e3],
  ['x', 'Tip x', 'mm', 1e3],
  ['y', 'Tip y', 'mm', 1e3],
  ['mean_speed', 'Mean speed', 'm/s', 1],
  ['peak_speed', 'Peak speed', 'm/s', 1],
  ['j1_final', 'J₁ final', 'J/m²', 1],
  ['j1_peak', 'J₁ peak', 'J/m²', 1],
  ['k1_final', 'K_I final', 'MPa·√m', 1e-6],
  ['k1_peak', 'K_I peak', 'MPa·√m', 1e-6],
  ['k2_final', 'K_II final', 'MPa·√m', 1e-6],
  ['k2_peak', 'K_II peak', 'MPa·√m', 1e-6],
];

/** Tip name as the plots say it: `end tip`, `crack 1 start tip`. */
function tipName(t, multi) {
  const end = Number(t.tip) === 0 ? 'start tip' : 'end tip';
  return multi ? `crack ${t.crack} ${end}` : end;
}

/**
 * The tip table of a summary: {columns: [{key, heading, unit}], rows: [{name, cells:
 * [text…], tip}], speedWindow: seconds or null}; null when the summary has no tips.
 * Initiation is "not initiated" for a tip that never grew.
 */
export function tipTable(summary) {
  const tips = summary && Array.isArray(summary.tips) ? summary.tips.filter((t) => t && typeof t === 'object') : [];
  if (!tips.length) return null;
  const multi = tips.some((t) => Number(t.crack) > 0);
  const windows = tips.map((t) => Number(t.speed_window)).filter((w) => Number.isFinite(w) && w > 0);
  return {
    columns: TIP_COLUMNS.map(([key, heading, unit]) => ({ key, heading, unit })),
    rows: tips.map((t) => ({
      tip: t,
      name: tipName(t, multi),
      cells: TIP_COLUMNS.map(([key, , , f]) => {
        if (key === 'samples') return t.samples === undefined || t.samples === null ? '–' : String(t.samples);
        if (key === 'initiation_time' && (t.initiation_time === null || t.initiation_time === undefined)) return 'not initiated';
        return scaled(t[key], f);
      }),
    })),
    speedWindow: windows.length ? Math.max(...windows) : null,
  };
}

/** Display name, unit and factor from SI of each reference quantity (scene `references`). */
export const REFERENCE_QUANTITIES = {
  j1: ['J₁', 'J/m²', 1], k1: ['K_I', 'MPa·√m', 1e-6], k2: ['K_II', 'MPa·√m', 1e-6],
  growth: ['growth', 'mm', 1e3], mean_speed: ['mean speed', 'm/s', 1], peak_speed: ['peak speed', 'm/s', 1],
  initiation_time: ['initiation time', 'µs', 1e6],
};
const AT_NAMES = { final: 'final', peak: 'peak', late_mean: 'mean over the last 20 %' };

/**
 * The reference rows of a summary: [{quantity, where, value, measured (with their unit),
 * error, tolerance, within, mark, source}] with the relative error in % and ✓ / ✗ when a tolerance decided it (empty
 * otherwise); [] when there are none.
 */
export function referenceRows(summary) {
  const refs = summary && Array.isArray(summary.references) ? summary.references.filter((r) => r && typeof r === 'object') : [];
  return refs.map((r) => {
    const err = Number(r.relative_error);
    const tol = Number(r.tolerance);
    const within = r.within === true || r.within === false ? r.within : null;
    const q = REFERENCE_QUANTITIES[r.quantity];
    const [name, unit, f] = q || [String(r.quantity ?? '–'), '', 1];
    const where = [
      r.at !== undefined && r.at !== null && r.at !== '' ? (AT_NAMES[r.at] || String(r.at)) : '',
      r.crack !== undefined && r.crack !== null ? `crack ${r.crack}` : '',
      r.tip !== undefined && r.tip !== null ? `tip ${r.tip}` : '',
    ].filter(Boolean).join(', ');
    const withUnit = (v) => { const t = scaled(v, f); return t === '–' || !unit ? t : `${t} ${unit}`; };
    return {
      quantity: name,
      where,
      value: withUnit(r.value),
      measured: withUnit(r.measured),
      error: r.relative_error === null || r.relative_error === undefined || !Number.isFinite(err) ? '–' : `${scaled(err * 100, 1, 3)} %`,
      tolerance: Number.isFinite(tol) && r.tolerance !== null ? `${scaled(tol * 100, 1, 3)} %` : '',
      within,
      mark: within === true ? '✓' : within === false ? '✗' : '',
      source: String(r.source ?? ''),
    };
  });
}
