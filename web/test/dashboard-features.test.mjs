// Unit tests of the pure parts of the gallery, sweep form, field-picture colour range,
// results tables, plot file names and the guide renderer: `node --test web/test/`.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { rangeParam, rangeProblem, rangeApplies, parseNumber, COMPONENT_UNITS, sliceKey, sliceLabel } from '../js/fields.js';
import { tipTable, referenceRows, scaled } from '../js/results.js';
import { slug, plotFileName, legendLayout } from '../js/download.js';
import { renderMarkdown, inline, linkTarget, headingId, escapeHtml } from '../js/markdown.js';
import { parseSweepValues, sweepParameters, numericPaths } from '../js/sweep.js';
import { estimateText, splitDescription } from '../js/views/gallery.js';

test('colour range: auto, symmetric and manual give the PNG’s range parameter', () => {
  assert.equal(rangeParam({ mode: 'auto' }), '');
  assert.equal(rangeParam(undefined), '');
  assert.equal(rangeParam({ mode: 'symmetric', abs: '2e6' }), '-2000000,2000000');
  assert.equal(rangeParam({ mode: 'symmetric', abs: '-3' }), '', 'a negative half-width is refused');
  assert.match(rangeProblem({ mode: 'symmetric', abs: '0' }), /positive/);
  assert.equal(rangeParam({ mode: 'manual', lo: '-1.5e6', hi: '4e6' }), '-1500000,4000000');
  assert.equal(rangeParam({ mode: 'manual', lo: '0', hi: '2,5' }), '0,2.5', 'decimal comma');
  assert.equal(rangeParam({ mode: 'manual', lo: '5', hi: '1' }), '');
  assert.match(rangeProblem({ mode: 'manual', lo: '5', hi: '1' }), /below/);
  assert.match(rangeProblem({ mode: 'manual', lo: 'x', hi: '1' }), /numbers/);
  assert.ok(Number.isNaN(parseNumber('2 MPa')));
  assert.equal(parseNumber(' 1e-3 '), 0.001);
  assert.equal(rangeApplies('sxx'), true);
  assert.equal(rangeApplies('fringe'), false);
  assert.equal(rangeApplies('material'), false);
  assert.equal(COMPONENT_UNITS.sxy, 'Pa');
  assert.equal(COMPONENT_UNITS.speed, 'm/s');
});

const tip = {
  crack: 0, tip: 1, samples: 101, x: 0.0231, y: 0.028, initiation_time: 4.2e-6, growth: 0.0011,
  j1_final: 120.5, j1_peak: 300, k1_final: 1.234e6, k1_peak: 2e6, k2_final: null, k2_peak: -1e4,
  mean_speed: 412.3, peak_speed: 655.2, speed_window: 2e-6,
};

test('results: one row per tip in mm, µs and MPa·√m, with the speed window', () => {
  assert.equal(tipTable(undefined), null);
  assert.equal(tipTable({ status: 'completed' }), null, 'an older summary has no tips');
  const t = tipTable({ tips: [tip, { ...tip, tip: 0, initiation_time: null, mean_speed: null, peak_speed: null }] });
  assert.equal(t.rows.length, 2);
  assert.equal(t.speedWindow, 2e-6);
  const col = (k) => t.columns.findIndex((c) => c.key === k);
  const r = t.rows[0].cells;
  assert.equal(t.rows[0].name, 'end tip');
  assert.equal(t.rows[1].name, 'start tip');
  assert.equal(r[col('initiation_time')], '4.2');
  assert.equal(t.columns[col('initiation_time')].unit, 'µs');
  assert.equal(r[col('growth')], '1.1');
  assert.equal(r[col('x')], '23.1');
  assert.equal(r[col('k1_final')], '1.234');
  assert.equal(t.columns[col('k1_final')].unit, 'MPa·√m');
  assert.equal(r[col('k2_final')], '–', 'null: undefined');
  assert.equal(r[col('k2_peak')], '-0.01');
  assert.equal(r[col('samples')], '101');
  assert.equal(t.rows[1].cells[col('initiation_time')], 'not initiated');
  assert.equal(t.rows[1].cells[col('peak_speed')], '–');
  const multi = tipTable({ tips: [tip, { ...tip, crack: 1 }] });
  assert.equal(multi.rows[1].name, 'crack 1 end tip');
  assert.equal(scaled(undefined, 1), '–');
  assert.equal(scaled(NaN, 1), '–');
});

