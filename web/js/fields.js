// Field pictures: the colour range of a snapshot picture (the PNG's `?range=LO,HI`, in SI
// units: server/src/http/results.rs) chosen as auto (the data's range), symmetric (±A) or
// manual (min–max); the plane of a 3D run's slice (`snapshot.slice`). Pure; tested in
// web/test/dashboard-features.test.mjs.

/** SI unit of each component's values (strain has none). */
export const COMPONENT_UNITS = {
  sxx: 'Pa', syy: 'Pa', sxy: 'Pa', von_mises: 'Pa', speed: 'm/s', vx: 'm/s', vy: 'm/s',
  ux: 'm', uy: 'm', umag: 'm', exx: '', eyy: '', exy: '',
  // 3D runs' slices
  szz: 'Pa', syz: 'Pa', sxz: 'Pa', vz: 'm/s', uz: 'm', ezz: '', eyz: '', exz: '',
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

/** Key of the plane a snapshot samples (a 3D run's slice; '' for a 2D snapshot). */
export function sliceKey(snap) {
  const s = snap && snap.slice;
  return s && s.normal ? `${s.normal}@${s.at}` : '';
}

/** A length in mm for a label: `2.0`, `2.5`, `12.75` (at least one decimal). */
function mm(m) {
  const v = Number(m) * 1e3;
  if (!Number.isFinite(v)) return '–';
  const r = Number(v.toPrecision(4));
  return Number.isInteger(r) ? r.toFixed(1) : String(r);
}

/**
 * The label of a 3D run's slice, e.g. `slice z = 2.0 mm (x–y plane)`, with the node plane
 * sampled when it is not the one asked for; '' for a 2D snapshot.
 */
export function sliceLabel(snap) {
  const s = snap && snap.slice;
  if (!s || !s.normal) return '';
  const axes = Array.isArray(s.axes) && s.axes.length === 2 ? ` (${s.axes[0]}–${s.axes[1]} plane)` : '';
  const node = Number.isFinite(Number(s.node_at)) && mm(s.node_at) !== mm(s.at) ? `, nodes at ${s.normal} = ${mm(s.node_at)} mm` : '';
  return `slice ${s.normal} = ${mm(s.at)} mm${axes}${node}`;
}
