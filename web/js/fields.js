// Field pictures: the colour range of a snapshot picture (the PNG's `?range=LO,HI`, in SI
// units: server/src/http/results.rs) chosen as auto (the data's range), symmetric (±A) or
// manual (min–max). Pure; tested in web/test/fields.test.mjs.

/** SI unit of each component's values (strain has none). */
export const COMPONENT_UNITS = {
  sxx: 'Pa', syy: 'Pa', sxy: 'Pa', von_mises: 'Pa', speed: 'm/s', vx: 'm/s', vy: 'm/s',
  ux: 'm', uy: 'm', umag: 'm', exx: '', eyy: '', exy: '',
};

/** Whether a component's picture takes a colour range (fringes and materials do not). */
export function rangeApplies(component) {
  return component !== 'fringe' && component !== 'material';
}

/** A number typed by a person: `2e6`, ` -1.5 `, `2,5` (decimal comma); NaN otherwise. */
export function parseNumber(text) {
  const t = String(text ?? '').trim().replace(/^([+-]?\d+),(\d+)$/, '$1.$2').replace('−', '-');
  if (!t || !/^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$/.test(t)) return NaN;
  return Number(t);
}

/**
 * Check a colour-range setting {mode: 'auto' | 'symmetric' | 'manual', abs, lo, hi} (the
 * texts of the inputs): '' when it is usable, else what is wrong.
 */
export function rangeProblem(s) {
  if (!s || s.mode === 'auto' || !s.mode) return '';
  if (s.mode === 'symmetric') {
    const a = parseNumber(s.abs);
    return Number.isFinite(a) && a > 0 ? '' : 'the symmetric range needs a positive number (±A)';
  }
  if (s.mode === 'manual') {
    const lo = parseNumber(s.lo), hi = parseNumber(s.hi);
    if (!Number.isFinite(lo) || !Number.isFinite(hi)) return 'min and max must both be numbers';
    return lo < hi ? '' : 'min must be below max';
  }
  return `unknown mode ${s.mode}`;
}

/** The `range` query value of a setting (`-A,A` or `LO,HI`), or '' for auto or a bad setting. */
export function rangeParam(s) {
  if (!s || rangeProblem(s) || s.mode === 'auto' || !s.mode) return '';
  if (s.mode === 'symmetric') {
    const a = Math.abs(parseNumber(s.abs));
    return `${-a},${a}`;
  }
  return `${parseNumber(s.lo)},${parseNumber(s.hi)}`;
}