test('results: references with the error in % and a mark only with a tolerance', () => {
  assert.deepEqual(referenceRows({}), []);
  const rows = referenceRows({ references: [
    { quantity: 'k1', at: 'late_mean', crack: 0, tip: 1, value: 1e6, measured: 1.05e6, relative_error: 0.05, source: 'Tada', tolerance: 0.1, within: true },
    { quantity: 'growth', at: 'final', crack: 0, value: 0.002, measured: 0.001, relative_error: -0.5, source: '', tolerance: 0.1, within: false },
    { quantity: 'peak_speed', at: 'final', crack: 0, value: 600, measured: null, relative_error: null, within: null },
  ] });
  assert.equal(rows[0].quantity, 'K_I');
  assert.equal(rows[0].value, '1 MPa·√m');
  assert.equal(rows[0].measured, '1.05 MPa·√m');
  assert.equal(rows[0].error, '5 %');
  assert.equal(rows[0].tolerance, '10 %');
  assert.equal(rows[0].mark, '✓');
  assert.match(rows[0].where, /mean over the last 20 %, crack 0, tip 1/);
  assert.equal(rows[1].value, '2 mm');
  assert.equal(rows[1].error, '-50 %');
  assert.equal(rows[1].mark, '✗');
  assert.equal(rows[2].measured, '–');
  assert.equal(rows[2].error, '–');
  assert.equal(rows[2].mark, '');
  assert.equal(rows[2].tolerance, '');
});

test('plot files: names from the run and the title', () => {
  assert.equal(plotFileName('edge crack', 'Crack-tip speed', 'svg'), 'edge-crack-crack-tip-speed.svg');
  assert.equal(plotFileName(undefined, 'Stress intensity factors', 'png'), 'stress-intensity-factors.png');
  assert.equal(plotFileName('', '', 'png'), 'plot.png');
  assert.equal(slug('J-integral (tip frame)'), 'j-integral-tip-frame');
  assert.equal(slug('Élan √ σxx'), 'elan-xx');
  assert.equal(slug('a'.repeat(100)).length, 60);
  const l = legendLayout([{ name: 'a'.repeat(30) }, { name: 'b'.repeat(30) }, { name: 'c' }], 300);
  assert.equal(l[0].y, 16);
  assert.equal(l[1].y, 32, 'the second does not fit on the first row');
  assert.ok(l[2].x > l[1].x);
});

test('sweep form: values, parameters in order, paths of a scene', () => {
  assert.deepEqual(parseSweepValues('25, 100,250'), [25, 100, 250]);
  assert.deepEqual(parseSweepValues('true, plane_stress, "x,y", [1, 2]'), [true, 'plane_stress', 'x,y', [1, 2]]);
  assert.throws(() => parseSweepValues(''), /at least one/);
  assert.throws(() => parseSweepValues('1,,2'), /empty/);
  const p = sweepParameters([{ path: 'z.b', values: '1,2' }, { path: '', values: '' }, { path: 'a', values: '3' }]);
  assert.deepEqual(Object.keys(p), ['z.b', 'a']);
  assert.deepEqual(p['z.b'], [1, 2]);
  assert.throws(() => sweepParameters([{ path: '', values: '1' }]), /path/);
  assert.throws(() => sweepParameters([{ path: 'a', values: '1' }, { path: 'a', values: '2' }]), /twice/);
  assert.throws(() => sweepParameters([]), /at least one/);
  assert.throws(() => sweepParameters([{ path: 'a', values: ' ' }]), /parameter 1 \(a\)/);
  const paths = numericPaths({ grid: { cell_size: 1e-3, min: [0, 0] }, cracks: [{ points: [[0, 1]], propagation: { toughness: 50 } }], name: 'x' });
  assert.deepEqual(paths, ['grid.cell_size', 'cracks.0.propagation.toughness']);
});

