// Sweeps: the list (#/sweeps) and one sweep (#/sweeps/{id}): its parameters, its jobs with
// their status and progress, and their crack-tip speed curves overlaid (one colour per
// run, legend with the parameter labels, reference speeds c_R, c_S, √2·c_S, c_L), live
// while jobs run (polling the sweep and each job's crack tips with ?since=).

import * as api from '../api.js';
import { Plot, PALETTE, DASHES } from '../plot.js';
import { sceneWaveSpeeds, speedRefLines } from '../waves.js';
import { h, replace, timeEl, statusBadge, num, notify, timeUnit } from '../util.js';
import { progressBar } from './runs.js';
import { TipHistory, countsText, isActive, parameterText, seriesName } from '../sweep.js';

const PAGE = 20;

function sweepProgress(s) {
  const pct = Math.round(Math.max(0, Math.min(1, Number(s.progress) || 0)) * 100);
  return h('div', { class: 'progress-cell' },
    h('progress', { max: 100, value: pct, 'aria-label': `${s.name || s.id} progress` }),
    h('span', { class: 'pct' }, `${pct} %`));
}

/** #/sweeps: sweeps, newest first, with counts and progress; cursor paging. */
export function sweepsView(main) {
  let alive = true;
  let timer = 0;
  const cursors = [];
  let cursor = null;
  const tableHost = h('div', { class: 'table-host', 'aria-live': 'polite' });
  const prevBtn = h('button', { type: 'button', class: 'secondary', disabled: true, onclick: () => { cursor = cursors.pop() ?? null; load(); } }, '← Newer');
  const nextBtn = h('button', { type: 'button', class: 'secondary', disabled: true, onclick: () => { cursors.push(cursor); cursor = nextBtn.dataset.cursor || null; load(); } }, 'Older →');
  replace(main,
    h('div', { class: 'page-head' }, h('h1', {}, 'Sweeps')),
    h('p', { class: 'muted' }, 'A sweep runs one scene for every combination of parameter values (',
      h('code', {}, 'POST /api/v1/sweeps'), ' or ', h('code', {}, 'fracture sweep scene.json --param path=v1,v2'), '). ',
      h('a', { href: '#/submit?sweep=1', id: 'new-sweep-link' }, 'Start a sweep'), ' from the scene editor or an example.'),
    tableHost,
    h('nav', { class: 'pager', 'aria-label': 'Pages' }, prevBtn, nextBtn));

  async function load(quiet = false) {
    clearTimeout(timer);
    try {
      const q = new URLSearchParams({ limit: String(PAGE) });
      if (cursor) q.set('cursor', cursor);
      const res = await api.request('GET', `/sweeps?${q}`, { raw: true });
      const list = await res.json();
      if (!alive) return;
      const next = res.headers.get('X-Next-Cursor');
      nextBtn.disabled = !next;
      nextBtn.dataset.cursor = next || '';
      prevBtn.disabled = !cursor;
      render(list);
      if (list.some(isActive)) timer = setTimeout(() => load(true), 2000);
    } catch (e) {
      if (!alive) return;
      if (!quiet) replace(tableHost, h('p', { class: 'error' }, `Could not load the sweeps: ${e.message}`));
      timer = setTimeout(() => load(true), 5000);
    }
  }

  function render(list) {
    if (!list.length) {
      replace(tableHost, h('p', { class: 'empty-state' }, 'No sweeps yet.'));
      return;
    }
    replace(tableHost, h('table', { class: 'runs sweeps' },
      h('caption', { class: 'visually-hidden' }, 'Sweeps, newest first'),
      h('thead', {}, h('tr', {}, ['Status', 'Name', 'Parameters', 'Jobs', 'Created', 'Progress'].map((t) => h('th', { scope: 'col' }, t)))),
      h('tbody', {}, list.map((s) => h('tr', { 'data-id': s.id, 'data-status': s.status },
        h('td', { 'data-label': 'Status' }, statusBadge(s.status)),
        h('td', { 'data-label': 'Name' }, h('a', { href: `#/sweeps/${encodeURIComponent(s.id)}`, class: 'sweep-link' }, s.name || s.id), h('div', { class: 'muted mono small-text' }, s.id)),
        h('td', { 'data-label': 'Parameters' }, parameterText(s.parameters).map((t) => h('div', { class: 'mono small-text' }, t))),
        h('td', { 'data-label': 'Jobs' }, countsText(s)),
        h('td', { 'data-label': 'Created' }, timeEl(s.created_at)),
        h('td', { 'data-label': 'Progress' }, sweepProgress(s)))))));
  }

  load();
  return () => { alive = false; clearTimeout(timer); };
}

