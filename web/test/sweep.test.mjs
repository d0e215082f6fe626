// Unit tests of web/js/sweep.js: `node --test web/test/`.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { TipHistory, countsText, isActive, parameterText, seriesName } from '../js/sweep.js';

test('tip histories ignore repeated and older rows and track the poll cursor', () => {
  const h = new TipHistory();
  assert.equal(h.since(), undefined);
  const rows = [
    { time: 0, crack: 0, tip: 1, speed: 0 },
    { time: 1e-6, crack: 0, tip: 1, speed: 500 },
    { time: 1e-6, crack: 0, tip: 0, speed: 10 },
  ];
  assert.equal(h.add(rows), 3);
  // a poll with ?since= repeats the rows at the cursor: nothing doubles
  assert.equal(h.add([rows[1], rows[2], { time: 2e-6, crack: 0, tip: 1, speed: 2551, length: 0.012 }]), 1);
  assert.equal(h.size, 4);
  assert.deepEqual(h.tips.get('0/1').t, [0, 1e-6, 2e-6]);
  assert.deepEqual(h.tips.get('0/1').v, [0, 500, 2551]);
  // the crack length goes with it (a gap where a row has none)
  assert.deepEqual(h.tips.get('0/1').l.map((l) => (Number.isNaN(l) ? null : l)), [null, null, 0.012]);
  assert.equal(h.since(), 1e-6); // the slower tip decides
  assert.equal(h.maxSpeed, 2551);
  assert.equal(h.multiCrack, false);
  // NaN speeds (null in JSON) stay as gaps; bad times are skipped
  assert.equal(h.add([{ time: 3e-6, crack: 1, tip: 0, speed: null }, { time: 'x', crack: 0, tip: 1 }]), 1);
  assert.ok(Number.isNaN(h.tips.get('1/0').v[0]));
  assert.equal(h.multiCrack, true);
});

test('sweep summaries', () => {
  const s = { status: 'running', total: 3, counts: { queued: 1, running: 1, completed: 1, failed: 0, cancelled: 0 } };
  assert.equal(countsText(s), '3 jobs: 1 completed, 1 running, 1 queued');
  assert.equal(isActive(s), true);
  assert.equal(isActive({ status: 'completed', total: 1, counts: { completed: 1 } }), false);
  assert.equal(isActive({ status: 'failed', counts: { running: 1 } }), true);
  assert.equal(countsText({ total: 1, counts: {} }), '1 job');
  assert.deepEqual(parameterText([{ path: 'cracks.0.propagation.toughness', values: [25, 100] }, { path: 'analysis', values: ['plane_stress'] }]),
    ['cracks.0.propagation.toughness: 25, 100', 'analysis: plane_stress']);
});

test('series names add the tip only when a job has several', () => {
  assert.equal(seriesName('toughness=25', { crack: 0, tip: 1 }, 1, false), 'toughness=25');
  assert.equal(seriesName('toughness=25', { crack: 0, tip: 0 }, 2, false), 'toughness=25, start tip');
  assert.equal(seriesName('toughness=25', { crack: 1, tip: 1 }, 3, true), 'toughness=25, crack 1 end tip');
});
