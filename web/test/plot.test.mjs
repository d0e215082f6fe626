// The plotting module's pure parts (web/js/plot.js): ticks, zoom and pan transforms, drag
// selection, nearest sample, thinning, legend state, hover rows. `node --test web/test/`.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { niceTicks, zoomAround, panBy, dragRange, nearestIndex, lowerBound, thinIndices, legendToggle, hoverRows, movingMean, filterWindows, MIN_SPAN } from '../js/plot.js';

const close = (a, b, tol = 1e-12) => Math.abs(a - b) <= tol * Math.max(1, Math.abs(a), Math.abs(b));

test('ticks are nice, inside the range and evenly spaced', () => {
  for (const [lo, hi] of [[0, 1], [0, 87.3], [-3e-5, 2e-5], [1172, 2551], [0.1, 0.1003]]) {
    const t = niceTicks(lo, hi, 5);
    assert.ok(t.length >= 2 && t.length <= 12, `${lo}..${hi}: ${t}`);
    assert.ok(t[0] >= lo - 1e-9 * (hi - lo) && t[t.length - 1] <= hi + 1e-9 * (hi - lo));
    const step = t[1] - t[0];
    const m = step / 10 ** Math.floor(Math.log10(step) + 1e-9);
    assert.ok([1, 2, 2.5, 5].some((x) => close(m, x, 1e-9)), `step ${step}`);
    for (let i = 1; i < t.length; i++) assert.ok(close(t[i] - t[i - 1], step, 1e-6));
  }
  assert.deepEqual(niceTicks(3, 3), [3]);
});

test('zooming keeps the point under the cursor still and stays inside the full range', () => {
  const full = [0, 100];
  const z = zoomAround([0, 100], 30, 0.5, full);
  assert.deepEqual(z, [15, 65]);
  // the cursor's fraction of the span is unchanged
  const z2 = zoomAround(z, 20, 0.8, full);
  assert.ok(close((20 - z2[0]) / (z2[1] - z2[0]), (20 - z[0]) / (z[1] - z[0])));
  // zooming out past the full range is no zoom at all
  assert.equal(zoomAround([40, 60], 50, 10, full), null);
  // zooming out near an edge shifts back inside
  const z3 = zoomAround([0, 10], 2, 3, full);
  assert.ok(z3[0] >= 0 && close(z3[1] - z3[0], 30));
  // no span below MIN_SPAN of the full range
  const deep = zoomAround([50, 50.0001], 50, 1e-6, full);
  assert.ok(close(deep[1] - deep[0], 100 * MIN_SPAN) && deep[0] <= 50 && deep[1] >= 50);
  // without a full range: plain scaling
  assert.deepEqual(zoomAround([0, 4], 2, 2), [-2, 6]);
});

test('panning shifts the span and stops at the ends', () => {
  assert.deepEqual(panBy([10, 20], 5, [0, 100]), [15, 25]);
  assert.deepEqual(panBy([10, 20], -50, [0, 100]), [0, 10]);
  assert.deepEqual(panBy([80, 95], 50, [0, 100]), [85, 100]);
  assert.deepEqual(panBy([10, 20], 500), [510, 520]);
});

test('a drag selects the data range under it, clipped to the plot; a click selects nothing', () => {
  const axis = { left: 50, width: 200, x0: 0, x1: 1e-4 };
  const r = dragRange(250, 100, axis);
  assert.ok(close(r[0], 0.25e-4) && close(r[1], 1e-4));
  const clipped = dragRange(10, 70, axis);
  assert.ok(close(clipped[0], 0) && close(clipped[1], 0.1e-4));
  assert.equal(dragRange(120, 123, axis), null);
});

test('the nearest sample and the lower bound', () => {
  const xs = [0, 1, 2, 4, 8];
  assert.equal(nearestIndex(xs, -5), 0);
  assert.equal(nearestIndex(xs, 2.9), 2);
  assert.equal(nearestIndex(xs, 3.1), 3);
  assert.equal(nearestIndex(xs, 100), 4);
  assert.equal(nearestIndex([], 1), -1);
  assert.equal(lowerBound(xs, 3), 3);
  assert.equal(lowerBound(xs, 0), 0);
  assert.equal(lowerBound(xs, 9), 5);
});

