// One run: live while running (Server-Sent Events), complete after. Plots of the crack-tip
// speed (with wave-speed reference lines), position/length, J, K and the energy balance;
// field snapshots with a time slider and a colour-range control; the results summary (per
// tip, and against the scene's references); the crack-path picture; summary, scene,
// downloads, cancel/delete; a note when the run was restarted from a checkpoint. A 3D run
// (`"analysis": "3d"`) has no crack tips: its page shows the energy balance and its slices
// (each snapshot a plane of the grid, chosen with the slice selector and named under the
// picture).

import * as api from '../api.js';
import { Plot, PALETTE, DASHES } from '../plot.js';
import { sceneWaveSpeeds, speedRefLines } from '../waves.js';
import { h, replace, num, si, count, duration, timeEl, timeUnit, statusBadge, saveBlob, notify, prettyJson, orderScene, etaText, tipLabel, cacheNote } from '../util.js';
import { wallTime, labelChips } from './runs.js';
import { COMPONENT_UNITS, rangeApplies, rangeParam, rangeProblem, sliceKey, sliceLabel } from '../fields.js';
import { tipTable, referenceRows } from '../results.js';

const TERMINAL = new Set(['completed', 'failed', 'cancelled']);
const COMPONENT_ORDER = ['fringe', 'sxx', 'syy', 'szz', 'sxy', 'syz', 'sxz', 'von_mises', 'speed', 'vx', 'vy', 'vz', 'ux', 'uy', 'uz', 'exx', 'eyy', 'ezz', 'exy', 'eyz', 'exz', 'material'];
const KIND_COMPONENTS = {
  stress: ['sxx', 'syy', 'sxy'], strain: ['exx', 'eyy', 'exy'], velocity: ['vx', 'vy', 'speed'],
  displacement: ['ux', 'uy'], fringe: ['fringe'], material: ['material'],
};
const COMPONENT_NAMES = {
  fringe: 'Isochromatic fringes', sxx: 'σxx', syy: 'σyy', sxy: 'σxy', speed: 'Velocity magnitude', vx: 'vx', vy: 'vy',
  ux: 'ux', uy: 'uy', exx: 'εxx', eyy: 'εyy', exy: 'εxy', material: 'Material', von_mises: 'von Mises stress', umag: 'Displacement magnitude',
  szz: 'σzz', syz: 'σyz', sxz: 'σxz', vz: 'vz', uz: 'uz', ezz: 'εzz', eyz: 'εyz', exz: 'εxz',
};

/** Rows from an SSE payload or API answer: an array, one row, or {rows|items|data: [...]}. */
export function rowsOf(d) {
  if (!d) return [];
  if (Array.isArray(d)) return d;
  if (Array.isArray(d.rows)) return d.rows;
  if (Array.isArray(d.items)) return d.items;
  if (Array.isArray(d.data)) return d.data;
  return typeof d === 'object' && 'time' in d ? [d] : [];
}

/** Components a snapshot offers (its `fields` may list kinds or components). */
export function snapshotComponents(snap) {
  const out = new Set();
  if (snap && Array.isArray(snap.components) && snap.components.length) for (const c of snap.components) out.add(c);
  else for (const f of (snap && snap.fields) || []) for (const c of KIND_COMPONENTS[f] || [f]) out.add(c);
  return [...out].sort((a, b) => (COMPONENT_ORDER.indexOf(a) + 99) % 99 - (COMPONENT_ORDER.indexOf(b) + 99) % 99 || a.localeCompare(b));
}

/** Series name of a crack tip (or of an interface's failure front, past `nCracks`). */
export function tipName(row, multiCrack, nCracks = Infinity) {
  return tipLabel(row.crack, row.tip, multiCrack, nCracks);
}

/** Counts the picture `el` as a read in flight (`api.settled`) until it loads or fails. */
function trackPicture(el) {
  api.track(new Promise((resolve) => {
    el.addEventListener('load', resolve, { once: true });
    el.addEventListener('error', resolve, { once: true });
  }));
}