/** #/sweeps/{id}: one sweep with its jobs and the overlaid crack-tip speed curves. */
export function sweepView(main, { id }) {
  let alive = true;
  let timer = 0;
  let sweep = null;
  const hist = new Map(); // job id → TipHistory
  let refsSet = false;

  const titleEl = h('h1', {}, 'Sweep');
  const badgeHost = h('span', { class: 'badge-host' });
  const actions = h('div', { class: 'actions' });
  const metaHost = h('dl', { class: 'meta' });
  const jobsHost = h('div', { class: 'table-host', 'aria-live': 'polite' });
  const plotGrid = h('div', { class: 'plot-grid' });
  replace(main,
    h('p', { class: 'crumbs' }, h('a', { href: '#/sweeps' }, '← Sweeps')),
    h('div', { class: 'page-head' }, h('div', { class: 'title-row' }, titleEl, badgeHost), actions),
    metaHost,
    h('section', { 'aria-labelledby': 'sweep-plot-h' }, h('h2', { id: 'sweep-plot-h' }, 'Crack-tip speed of every run'), plotGrid),
    h('section', { 'aria-labelledby': 'sweep-jobs-h' }, h('h2', { id: 'sweep-jobs-h' }, 'Runs'), jobsHost));
  const speedPlot = new Plot(plotGrid, {
    id: 'sweep-speed', title: 'Crack-tip speed', yLabel: 'speed', yUnit: 'm/s', yPrefix: false, yZero: true, filter: 2,
    xUnit: { factor: 1e-6, unit: 'µs' }, empty: 'No crack-tip data yet',
  });
  const lengthPlot = new Plot(plotGrid, {
    id: 'sweep-length', title: 'Crack length', yLabel: 'crack length', yUnit: 'm',
    xUnit: { factor: 1e-6, unit: 'µs' }, empty: 'No crack-tip data yet',
  });
  const plots = [speedPlot, lengthPlot];

  async function onCancel() {
    try {
      sweep = await api.request('POST', `/sweeps/${encodeURIComponent(id)}/cancel`);
      notify('Cancellation requested for the sweep’s unfinished runs.');
      render();
      load();
    } catch (e) {
      notify(`Could not cancel: ${e.message}`, 'error');
    }
  }

  function render() {
    titleEl.textContent = sweep.name || sweep.id;
    for (const p of [speedPlot, lengthPlot]) p.setFileStem(`sweep ${sweep.name || sweep.id}`);
    document.title = `${sweep.name || sweep.id} · sweep · mpm-fracture`;
    replace(badgeHost, statusBadge(sweep.status));
    const jobs = sweep.jobs || [];
    replace(actions,
      isActive(sweep) ? h('button', { type: 'button', class: 'danger', id: 'cancel-sweep', onclick: onCancel }, 'Cancel sweep') : null,
      jobs.length ? h('a', { class: 'button secondary', href: `#/compare?ids=${jobs.map((j) => encodeURIComponent(j.id)).join(',')}` }, 'Compare runs…') : null);
    const sp = sceneWaveSpeeds(sweep.scene);
    replace(metaHost,
      h('dt', {}, 'Id'), h('dd', {}, h('span', { class: 'mono' }, sweep.id)),
      h('dt', {}, 'Parameters'), h('dd', {}, parameterText(sweep.parameters).map((t) => h('div', { class: 'mono' }, t))),
      h('dt', {}, 'Jobs'), h('dd', { id: 'sweep-counts' }, countsText(sweep)),
      h('dt', {}, 'Progress'), h('dd', {}, sweepProgress(sweep)),
      h('dt', {}, 'Created'), h('dd', {}, timeEl(sweep.created_at)),
      sp ? [h('dt', {}, 'Wave speeds'), h('dd', {}, `${sp.name}: c_L ${num(sp.speeds.cL, 4)}, c_S ${num(sp.speeds.cS, 4)}, c_R ${num(sp.speeds.cR, 4)}, √2·c_S ${num(sp.speeds.sqrt2cS, 4)} m/s`)] : null);
    if (sp && !refsSet) { speedPlot.setRefLines(speedRefLines(sp.speeds)); refsSet = true; }
    const end = sweep.scene && sweep.scene.time && Number(sweep.scene.time.end);
    if (end > 0) for (const p of plots) { p.setXUnit(timeUnit(end)); p.setXDomain(0, end); }
    replace(jobsHost, h('table', { class: 'runs sweep-jobs' },
      h('caption', { class: 'visually-hidden' }, 'Runs of the sweep'),
      h('thead', {}, h('tr', {}, ['', 'Parameters', 'Status', 'Run', 'Peak tip speed', 'Progress'].map((t, i) => h('th', { scope: 'col' }, i === 0 ? h('span', { class: 'visually-hidden' }, 'Colour') : t)))),
      h('tbody', {}, jobs.map((j, i) => {
        const th = hist.get(j.id);
        const peak = th && th.maxSpeed > 0 ? `${num(th.maxSpeed, 4)} m/s${sp ? ` = ${num(th.maxSpeed / sp.speeds.cS, 3)} c_S` : ''}` : '–';
        return h('tr', { 'data-id': j.id, 'data-status': j.status },
          h('td', { 'data-label': 'Colour' }, h('span', { class: 'swatch-dot', style: `background:${PALETTE[i % PALETTE.length]}`, 'aria-hidden': 'true' })),
          h('td', { 'data-label': 'Parameters', class: 'mono' }, j.label),
          h('td', { 'data-label': 'Status' }, statusBadge(j.status)),
          h('td', { 'data-label': 'Run' }, h('a', { href: `#/runs/${encodeURIComponent(j.id)}`, class: 'run-link' }, j.name || j.id)),
          h('td', { 'data-label': 'Peak tip speed', class: 'num' }, peak),
          h('td', { 'data-label': 'Progress' }, j.status === 'running' || j.status === 'queued' ? progressBar(j) : j.status === 'completed' ? '100 %' : (j.message || '–')));
      }))));
  }

  function plotJob(j, i) {
    const th = hist.get(j.id);
    if (!th) return;
    const color = PALETTE[i % PALETTE.length];
    let k = 0;
    for (const [key, s] of th.tips) {
      const style = {
        name: seriesName(j.label || j.name || j.id, s, th.tips.size, th.multiCrack),
        color, dash: th.tips.size > 1 ? DASHES[k % DASHES.length] : '',
      };
      speedPlot.setData(`${j.id}/${key}`, s.t.slice(), s.v.slice(), style);
      lengthPlot.setData(`${j.id}/${key}`, s.t.slice(), s.l.slice(), style);
      k++;
    }
  }

  async function load() {
    clearTimeout(timer);
    try {
      sweep = await api.request('GET', `/sweeps/${encodeURIComponent(id)}`);
      if (!alive) return;
      const jobs = sweep.jobs || [];
      // crack tips of every job that has started, only the rows after what we have
      await Promise.all(jobs.map(async (j, i) => {
        if (j.status === 'queued') return;
        let th = hist.get(j.id);
        if (!th) { th = new TipHistory(); hist.set(j.id, th); }
        try {
          const rows = await api.history(j.id, 'crack-tips', th.since());
          if (!alive) return;
          if (th.add(Array.isArray(rows) ? rows : []) > 0) plotJob(j, i);
        } catch (e) {
          if (!(e instanceof api.ApiError && e.status === 404)) throw e;
        }
      }));
      if (!alive) return;
      // Rows arrive job by job in any order: keep the legend in the table's order.
      const rank = new Map();
      jobs.forEach((j, i) => {
        const th = hist.get(j.id);
        let k = 0;
        if (th) for (const key of th.tips.keys()) rank.set(`${j.id}/${key}`, i * 1000 + k++);
      });
      for (const p of plots) p.orderBy((key) => rank.get(key) ?? Number.MAX_SAFE_INTEGER);
      render();
      if (isActive(sweep)) timer = setTimeout(load, 2000);
    } catch (e) {
      if (!alive) return;
      if (!sweep) {
        replace(main, h('p', { class: 'crumbs' }, h('a', { href: '#/sweeps' }, '← Sweeps')),
          h('p', { class: 'error' }, e instanceof api.ApiError && e.status === 404 ? `No sweep with id ${id}.` : `Could not load the sweep: ${e.message}`));
        return;
      }
      timer = setTimeout(load, 5000);
    }
  }

  load();
  return () => { alive = false; clearTimeout(timer); for (const p of plots) p.destroy(); };
}
