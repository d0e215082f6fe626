// Unit tests of the dashboard's pure modules: `node --test web/test/` (no browser, no
// packages). The browser test in tests/tests/dashboard.rs covers the pages.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { rayleighSpeed, waveSpeeds, sceneWaveSpeeds } from '../js/waves.js';
import { locate, splitPath, syntaxErrorPosition } from '../js/jsonlocate.js';
import { niceTicks, placeLabels, LABEL_GAP_PX } from '../js/plot.js';
import { prettyJson, siPrefix, num, parseLabels, etaSeconds, etaText, tipLabel, cacheNote } from '../js/util.js';
import { speedRefLines } from '../js/waves.js';

test('wave speeds of Homalite-100 match reference-solutions.md', () => {
  const pe = waveSpeeds(5.2e9, 0.34, 1230, 'plane_strain');
  const ps = waveSpeeds(5.2e9, 0.34, 1230, 'plane_stress');
  assert.equal(Math.round(pe.cS), 1256);
  assert.equal(Math.round(pe.cL), 2551);
  assert.equal(Math.round(ps.cL), 2186);
  assert.equal(Math.round(pe.cR), 1172);
  assert.equal(Math.round(ps.cR), 1156);
  assert.equal(Math.round(pe.sqrt2cS), 1776);
});

test('the Rayleigh speed solves the Rayleigh equation exactly', () => {
  for (const nu of [0.0, 0.2, 0.25, 0.34, 0.45, 0.49]) {
    const { cL, cS, cR } = waveSpeeds(1e9, nu, 1000);
    const x = (cR / cS) ** 2, k = (cS / cL) ** 2;
    assert.ok(Math.abs((2 - x) ** 2 - 4 * Math.sqrt(1 - x) * Math.sqrt(1 - k * x)) < 1e-12, `nu=${nu}`);
    assert.ok(cR < cS && cR > 0.87 * cS);
  }
  // ν = 0.25 (κ = 1/3): x = 2 − 2/√3 (Rayleigh's classical root)
  const { cS, cL } = waveSpeeds(1e9, 0.25, 1000);
  assert.ok(Math.abs(rayleighSpeed(cL, cS) / cS - Math.sqrt(2 - 2 / Math.sqrt(3))) < 1e-12);
});

test('the material is the one the crack lies in', () => {
  const scene = {
    materials: { soft: { youngs_modulus: 1e9, poissons_ratio: 0.3, density: 1000 }, stiff: { youngs_modulus: 2e11, poissons_ratio: 0.3, density: 7800 } },
    bodies: [
      { material: 'stiff', region: { rectangle: { min: [0, 0], max: [1, 1] } } },
      { material: 'soft', region: { circle: { center: [3, 3], radius: 1 } } },
    ],
    cracks: [{ points: [[3, 3], [3.5, 3]] }],
  };
  assert.equal(sceneWaveSpeeds(scene).name, 'soft');
  assert.equal(sceneWaveSpeeds({ ...scene, cracks: [] }).name, 'stiff');
  assert.equal(sceneWaveSpeeds({}), null);
});

test('a validator path is found at its line', () => {
  const text = prettyJson({ name: 'x', materials: { 'pl.ate': { poissons_ratio: 0.7 } }, bodies: [{ material: 'a' }, { material: 'b', region: { rectangle: { min: [0, 0] } } }] });
  const lines = text.split('\n');
  const at = (p) => lines[locate(text, p).line - 1];
  assert.match(at('materials.pl.ate.poissons_ratio'), /poissons_ratio/);
  assert.match(at('bodies.1.material'), /"b"/);
  assert.match(at('bodies[1].region.rectangle.min'), /"min"/);
  assert.equal(locate(text, 'time.end').found, false);
  assert.deepEqual(splitPath('a[0].b["c"]'), ['a', '0', 'b', 'c']);
});

test('JSON syntax errors are placed', () => {
  const text = '{\n  "a": 1,\n  "b": }\n';
  let err;
  try { JSON.parse(text); } catch (e) { err = e; }
  assert.equal(syntaxErrorPosition(text, err).line, 3);
});

test('ticks, prefixes, numbers, labels', () => {
  assert.deepEqual(niceTicks(0, 100, 5), [0, 20, 40, 60, 80, 100]);
  assert.deepEqual(niceTicks(0.3, 1.1, 4), [0.4, 0.6, 0.8, 1]);
  assert.deepEqual(siPrefix(2.5e6), { factor: 1e6, prefix: 'M' });
  assert.deepEqual(siPrefix(3e-5), { factor: 1e-6, prefix: 'µ' });
  assert.equal(num(1234.5678), '1235');
  assert.equal(num(1.5e-5), '1.500e-5');
  assert.deepEqual(parseLabels('a:b, c=d'), { a: 'b', c: 'd' });
  assert.throws(() => parseLabels('nocolon'));
});