test('gallery: estimated wall time as text', () => {
  assert.equal(estimateText(null), '');
  assert.equal(estimateText(undefined), '');
  assert.equal(estimateText(0.2), 'under a second');
  assert.equal(estimateText(2.51), 'about 3 s');
  assert.equal(estimateText(12.3), 'about 10 s');
  assert.equal(estimateText(22.2), 'about 20 s');
  assert.equal(estimateText(177), 'about 3 min 00 s');
  assert.equal(estimateText(125), 'about 2 min 10 s');
  assert.equal(splitDescription('An unstressed square flying freely at (5, 2) m/s: ' + 'x '.repeat(120)).lead.endsWith('…'), true);
  const d = splitDescription('Mode I centre crack in a long strip under remote tension (Tada). Homalite-100 (E = 5.2 GPa). More text.');
  assert.equal(d.lead, 'Mode I centre crack in a long strip under remote tension (Tada).');
  assert.equal(d.rest, 'Homalite-100 (E = 5.2 GPa). More text.');
  assert.deepEqual(splitDescription('Short one.'), { lead: 'Short one.', rest: '' });
  const long = splitDescription('word '.repeat(100));
  assert.ok(long.lead.length <= 222 && long.lead.endsWith('…'), long.lead);
});

test('guides: Markdown to escaped HTML with dashboard links', () => {
  const html = renderMarkdown([
    '# Scene format',
    '',
    'A *scene* is **JSON**; see [extensions](scene-extensions.md#cracks) and [top](#grid).',
    'Still the same paragraph <script>x</script>.',
    '',
    '## The grid',
    '',
    '| key | meaning |',
    '| --- | --- |',
    '| `cell_size` | edge (m) \\| of a cell |',
    '',
    '- one',
    '  - nested',
    '- two',
    '',
    '1. first',
    '2. second',
    '',
    '```json',
    '{"a": "<b>"}',
    '```',
    '',
    '> quoted',
    '',
    '[bad](javascript:alert(1))',
  ].join('\n'), 'scenes');
  assert.match(html, /<h1 id="scene-format">Scene format<\/h1>/);
  assert.match(html, /<h2 id="the-grid">/);
  assert.match(html, /<em>scene<\/em>/);
  assert.match(html, /<strong>JSON<\/strong>/);
  assert.match(html, /href="#\/docs\/scene-extensions~cracks"/);
  assert.match(html, /href="#\/docs\/scenes~grid"/);
  assert.match(html, /Still the same paragraph &lt;script&gt;/);
  assert.ok(!html.includes('<script>'));
  assert.match(html, /<td><code>cell_size<\/code><\/td><td>edge \(m\) \| of a cell<\/td>/);
  assert.match(html, /<ul><li>one<ul><li>nested<\/li><\/ul><\/li><li>two<\/li><\/ul>/);
  assert.match(html, /<ol><li>first<\/li><li>second<\/li><\/ol>/);
  assert.match(html, /<code>\{&quot;a&quot;: &quot;&lt;b&gt;&quot;\}<\/code>/);
  assert.match(html, /<blockquote><p>quoted<\/p><\/blockquote>/);
  assert.ok(!html.includes('javascript:'));
  assert.equal(linkTarget('https://example.org/x'), 'https://example.org/x');
  assert.equal(linkTarget('/api/v1/docs'), '/api/v1/docs');
  assert.equal(linkTarget('data:text/html,x'), null);
  assert.equal(headingId('The `grid` (box)'), 'the-grid-box');
  assert.equal(inline('a_b_c and _x_'), 'a_b_c and <em>x</em>');
  assert.equal(escapeHtml('<"&\'>'), '&lt;&quot;&amp;&#39;&gt;');
});

test('a 3D snapshot is labelled with its plane; a 2D one has no plane', () => {
  const z = { index: 0, slice: { normal: 'z', at: 0.002, node_at: 0.002, axes: ['x', 'y'] } };
  const y = { index: 1, slice: { normal: 'y', at: 0.0125, node_at: 0.012, axes: ['x', 'z'] } };
  assert.equal(sliceLabel(z), 'slice z = 2.0 mm (x–y plane)');
  assert.equal(sliceLabel(y), 'slice y = 12.5 mm (x–z plane), nodes at y = 12.0 mm');
  assert.notEqual(sliceKey(z), sliceKey(y));
  assert.equal(sliceKey({ ...z, index: 2 }), sliceKey(z));
  assert.equal(sliceKey({ index: 0 }), '');
  assert.equal(sliceLabel({ index: 0 }), '');
  assert.equal(COMPONENT_UNITS.syz, 'Pa');
  assert.equal(COMPONENT_UNITS.vz, 'm/s');
});