test('thinning keeps per column the first, extremes and last, and every gap', () => {
  const n = 100000;
  const xs = Array.from({ length: n }, (_, i) => i / n);
  const ys = xs.map((x) => Math.sin(40 * x));
  ys[5000] = 50; // a spike
  ys[7000] = NaN; // a gap
  const cols = 300;
  const col = (x) => x * cols;
  const idx = thinIndices(xs, ys, 0, n, col, cols);
  assert.ok(idx.length <= 4 * cols + 2, `${idx.length} points for ${cols} columns`);
  assert.ok(idx.includes(5000) && idx.includes(7000) && idx.includes(0) && idx.includes(n - 1));
  for (let i = 1; i < idx.length; i++) assert.ok(idx[i] > idx[i - 1]);
  // per column, the drawn points hold the column's true min and max
  const c = 17;
  const inCol = [...xs.keys()].filter((i) => Math.floor(col(xs[i])) === c);
  const drawn = idx.filter((i) => inCol.includes(i)).map((i) => ys[i]);
  assert.equal(Math.max(...drawn), Math.max(...inCol.map((i) => ys[i])));
  assert.equal(Math.min(...drawn), Math.min(...inCol.map((i) => ys[i])));
  // few samples: all of them
  assert.deepEqual(thinIndices([0, 1, 2], [1, 2, 3], 0, 3, (x) => x, 100), [0, 1, 2]);
});

test('legend clicks toggle one series; Shift-click shows only one, again all', () => {
  const all = { a: true, b: true, c: true };
  assert.deepEqual(legendToggle(all, 'b'), { a: true, b: false, c: true });
  assert.deepEqual(legendToggle({ a: true, b: false, c: true }, 'b'), all);
  const solo = legendToggle(all, 'c', true);
  assert.deepEqual(solo, { a: false, b: false, c: true });
  assert.deepEqual(legendToggle(solo, 'c', true), all);
  assert.deepEqual(legendToggle(solo, 'a', true), { a: true, b: false, c: false });
  assert.deepEqual(all, { a: true, b: true, c: true }); // input unchanged
});

test('hover rows hold each visible series\' nearest sample', () => {
  const series = [
    { key: 'v', name: 'speed', color: '#000', visible: true, xs: [0, 1e-6, 2e-6], ys: [0, 300, 600] },
    { key: 'w', name: 'hidden', color: '#111', visible: false, xs: [0, 1e-6], ys: [1, 2] },
    { key: 'e', name: 'empty', color: '#222', visible: true, xs: [], ys: [] },
    { key: 'x', name: 'x', color: '#333', visible: true, xs: [0.5e-6, 1.9e-6], ys: [0.01, 0.02] },
  ];
  const rows = hoverRows(series, 1.6e-6);
  assert.deepEqual(rows.map((r) => [r.key, r.t, r.y]), [['v', 2e-6, 600], ['x', 1.9e-6, 0.02]]);
});

test('the moving mean averages the samples within the window and keeps gaps', () => {
  const xs = [0, 1, 2, 3, 4, 5];
  const ys = [0, 10, 0, 10, NaN, 10];
  const m = movingMean(xs, ys, 2); // ±1
  assert.deepEqual(m.slice(0, 4), [5, 10 / 3, 20 / 3, 5]);
  assert.ok(Number.isNaN(m[4]));
  assert.equal(m[5], 10); // its neighbour within ±1 is the gap
  assert.equal(movingMean(xs, ys, 0), ys);
  // a zig-zag becomes its mean
  const zx = Array.from({ length: 200 }, (_, i) => i * 1e-7);
  const zy = zx.map((_, i) => (i % 2 ? 1200 : 0));
  const zm = movingMean(zx, zy, 2e-6);
  for (let i = 20; i < 180; i++) assert.ok(Math.abs(zm[i] - 600) < 60, `${i}: ${zm[i]}`);
});

test('filter windows are round fractions of the span', () => {
  const ws = filterWindows(80e-6);
  assert.equal(ws[0], 0);
  assert.ok(ws.includes(1e-6), String(ws));
  for (const w of ws.slice(1)) {
    const m = w / 10 ** Math.floor(Math.log10(w) + 1e-9);
    assert.ok([1, 2, 5].some((x) => close(m, x, 1e-9)) && w < 80e-6 / 10, `${w}`);
  }
  assert.deepEqual(filterWindows(0), [0]);
});

test('a moving mean extended from an index equals the full one', () => {
  const xs = [], ys = [];
  for (let i = 0; i < 500; i++) { xs.push(i * 1e-7 + (i % 3) * 1e-9); ys.push(i % 7 === 0 ? NaN : Math.sin(i) * 1000); }
  const full = movingMean(xs, ys, 1e-6);
  // the first 300 samples, then 200 appended: recompute from w/2 before the first new one
  const out = movingMean(xs.slice(0, 300), ys.slice(0, 300), 1e-6);
  const part = movingMean(xs, ys, 1e-6, lowerBound(xs, xs[300] - 0.5e-6), out);
  assert.equal(part.length, 500);
  for (let i = 0; i < 500; i++) {
    assert.ok(Number.isNaN(full[i]) ? Number.isNaN(part[i]) : Math.abs(part[i] - full[i]) < 1e-9, `${i}`);
  }
});