test('prettyJson round-trips and keeps points on one line', () => {
  const v = { grid: { min: [0, 0], max: [0.1, 0.1] }, cracks: [{ points: [[0.04, 0.05], [0.06, 0.05]] }], e: [], o: {} };
  const t = prettyJson(v);
  assert.deepEqual(JSON.parse(t), v);
  assert.match(t, /"points": \[\[0.04, 0.05\], \[0.06, 0.05\]\]/);
});

test('reference labels close together are staggered, never overlapping', () => {
  // Homalite: c_R and c_S are 7 % apart: a few pixels on a 200 px plot of 0 … c_L.
  const sp = waveSpeeds(5.2e9, 0.34, 1230, 'plane_strain');
  const sy = (v) => 220 - (v / (1.05 * sp.cL)) * 200;
  const labels = speedRefLines(sp).map((r) => ({ y: sy(r.y), text: r.label }));
  const cR = labels.find((l) => l.text === 'c_R'), cS = labels.find((l) => l.text === 'c_S');
  assert.ok(Math.abs(cR.y - cS.y) < LABEL_GAP_PX, 'the case of the bug: lines closer than a label');
  for (const columns of [1, 2]) {
    const placed = placeLabels(labels, columns, LABEL_GAP_PX);
    assert.equal(placed.length, labels.length);
    for (let i = 0; i < placed.length; i++) {
      for (let j = i + 1; j < placed.length; j++) {
        if (placed[i].column === placed[j].column) {
          assert.ok(Math.abs(placed[i].y - placed[j].y) >= LABEL_GAP_PX, `${placed[i].text} / ${placed[j].text} overlap`);
        }
      }
    }
    if (columns === 2) {
      // staggered: both stay on their own lines, in different columns
      const r = placed.find((l) => l.text === 'c_R'), s = placed.find((l) => l.text === 'c_S');
      assert.notEqual(r.column, s.column);
      assert.equal(r.y, cR.y);
      assert.equal(s.y, cS.y);
    }
  }
  // far-apart labels stay in the first column at their own height
  const far = placeLabels([{ y: 10, text: 'a' }, { y: 100, text: 'b' }], 2, LABEL_GAP_PX);
  assert.deepEqual(far.map((l) => [l.y, l.column]), [[10, 0], [100, 0]]);
});

test('the ETA follows the rate so far', () => {
  assert.equal(etaSeconds(0.25, 30), 90);
  assert.equal(etaSeconds(1, 30), 0);
  assert.equal(etaSeconds(0.001, 30), null);
  assert.equal(etaSeconds(NaN, 30), null);
  const started = '2026-01-01T00:00:00.000Z';
  const now = Date.parse(started) + 60_000;
  assert.equal(etaText({ status: 'running', started_at: started, progress: { fraction: 0.5 } }, now), 'about 1 min 00 s left');
  assert.equal(etaText({ status: 'queued', started_at: null, progress: null }, now), '');
  assert.equal(etaText({ status: 'completed', started_at: started, progress: { fraction: 1 } }, now), '');
});

test('tip labels name cracks, ends and interface fronts', () => {
  assert.equal(tipLabel(0, 1, false, 1), 'end tip');
  assert.equal(tipLabel(0, 0, true, 2), 'crack 0 start tip');
  // Interface rows come after the scene's cracks (run-output.md).
  assert.equal(tipLabel(1, 1, true, 1), 'interface 0 front');
  assert.equal(tipLabel(3, 1, true, 1), 'interface 2 front');
  // Unknown crack count: no row is taken for an interface.
  assert.equal(tipLabel(5, 1, true), 'crack 5 end tip');
});

test('cacheNote marks a job answered from the cache, and only such a job', () => {
  const n = cacheNote({ id: 'b', status: 'completed', cached_from: 'a1' });
  assert.equal(n.text, 'from cache');
  assert.equal(n.of, 'a1');
  assert.ok(n.title.includes('a1'));
  assert.equal(cacheNote({ id: 'a1', status: 'completed' }), null);
  assert.equal(cacheNote({ id: 'c', status: 'completed', cached_from: null }), null);
  assert.equal(cacheNote({ id: 'c', status: 'queued', cached_from: '' }), null);
  assert.equal(cacheNote(null), null);
});