export function runView(main, { id }) {
  let alive = true;
  let job = null;
  let closeEvents = null;
  let pollTimer = 0;
  let playTimer = 0;
  const plots = [];
  const lastTip = new Map(); // "crack/tip" → last time plotted
  let lastEnergy = -Infinity;
  const tipKeys = [];
  let snapshots = [];
  let multiCrack = false;
  let speeds = null;
  let maxSpeed = 0;

  const titleEl = h('h1', {}, 'Run');
  const badgeHost = h('span', { class: 'badge-host' });
  const actions = h('div', { class: 'actions' });
  const progressHost = h('div', { class: 'run-progress' });
  const metaHost = h('dl', { class: 'meta' });
  const plotGrid = h('div', { class: 'plot-grid' });
  const snapHost = h('section', { class: 'card', 'aria-labelledby': 'snap-h' });
  const summaryHost = h('section', { class: 'card', 'aria-labelledby': 'sum-h' });
  const resultsHost = h('section', { class: 'card', id: 'results', 'aria-labelledby': 'results-h', hidden: true });
  const pathHost = h('section', { class: 'card', id: 'crack-path', 'aria-labelledby': 'path-h', hidden: true });
  const restartHost = h('div', { id: 'restart-note' });
  const sceneHost = h('section', { class: 'card', 'aria-labelledby': 'scene-h' });
  const downloads = h('section', { class: 'card', 'aria-labelledby': 'dl-h' });
  const messageHost = h('div');

  replace(main,
    h('p', { class: 'crumbs' }, h('a', { href: '#/runs' }, '← Runs')),
    h('div', { class: 'page-head' }, h('div', { class: 'title-row' }, titleEl, badgeHost), actions),
    messageHost, restartHost, progressHost, metaHost,
    resultsHost,
    h('section', { 'aria-labelledby': 'plots-h' }, h('h2', { id: 'plots-h' }, 'Histories'), plotGrid),
    h('div', { class: 'fig-row' }, snapHost, pathHost), summaryHost, downloads, sceneHost);

  // ---- plots ----------------------------------------------------------------------------
  const tu0 = { factor: 1e-6, unit: 'µs' };
  const speedPlot = new Plot(plotGrid, { id: 'plot-speed', title: 'Crack-tip speed', yLabel: 'speed', yUnit: 'm/s', yPrefix: false, yZero: true, xUnit: tu0, filter: 0, empty: 'No crack-tip data yet' });
  const posPlot = new Plot(plotGrid, { id: 'plot-position', title: 'Crack-tip position and crack length', yLabel: 'position, length', yUnit: 'm', xUnit: tu0, empty: 'No crack-tip data yet' });
  const jPlot = new Plot(plotGrid, { id: 'plot-j', title: 'J-integral (tip frame)', yLabel: 'J', yUnit: 'J/m²', xUnit: tu0, filter: 0, empty: 'No crack-tip data yet' });
  const kPlot = new Plot(plotGrid, { id: 'plot-k', title: 'Stress intensity factors', yLabel: 'K', yUnit: 'Pa·√m', xUnit: tu0, filter: 0, empty: 'No crack-tip data yet' });
  const ePlot = new Plot(plotGrid, { id: 'plot-energy', title: 'Energy balance', yLabel: 'energy', yUnit: 'J', xUnit: tu0, empty: 'No energy data yet' });
  plots.push(speedPlot, posPlot, jPlot, kPlot, ePlot);
  const energyCols = [['kinetic', 'kinetic'], ['strain', 'strain'], ['external_work', 'external work'], ['dissipated', 'dissipated'], ['total_error', 'error (balance)']];
  energyCols.forEach(([k, name], i) => ePlot.ensure(k, { name, color: PALETTE[i], dash: k === 'total_error' ? DASHES[1] : '' }));

  /** Whether the run is 3D (its scene's `analysis`, or its summary's `dimension`). */
  const is3d = () => !!job && ((job.scene && job.scene.analysis === '3d') || (job.summary && Number(job.summary.dimension) === 3));
  /** A 3D run has no crack tips (run-output.md): its tip plots are hidden, its energy plot stays. */
  function applyDimension() {
    const three = is3d();
    for (const p of [speedPlot, posPlot, jPlot, kPlot]) p.root.hidden = three;
    plotGrid.dataset.dimension = three ? '3' : '2';
  }

  function addTipRows(rows) {
    let changed = false;
    for (const r of rows) {
      if (!r || !Number.isFinite(Number(r.time))) continue;
      const key = `${r.crack}/${r.tip}`;
      const t = Number(r.time);
      if (lastTip.has(key) && t <= lastTip.get(key)) continue;
      if (!lastTip.has(key)) tipKeys.push(key);
      lastTip.set(key, t);
      if (Number(r.crack) > 0) multiCrack = true;
      const color = PALETTE[tipKeys.indexOf(key) % PALETTE.length];
      const nCracks = job && job.scene && Array.isArray(job.scene.cracks) ? job.scene.cracks.length : Infinity;
      const n = tipName(r, multiCrack, nCracks);
      speedPlot.push(key, t, r.speed, { name: `speed, ${n}`, color });
      posPlot.push(`${key}x`, t, r.x, { name: `x, ${n}`, color });
      posPlot.push(`${key}y`, t, r.y, { name: `y, ${n}`, color, dash: DASHES[1] });
      posPlot.push(`${key}l`, t, r.length, { name: `length, ${n}`, color, dash: DASHES[2] });
      // An interface's process-zone front (run-output.md: `zone_x`, empty before any point
      // has softened), beside its failure front `x`.
      if (r.zone_x !== null && r.zone_x !== undefined && r.zone_x !== '' && Number.isFinite(Number(r.zone_x))) {
        posPlot.push(`${key}z`, t, Number(r.zone_x), { name: `process-zone front x, ${n}`, color, dash: DASHES[3] });
      }
      // The failure front connected to the interface's start (`connected_x`): apart from `x`
      // when a point ahead failed first (a daughter crack).
      if (r.connected_x !== null && r.connected_x !== undefined && r.connected_x !== '' && Number.isFinite(Number(r.connected_x))) {
        posPlot.push(`${key}c`, t, Number(r.connected_x), { name: `connected failure front x, ${n}`, color, dash: DASHES[2] });
      }
      jPlot.push(`${key}1`, t, r.j1, { name: `J1, ${n}`, color });
      jPlot.push(`${key}2`, t, r.j2, { name: `J2, ${n}`, color, dash: DASHES[1] });
      kPlot.push(`${key}1`, t, r.k1, { name: `K_I, ${n}`, color });
      kPlot.push(`${key}2`, t, r.k2, { name: `K_II, ${n}`, color, dash: DASHES[1] });
      if (Number.isFinite(r.speed)) maxSpeed = Math.max(maxSpeed, Math.abs(r.speed));
      changed = true;
    }
    return changed;
  }

  function addEnergyRows(rows) {
    for (const r of rows) {
      const t = Number(r && r.time);
      if (!Number.isFinite(t) || t <= lastEnergy) continue;
      lastEnergy = t;
      for (const [k] of energyCols) ePlot.push(k, t, r[k]);
      // Fracture energy (run-output.md's `fracture` column, part of `dissipated`): shown
      // once a run has any.
      const fr = Number(r.fracture);
      if (Number.isFinite(fr) && (fr !== 0 || ePlot.series.some((x) => x.key === 'fracture'))) {
        ePlot.push('fracture', t, fr, { name: 'fracture (in dissipated)', color: PALETTE[energyCols.length], dash: DASHES[2] });
      }
    }
  }

  async function fillHistories() {
    const since = (m) => (m.size ? Math.min(...m.values()) : undefined);
    const [tips, energy] = await Promise.all([
      api.history(id, 'crack-tips', since(lastTip)).catch(softFail),
      api.history(id, 'energy', Number.isFinite(lastEnergy) ? lastEnergy : undefined).catch(softFail),
    ]);
    if (!alive) return;
    if (addTipRows(rowsOf(tips))) renderSummary();
    addEnergyRows(rowsOf(energy));
  }

  function softFail(e) {
    if (e instanceof api.ApiError && e.status === 404) return [];
    throw e;
  }

  // ---- header, progress, actions --------------------------------------------------------
  function renderHeader() {
    titleEl.textContent = job.name || job.id;
    document.title = `${job.name || job.id} · mpm-fracture`;
    applyDimension();
    replace(badgeHost, statusBadge(job.status));
    const running = job.status === 'running' || job.status === 'queued';
    replace(actions,
      running ? h('button', { type: 'button', class: 'danger', id: 'cancel-run', onclick: onCancel }, 'Cancel run') : null,
      TERMINAL.has(job.status) ? h('button', { type: 'button', class: 'danger secondary', id: 'delete-run', onclick: onDelete }, 'Delete run') : null,
      h('a', { class: 'button secondary', id: 'clone-run', href: `#/submit?from=${encodeURIComponent(id)}`, title: 'Open the scene editor with this run’s scene' }, 'Clone'),
      h('button', { type: 'button', class: 'secondary', id: 'rerun-run', onclick: onRerun, title: 'Run the same scene again, with the same name and labels' }, 'Rerun'),
      h('a', { class: 'button secondary', href: `#/compare?ids=${encodeURIComponent(id)}` }, 'Compare…'));
    replace(messageHost, job.message && job.status !== 'completed' ? h('p', { class: job.status === 'failed' ? 'error' : 'notice' }, job.message) : null);
    renderRestart();
    renderProgress();
    replace(metaHost,
      meta('Id', h('span', { class: 'mono' }, job.id)),
      cacheNote(job) ? meta('From cache', h('span', { id: 'from-cache', title: cacheNote(job).title }, 'from cache: the results of run ',
        h('a', { href: `#/runs/${encodeURIComponent(job.cached_from)}`, id: 'cached-from-link', class: 'mono' }, job.cached_from))) : null,
      job.rerun_of ? meta('Rerun of', h('a', { href: `#/runs/${encodeURIComponent(job.rerun_of)}`, id: 'rerun-of-link', class: 'mono' }, job.rerun_of)) : null,
      job.sweep_id ? meta('Sweep', h('a', { href: `#/sweeps/${encodeURIComponent(job.sweep_id)}`, id: 'run-sweep-link' }, 'part of a sweep: compare its runs')) : null,
      meta('Labels', labelChips(job.labels)),
      meta('Created', timeEl(job.created_at)),
      meta('Started', timeEl(job.started_at)),
      meta('Finished', timeEl(job.finished_at)),
      meta('Wall time', duration(wallTime(job))),
      meta('Attempts', String(job.attempts ?? '–')),
      speeds ? meta('Wave speeds', h('span', {}, `${speeds.name} (${speeds.analysis.replace('_', ' ')}): c_L ${num(speeds.speeds.cL, 4)}, c_S ${num(speeds.speeds.cS, 4)}, c_R ${num(speeds.speeds.cR, 4)}, √2·c_S ${num(speeds.speeds.sqrt2cS, 4)} m/s`)) : null);
  }

  // ---- restarts ---------------------------------------------------------------------------
  // A job whose worker died goes back to the queue and resumes from its last checkpoint:
  // its progress falls back. Said from `attempts`, a fall of the progress fraction seen
  // live, and the stream's restart events (their message as sent).
  const restarts = []; // texts, newest last
  let lastFraction = null;
  function noteRestart(text) {
    if (!restarts.includes(text)) restarts.push(text);
    renderRestart();
  }
  function renderRestart() {
    if (!job) return;
    const k = Number(job.attempts) || 0;
    const lines = [...restarts];
    if (!lines.length && k > 1) lines.push(`This run was restarted: attempt ${k}${job.max_attempts ? ` of at most ${job.max_attempts}` : ''} (a worker was lost; the run resumed from its last checkpoint, or from the start without one).`);
    replace(restartHost, lines.length ? h('p', { class: 'notice', role: 'status' }, h('strong', {}, 'Restarted. '), lines.join(' ')) : null);
  }
  function watchFraction(p) {
    const f = p && Number(p.fraction);
    if (!Number.isFinite(f)) return;
    if (lastFraction !== null && f < lastFraction - 1e-9) {
      noteRestart(`Restarted from checkpoint at ${(f * 100).toFixed(1)} %${job && job.attempts ? ` (attempt ${Number(job.attempts) + (job.status === 'running' ? 0 : 1)})` : ''}: the progress fell back from ${(lastFraction * 100).toFixed(1)} %.`);
      refreshJob().catch(() => {});
    }
    lastFraction = f;
  }
  function restartEvent(d) {
    if (d && typeof d === 'object') {
      const f = Number(d.fraction ?? (d.progress && d.progress.fraction));
      const k = d.attempt ?? d.attempts;
      if (d.message) noteRestart(String(d.message));
      else if (Number.isFinite(f)) noteRestart(`Restarted from checkpoint at ${(f * 100).toFixed(1)} %${k ? ` (attempt ${k})` : ''}.`);
      else noteRestart(`Restarted${k ? ` (attempt ${k})` : ''}.`);
      if (k && job) job.attempts = Math.max(Number(job.attempts) || 0, Number(k));
    } else if (typeof d === 'string' && d) noteRestart(d);
    if (Number.isFinite(Number(d && d.fraction))) lastFraction = Number(d.fraction);
  }

  function renderProgress() {
    const p = job.progress;
    if (job.status !== 'running' && job.status !== 'queued') { progressHost.replaceChildren(); return; }
    const f = p && Number.isFinite(p.fraction) ? Math.max(0, Math.min(1, p.fraction)) : 0;
    replace(progressHost,
      h('progress', { max: 1000, value: Math.round(f * 1000), 'aria-label': 'Run progress' }),
      h('span', { class: 'muted' }, job.status === 'queued' ? 'queued, waiting for a worker' :
        `${(f * 100).toFixed(1)} % · step ${p ? count(p.step) : '–'} · t = ${p ? si(p.sim_time, 's') : '–'} of ${p ? si(p.end_time, 's') : '–'}`),
      h('span', { class: 'muted', id: 'run-eta' }, etaText(job) ? ` · ${etaText(job)}` : ''));
  }

  function meta(k, v) {
    return [h('dt', {}, k), h('dd', {}, v)];
  }

  async function onCancel(ev) {
    ev.target.disabled = true;
    try {
      await api.cancelJob(id);
      notify('Cancellation requested.');
      await refreshJob();
    } catch (e) {
      notify(`Cancel failed: ${e.message}${e.status === 401 ? ' (set the API token at the top)' : ''}`, 'error');
      ev.target.disabled = false;
    }
  }

  async function onRerun(ev) {
    ev.target.disabled = true;
    try {
      const j = await api.rerunJob(id);
      notify(`Rerun submitted: ${j.id}`);
      location.hash = `#/runs/${encodeURIComponent(j.id)}`;
    } catch (e) {
      notify(`Rerun failed: ${e.message}${e.status === 401 ? ' (set the API token at the top)' : ''}`, 'error');
      ev.target.disabled = false;
    }
  }

  async function onDelete(ev) {
    if (!window.confirm(`Delete run "${job.name || id}" and all its results?`)) return;
    ev.target.disabled = true;
    try {
      // let this page's own reads of the run (pictures, fringe reports, results) finish
      // first: deleted under them they would fail with 404s
      stop();
      // (at most 20 s: a picture whose load never ends must not block the deletion)
      await Promise.race([api.settled(), new Promise((r) => setTimeout(r, 20000))]);
      await api.deleteJob(id);
      notify('Run deleted.');
      location.hash = '#/runs';
    } catch (e) {
      notify(`Delete failed: ${e.message}${e.status === 401 ? ' (set the API token at the top)' : ''}`, 'error');
      ev.target.disabled = false;
    }
  }

  // ---- summary, scene, downloads --------------------------------------------------------
  function renderSummary() {
    const s = job && job.summary;
    const rows = [];
    if (s) {
      rows.push(
        meta('Outcome', h('span', {}, statusBadge(s.status), s.message ? ` ${s.message}` : '')),
        Number(s.dimension) === 3 ? meta('Dimension', h('span', { id: 'summary-dimension' }, '3D')) : null,
        meta('Steps', count(s.steps)),
        meta('Time step', si(s.time_step, 's')),
        meta('Simulated time', si(s.sim_time, 's')),
        meta('Particles', count(s.particles)),
        meta('Grid nodes', `${count(s.grid_nodes)} (active on average ${count(s.active_nodes_mean)})`),
        meta('Wall time', duration(s.wall_seconds)),
        meta('Throughput', `${count(s.particle_steps_per_second)} particle-steps/s on ${s.threads} thread${s.threads === 1 ? '' : 's'}`),
        meta('Solver', s.solver_version || '–'),
        meta('Scene hash', h('span', { class: 'mono break' }, s.scene_hash || '–')));
    }
    if (maxSpeed > 0) {
      const sp = speeds && speeds.speeds;
      rows.push(meta('Peak tip speed', `${num(maxSpeed, 4)} m/s${sp ? ` = ${num(maxSpeed / sp.cS, 3)} c_S = ${num(maxSpeed / sp.cR, 3)} c_R` : ''}`));
    }
    replace(summaryHost, h('h2', { id: 'sum-h' }, 'Summary'),
      rows.length ? h('dl', { class: 'meta' }, rows) : h('p', { class: 'muted' }, 'The summary appears when the run ends.'));
    renderResults();
  }

  /** The "Results" card: one row per tip and the reference checks (absent for older runs). */
  function renderResults() {
    const s = job && job.summary;
    const table = tipTable(s);
    const refs = referenceRows(s);
    resultsHost.hidden = !table && !refs.length;
    if (resultsHost.hidden) { resultsHost.replaceChildren(); return; }
    const win = table && table.speedWindow;
    replace(resultsHost, h('h2', { id: 'results-h' }, 'Results'),
      table ? h('p', { class: 'muted small-text', id: 'results-tips-note' }, 'Per crack tip. Lengths in mm, times in µs, K in MPa·√m.',
        win ? ` Peak speed: the advance along the path over ${num(win * 1e6, 3)} µs (the speed window), divided by it; mean speed: the advance from the last sample at rest to the last advance, over that time.` : '') : null,
      table ? h('div', { class: 'results-host' }, h('table', { class: 'results-table', id: 'results-tips', 'aria-describedby': 'results-tips-note' },
        h('caption', { class: 'visually-hidden' }, 'Results per crack tip'),
        h('thead', {}, h('tr', {}, h('th', { scope: 'col' }, 'Tip'), table.columns.map((c) => h('th', { scope: 'col' }, c.heading, c.unit ? h('span', { class: 'unit' }, ` (${c.unit})`) : '')))),
        h('tbody', {}, table.rows.map((r) => h('tr', { 'data-crack': r.tip.crack, 'data-tip': r.tip.tip },
          h('th', { scope: 'row' }, r.name), r.cells.map((c) => h('td', { class: 'num' }, c))))))) : null,
      refs.length ? h('p', { class: 'muted small-text', id: 'results-references-note' }, 'Against the scene’s reference values (error = (measured − reference) / |reference|; ✓ or ✗ where the scene gives a tolerance).') : null,
      refs.length ? h('div', { class: 'results-host' }, h('table', { class: 'results-table', id: 'results-references', 'aria-describedby': 'results-references-note' },
        h('caption', { class: 'visually-hidden' }, 'Reference values'),
        h('thead', {}, h('tr', {}, ['Quantity', 'Reference', 'Measured', 'Error', 'Tolerance', '', 'Source'].map((t) => h('th', { scope: 'col' }, t)))),
        h('tbody', {}, refs.map((r) => h('tr', { 'data-within': r.within === null ? '' : String(r.within) },
          h('th', { scope: 'row' }, r.quantity, r.where ? h('div', { class: 'muted small-text' }, r.where) : null),
          h('td', { class: 'num' }, r.value), h('td', { class: 'num' }, r.measured), h('td', { class: 'num' }, r.error),
          h('td', { class: 'num' }, r.tolerance || '–'),
          h('td', { class: `check ${r.within === true ? 'ok-mark' : r.within === false ? 'bad-mark' : ''}`, 'aria-label': r.within === true ? 'within the tolerance' : r.within === false ? 'outside the tolerance' : 'no tolerance' }, r.mark),
          h('td', { class: 'small-text' }, r.source)))))) : null);
  }

  // ---- crack path -------------------------------------------------------------------------
  // `path.svg`: x–y of every tip over time over the body outline. Fetched first (a server
  // without the route, or a run without tips, answers 404: the figure stays hidden).
  let pathUrl = null;
  async function loadPath() {
    if (!job || !job.scene || !Array.isArray(job.scene.cracks) || !job.scene.cracks.length) return;
    let res;
    try {
      res = await api.track(fetch(api.pathSvgUrl(id), { headers: { Accept: 'image/svg+xml' } }));
    } catch { return; }
    if (!alive || !res.ok) { pathHost.hidden = true; return; }
    const blob = await res.blob();
    if (!alive) return;
    if (pathUrl) URL.revokeObjectURL(pathUrl);
    pathUrl = URL.createObjectURL(blob);
    replace(pathHost, h('h2', { id: 'path-h' }, 'Crack path'),
      h('figure', { class: 'crack-path' },
        h('img', { id: 'crack-path-img', src: pathUrl, alt: 'Crack path: x–y of every crack tip over time, over the body outline' }),
        h('figcaption', { class: 'muted small-text' }, 'Every tip’s path over the run, on the body’s outline. ',
          h('a', { href: api.pathSvgUrl(id), download: `${job.name || id}-crack-path.svg`, id: 'crack-path-download' }, 'Download SVG'))));
    pathHost.hidden = false;
  }

  function renderScene() {
    const text = prettyJson(job.scene ? orderScene(job.scene) : null);
    replace(sceneHost, h('h2', { id: 'scene-h' }, 'Scene'),
      job.scene && job.scene.description ? h('p', {}, job.scene.description) : null,
      h('details', {}, h('summary', {}, 'Scene JSON'), h('pre', { class: 'json', tabindex: 0 }, text)),
      h('p', {}, h('a', { href: `#/submit?from=${encodeURIComponent(id)}` }, 'Edit a copy as a new run')));
  }

  function renderDownloads() {
    const csv = (kind, file) => h('button', {
      type: 'button', class: 'secondary', onclick: async () => {
        try { saveBlob(await api.historyCsv(id, kind), `${job.name || id}-${file}`); } catch (e) { notify(`Download failed: ${e.message}`, 'error'); }
      },
    }, file);
    const json = (obj, file) => h('button', {
      type: 'button', class: 'secondary', disabled: !obj,
      onclick: () => saveBlob(new Blob([JSON.stringify(obj, null, 2)], { type: 'application/json' }), `${job.name || id}-${file}`),
    }, file);
    replace(downloads, h('h2', { id: 'dl-h' }, 'Downloads'),
      h('div', { class: 'row wrap' },
        csv('crack-tips', 'crack_tips.csv'), csv('energy', 'energy.csv'),
        h('a', { class: 'button secondary', href: api.mcapUrl(id), download: `${job.name || id}-fields.mcap` }, 'fields.mcap'),
        h('a', { class: 'button secondary', id: 'dl-vtk', href: api.vtkUrl(id), download: `${id}-vtk.zip` }, 'ParaView (VTK)'),
        json(job.scene, 'scene.json'), json(job.summary, 'summary.json')),
      h('p', { class: 'muted small-text' }, 'fields.mcap opens in Foxglove; while the run is going it holds what has been written so far. ParaView (VTK) is a zip of the field snapshots as a VTK series: open its fields.pvd (and cracks.pvd) in ParaView.'));
  }

  // ---- snapshots ------------------------------------------------------------------------
  const compSel = h('select', { id: 'snap-component' });
  // A 3D run's snapshots are slices: one picture per plane per snapshot time. The slider
  // runs over the times of the chosen plane.
  const sliceSel = h('select', { id: 'snap-slice' });
  const sliceField = h('div', { class: 'field', hidden: true }, h('label', { for: 'snap-slice' }, 'Slice'), sliceSel);
  const sliceCaption = h('figcaption', { id: 'snap-slice-label', class: 'muted small-text', hidden: true });
  /** The snapshots the slider runs over: those of the chosen slice (all of a 2D run). */
  const frames = () => snapshots.filter((s) => sliceKey(s) === sliceSel.value);
  const slider = h('input', { id: 'snap-slider', type: 'range', min: 0, max: 0, step: 1, value: 0 });
  const timeOut = h('output', { for: 'snap-slider', class: 'mono' }, '–');
  const playBtn = h('button', { type: 'button', id: 'snap-play', 'aria-pressed': 'false' }, '▶ Play');
  const ppcSel = h('select', { id: 'snap-ppc', title: 'Pixels per grid cell of the picture' },
    h('option', { value: '' }, 'auto'), [4, 8, 16].map((n) => h('option', { value: String(n) }, `${n} px per cell`)));
  const snapNote = h('p', { id: 'snap-note', class: 'muted small-text', hidden: true });
  const reports = new Map(); // report URL → promise of the render report
  // colour range, remembered per component while on the page
  const ranges = new Map(); // component → {mode, abs, lo, hi} (input texts)
  const rangeMode = h('select', { id: 'snap-range-mode', title: 'Colour range of the picture' },
    h('option', { value: 'auto' }, 'auto'), h('option', { value: 'symmetric' }, 'symmetric ±'), h('option', { value: 'manual' }, 'min – max'));
  const rangeAbs = h('input', { id: 'snap-range-abs', type: 'text', inputmode: 'decimal', size: 9, placeholder: 'e.g. 2e6', 'aria-label': 'Colour range: ± this value', autocomplete: 'off' });
  const rangeLo = h('input', { id: 'snap-range-min', type: 'text', inputmode: 'decimal', size: 9, placeholder: 'min', 'aria-label': 'Colour range minimum', autocomplete: 'off' });
  const rangeHi = h('input', { id: 'snap-range-max', type: 'text', inputmode: 'decimal', size: 9, placeholder: 'max', 'aria-label': 'Colour range maximum', autocomplete: 'off' });
  const rangeUnit = h('span', { class: 'muted small-text', id: 'snap-range-unit' });
  const rangeMsg = h('span', { class: 'error small-text', id: 'snap-range-msg', role: 'alert' });
  const rangeField = h('div', { class: 'field snap-range' }, h('label', { for: 'snap-range-mode' }, 'Colour range'),
    h('div', { class: 'row' }, rangeMode, h('span', { class: 'range-sym' }, '±', rangeAbs), h('span', { class: 'range-man' }, rangeLo, '–', rangeHi), rangeUnit), rangeMsg);
  const currentComponent = () => {
    const f = frames();
    const s = f[Math.min(Number(slider.value), f.length - 1)];
    const c = compSel.value;
    return s && !snapshotComponents(s).includes(c) ? snapshotComponents(s)[0] : c;
  };
  const rangeOf = (comp) => ranges.get(comp) || { mode: 'auto', abs: '', lo: '', hi: '' };
  /** Show the range inputs of the current component (its remembered setting). */
  function syncRangeInputs() {
    const comp = currentComponent();
    const applies = rangeApplies(comp);
    rangeField.hidden = !applies;
    const r = rangeOf(comp);
    rangeMode.value = r.mode;
    rangeAbs.value = r.abs;
    rangeLo.value = r.lo;
    rangeHi.value = r.hi;
    rangeField.dataset.mode = r.mode;
    const u = COMPONENT_UNITS[comp];
    rangeUnit.textContent = r.mode === 'auto' ? '' : (u ? u : '(no unit)');
    rangeMsg.textContent = rangeProblem(r) && (r.abs || r.lo || r.hi) ? rangeProblem(r) : '';
  }
  function onRangeInput() {
    const comp = currentComponent();
    if (!comp) return;
    ranges.set(comp, { mode: rangeMode.value, abs: rangeAbs.value, lo: rangeLo.value, hi: rangeHi.value });
    syncRangeInputs();
    showSnapshot();
  }
  rangeMode.addEventListener('change', () => {
    onRangeInput();
    const first = rangeMode.value === 'symmetric' ? rangeAbs : rangeMode.value === 'manual' ? rangeLo : null;
    if (first) first.focus();
  });
  for (const el of [rangeAbs, rangeLo, rangeHi]) {
    el.addEventListener('change', onRangeInput);
    el.addEventListener('keydown', (ev) => { if (ev.key === 'Enter') { ev.preventDefault(); onRangeInput(); } });
  }
  const pictureOpts = (comp = currentComponent()) => ({ px_per_cell: ppcSel.value, range: rangeApplies(comp) ? rangeParam(rangeOf(comp)) : '' });
  const img = h('img', { id: 'snap-image', class: 'snap-image', alt: '', hidden: true });
  const snapEmpty = h('p', { class: 'muted' }, 'No field snapshots yet.');
  const snapTitle = h('h2', { id: 'snap-h' }, 'Field snapshots');
  let following = true; // slider follows the newest snapshot while live
  replace(snapHost, snapTitle,
    h('div', { class: 'snap-controls' },
      sliceField,
      h('div', { class: 'field' }, h('label', { for: 'snap-component' }, 'Field'), compSel),
      h('div', { class: 'field grow' }, h('label', { for: 'snap-slider' }, 'Time ', timeOut), slider),
      h('div', { class: 'field' }, h('label', { for: 'snap-ppc' }, 'Resolution'), ppcSel),
      rangeField,
      playBtn),
    h('figure', { class: 'snap' }, img, sliceCaption, snapEmpty), snapNote);
  compSel.addEventListener('change', () => { syncRangeInputs(); showSnapshot(); });
  sliceSel.addEventListener('change', () => {
    // stay at the same time on the other plane
    const shown = img.dataset.time === undefined ? NaN : Number(img.dataset.time);
    const f = frames();
    let best = f.length - 1;
    if (Number.isFinite(shown)) f.forEach((s, i) => { if (Math.abs(s.time - shown) < Math.abs(f[best].time - shown)) best = i; });
    slider.max = String(Math.max(0, f.length - 1));
    slider.value = String(Math.max(0, best));
    following = best === f.length - 1;
    stop();
    showSnapshot();
  });
  ppcSel.addEventListener('change', showSnapshot);
  slider.addEventListener('input', () => { following = Number(slider.value) === frames().length - 1; stop(); showSnapshot(); });
  playBtn.addEventListener('click', () => (playTimer ? stop() : play()));

  function addSnapshots(list) {
    let added = false;
    for (const s of list) {
      if (!s || s.index === undefined || snapshots.some((x) => x.index === s.index)) continue;
      snapshots.push(s);
      added = true;
    }
    if (!added) return;
    snapshots.sort((a, b) => a.index - b.index);
    // the planes of a 3D run, in the order the run writes them
    const planes = [];
    for (const s of snapshots) if (sliceKey(s) && !planes.some((p) => p.key === sliceKey(s))) planes.push({ key: sliceKey(s), snap: s });
    if (planes.length && sliceSel.options.length !== planes.length) {
      const was = sliceSel.value;
      replace(sliceSel, planes.map((p) => h('option', { value: p.key }, sliceLabel(p.snap).replace(/^slice /, ''))));
      sliceSel.value = planes.some((p) => p.key === was) ? was : planes[0].key;
      sliceField.hidden = false;
      snapTitle.textContent = 'Field slices';
    }
    const comps = new Set();
    for (const s of snapshots) for (const c of snapshotComponents(s)) comps.add(c);
    const cur = compSel.value;
    const ordered = [...comps].sort((a, b) => ((COMPONENT_ORDER.indexOf(a) + 99) % 99) - ((COMPONENT_ORDER.indexOf(b) + 99) % 99));
    if (compSel.options.length !== ordered.length) {
      replace(compSel, ordered.map((c) => h('option', { value: c }, COMPONENT_NAMES[c] || c)));
      compSel.value = ordered.includes(cur) ? cur : ordered[0];
    }
    slider.max = String(Math.max(0, frames().length - 1));
    if (following) slider.value = String(Math.max(0, frames().length - 1));
    showSnapshot();
  }

  function showSnapshot() {
    const f = frames();
    if (!f.length) return;
    const s = f[Math.min(Number(slider.value), f.length - 1)];
    let comp = compSel.value;
    if (!snapshotComponents(s).includes(comp)) comp = snapshotComponents(s)[0];
    if (!comp) return;
    const url = api.snapshotUrl(id, s.index, comp, pictureOpts(comp));
    if (rangeField.hidden === rangeApplies(comp)) syncRangeInputs();
    img.dataset.range = pictureOpts(comp).range;
    showReport(s, comp);
    timeOut.textContent = `${si(s.time, 's')} (${Number(slider.value) + 1}/${f.length})`;
    slider.setAttribute('aria-valuetext', `t = ${si(s.time, 's')}, snapshot ${Number(slider.value) + 1} of ${f.length}`);
    const plane = sliceLabel(s);
    sliceCaption.textContent = plane;
    sliceCaption.hidden = !plane;
    img.dataset.time = String(s.time);
    img.dataset.slice = sliceKey(s);
    if (img.dataset.src !== url) {
      img.dataset.src = url;
      img.src = url;
      trackPicture(img);
    }
    img.alt = plane
      ? `${COMPONENT_NAMES[comp] || comp} at t = ${si(s.time, 's')} on the ${plane}, with its colour scale`
      : `${COMPONENT_NAMES[comp] || comp} at t = ${si(s.time, 's')}, with its colour scale and the crack path`;
    img.hidden = false;
    snapEmpty.hidden = true;
  }

  /** Under a fringe picture: whether every fringe is resolved (the server's render report). */
  function showReport(s, comp) {
    if (comp !== 'fringe') { snapNote.hidden = true; delete snapNote.dataset.aliased; return; }
    const url = api.snapshotUrl(id, s.index, comp, pictureOpts(), 'json');
    if (!reports.has(url)) reports.set(url, api.request('GET', url.slice(api.BASE.length)).catch(() => null));
    snapNote.dataset.for = url;
    reports.get(url).then((r) => {
      if (!alive || snapNote.dataset.for !== url || !r) return;
      snapNote.dataset.aliased = String(!!r.aliased);
      const box = r.aliased_box ? ` around x ${num(r.aliased_box[0] * 1e3, 3)}–${num(r.aliased_box[2] * 1e3, 3)} mm, y ${num(r.aliased_box[1] * 1e3, 3)}–${num(r.aliased_box[3] * 1e3, 3)} mm` : '';
      snapNote.textContent = r.aliased
        ? `Some fringes are finer than a pixel at ${num(r.px_per_cell, 3)} px per cell (up to ${num(r.max_fringes_per_pixel, 3)} fringes per pixel${box}): they are not resolved; a higher resolution resolves more of them.`
        : `Every fringe is resolved at ${num(r.px_per_cell, 3)} px per cell (at most ${num(r.max_fringes_per_pixel, 3)} fringes per pixel).`;
      snapNote.hidden = false;
    });
  }

  function play() {
    const f = frames();
    if (f.length < 2) return;
    if (Number(slider.value) >= f.length - 1) slider.value = '0';
    playBtn.textContent = '❚❚ Pause';
    playBtn.setAttribute('aria-pressed', 'true');
    following = false;
    const step = () => {
      const i = Number(slider.value) + 1;
      if (i >= f.length) { stop(); following = true; return; }
      // advance once the current image is there, so playback never shows a blank frame
      const next = new Image();
      next.onload = next.onerror = () => {
        if (!playTimer) return;
        slider.value = String(i);
        showSnapshot();
        playTimer = setTimeout(step, 500);
      };
      trackPicture(next);
      const c = snapshotComponents(f[i]).includes(compSel.value) ? compSel.value : snapshotComponents(f[i])[0];
      next.src = api.snapshotUrl(id, f[i].index, c, pictureOpts(c));
    };
    playTimer = setTimeout(step, 300);
  }

  function stop() {
    clearTimeout(playTimer);
    playTimer = 0;
    playBtn.textContent = '▶ Play';
    playBtn.setAttribute('aria-pressed', 'false');
  }

  async function loadSnapshots() {
    try {
      const list = await api.listSnapshots(id);
      if (alive) addSnapshots(rowsOfSnapshots(list));
    } catch (e) {
      if (!(e instanceof api.ApiError && e.status === 404)) throw e;
    }
  }

  // ---- live updates ---------------------------------------------------------------------
  function setStatus(status, extra = {}) {
    if (!status || !job) return;
    const changed = job.status !== status;
    Object.assign(job, extra, { status });
    if (changed) renderHeader();
    if (TERMINAL.has(status)) finish();
  }

  /**
   * A run that did not complete has no data past its last sample: end the time axis there
   * (instead of at the scene's end time) so its curves fill the plots.
   */
  function fitTimeAxis() {
    if (!job || !TERMINAL.has(job.status) || job.status === 'completed') return;
    let last = Math.max(lastEnergy, ...lastTip.values());
    const reached = job.summary ? Number(job.summary.sim_time) : job.progress ? Number(job.progress.sim_time) : NaN;
    if (!(last > 0) && reached > 0) last = reached;
    if (!(last > 0)) return;
    const tu = timeUnit(last);
    for (const p of plots) { p.setXUnit(tu); p.setXDomain(0, last); }
    plotGrid.dataset.timeEnd = String(last);
  }

  let finishing = false;
  async function finish() {
    if (finishing) return;
    finishing = true;
    if (closeEvents) { closeEvents(); closeEvents = null; }
    clearInterval(pollTimer);
    // the final state: summary, the last rows, the last snapshots
    try {
      await refreshJob();
      await Promise.all([fillHistories(), loadSnapshots(), loadPath()]);
      if (alive) fitTimeAxis();
    } catch (e) {
      if (alive) notify(`Could not load the final results: ${e.message}`, 'error');
    }
  }

  async function refreshJob() {
    const j = await api.getJob(id);
    if (!alive) return;
    if (j.progress && j.status === 'running') watchFraction(j.progress);
    job = j;
    renderHeader();
    renderSummary();
    renderDownloads();
    if (TERMINAL.has(job.status) && !finishing) finish();
  }

  // Events that arrive before the first history load has answered wait here, so that the
  // loaded rows and the streamed ones join without a gap or a skipped row.
  let ready = false;
  const pending = [];
  const whenReady = (fn) => (d) => { if (ready) fn(d); else pending.push(() => fn(d)); };

  function connect() {
    let hadError = false;
    closeEvents = api.subscribe(id, {
      progress: (d) => {
        const p = d && d.progress ? d.progress : d;
        if (!p || typeof p !== 'object' || !job) return;
        watchFraction(p);
        job.progress = p;
        if (job.status === 'queued') setStatus('running');
        renderProgress();
      },
      crack_tip: whenReady((d) => { if (addTipRows(rowsOf(d))) renderSummary(); }),
      energy: whenReady((d) => addEnergyRows(rowsOf(d))),
      snapshot: whenReady((d) => addSnapshots(rowsOfSnapshots(d))),
      status: (d) => {
        const st = typeof d === 'string' ? d : d && (d.status || (d.job && d.job.status));
        setStatus(st, d && typeof d === 'object' && d.message ? { message: d.message } : {});
      },
      restart: restartEvent,
      restarted: restartEvent,
      message: (d) => { if (d && (typeof d === 'string' || d.message)) noteRestart(typeof d === 'string' ? d : String(d.message)); },
      onopen: () => { if (hadError) { hadError = false; fillHistories().catch(() => {}); } },
      onerror: () => { hadError = true; },
    });
  }

  // ---- start ----------------------------------------------------------------------------
  (async () => {
    try {
      job = await api.getJob(id);
    } catch (e) {
      if (!alive) return;
      replace(main, h('p', { class: 'crumbs' }, h('a', { href: '#/runs' }, '← Runs')),
        h('h1', {}, 'Run not found'),
        h('p', { class: 'error' }, e.status === 404 ? `There is no run with id ${id}.` : `Could not load the run: ${e.message}`));
      return;
    }
    if (!alive) return;
    speeds = sceneWaveSpeeds(job.scene);
    for (const p of plots) p.setFileStem(job.name || id);
    if (job.progress) lastFraction = Number(job.progress.fraction);
    const end = (job.scene && job.scene.time && job.scene.time.end) || (job.progress && job.progress.end_time) || 1e-4;
    const tu = timeUnit(end);
    for (const p of plots) { p.setXUnit(tu); p.setXDomain(0, end); }
    plotGrid.dataset.timeEnd = String(end);
    speedPlot.setRefLines(speedRefLines(speeds && speeds.speeds));
    renderHeader();
    renderSummary();
    renderScene();
    renderDownloads();
    if (!TERMINAL.has(job.status)) {
      connect();
      // a slow safety net in case the event stream is interrupted: keeps the header right
      pollTimer = setInterval(() => { if (!finishing) refreshJob().then(() => fillHistories()).catch(() => {}); }, 5000);
    }
    try {
      await Promise.all([fillHistories(), loadSnapshots()]);
    } catch (e) {
      if (alive) notify(`Could not load the results: ${e.message}`, 'error');
    }
    ready = true;
    for (const f of pending.splice(0)) f();
    if (TERMINAL.has(job.status)) { finishing = true; fitTimeAxis(); loadPath(); }
  })();

  return () => {
    alive = false;
    stop();
    clearInterval(pollTimer);
    if (closeEvents) closeEvents();
    if (pathUrl) URL.revokeObjectURL(pathUrl);
    for (const p of plots) p.destroy();
    document.title = 'mpm-fracture';
  };
}

function rowsOfSnapshots(d) {
  if (!d) return [];
  if (Array.isArray(d)) return d;
  if (Array.isArray(d.snapshots)) return d.snapshots;
  return typeof d === 'object' && 'index' in d ? [d] : [];
}
