// Runs list: status, name, labels, times, wall time, particle-steps/s, live progress;
// filters by status and label (kept in the URL), cursor paging, selection for compare.

import { listJobs, ApiError } from '../api.js';
import { h, replace, timeEl, duration, count, statusBadge, hashQuery, etaText, cacheNote } from '../util.js';

const STATUSES = ['queued', 'running', 'completed', 'failed', 'cancelled'];
const PAGE = 20;

/** Wall time of a job: the summary's, else finished/now − started. */
export function wallTime(job) {
  if (job.summary && Number.isFinite(job.summary.wall_seconds)) return job.summary.wall_seconds;
  if (!job.started_at) return null;
  const end = job.finished_at ? Date.parse(job.finished_at) : Date.now();
  return Math.max(0, (end - Date.parse(job.started_at)) / 1000);
}

export function progressBar(job) {
  const f = job.progress && Number.isFinite(job.progress.fraction) ? job.progress.fraction : 0;
  const pct = Math.round(Math.max(0, Math.min(1, f)) * 100);
  const eta = etaText(job);
  return h('div', { class: 'progress-cell' },
    h('progress', { max: 100, value: pct, 'aria-label': `${job.name || job.id} progress` }),
    h('span', { class: 'pct' }, `${pct} %`),
    eta ? h('span', { class: 'eta muted small-text' }, eta) : null);
}

export function labelChips(labels, onPick) {
  const entries = Object.entries(labels || {});
  if (!entries.length) return h('span', { class: 'muted' }, '–');
  return h('span', { class: 'chips' }, entries.map(([k, v]) => onPick
    ? h('button', { type: 'button', class: 'chip', title: `Show runs labelled ${k}:${v}`, onclick: () => onPick(`${k}:${v}`) }, `${k}: ${v}`)
    : h('span', { class: 'chip' }, `${k}: ${v}`)));
}

export function runsView(main) {
  const selected = new Set();
  let cursors = []; // cursors of the pages before this one, for "Newer"
  let timer = 0;
  let alive = true;

  const statusSel = h('select', { id: 'f-status', name: 'status' },
    h('option', { value: '' }, 'any'), STATUSES.map((s) => h('option', { value: s }, s)));
  const labelIn = h('input', { id: 'f-label', name: 'label', type: 'text', placeholder: 'key:value', autocomplete: 'off', spellcheck: false });
  const filters = h('form', { class: 'filters', role: 'search', 'aria-label': 'Filter runs', onsubmit: (ev) => { ev.preventDefault(); go(); } },
    h('div', { class: 'field' }, h('label', { for: 'f-status' }, 'Status'), statusSel),
    h('div', { class: 'field' }, h('label', { for: 'f-label' }, 'Label'), labelIn),
    h('button', { type: 'submit' }, 'Filter'),
    h('button', { type: 'button', class: 'secondary', onclick: () => { statusSel.value = ''; labelIn.value = ''; go(); } }, 'Clear'));
  statusSel.addEventListener('change', () => go());

  const compareBtn = h('button', { type: 'button', disabled: true, onclick: () => { location.hash = `#/compare?ids=${[...selected].map(encodeURIComponent).join(',')}`; } }, 'Compare selected');
  const tableHost = h('div', { class: 'table-host', 'aria-live': 'polite', 'aria-busy': 'true' });
  const prevBtn = h('button', { type: 'button', class: 'secondary', disabled: true, onclick: () => page(-1) }, '← Newer');
  const nextBtn = h('button', { type: 'button', class: 'secondary', disabled: true, onclick: () => page(1) }, 'Older →');
  const pageInfo = h('span', { class: 'muted' });

  replace(main,
    h('div', { class: 'page-head' }, h('h1', {}, 'Runs'), h('div', { class: 'actions' }, compareBtn, h('a', { class: 'button', href: '#/submit' }, 'New run'))),
    filters, tableHost,
    h('nav', { class: 'pager', 'aria-label': 'Pages' }, prevBtn, pageInfo, nextBtn));

  function readQuery() {
    const q = hashQuery();
    statusSel.value = q.get('status') || '';
    labelIn.value = q.get('label') || '';
    return q;
  }

  function go(cursor = null, keepHistory = false) {
    const q = new URLSearchParams();
    if (statusSel.value) q.set('status', statusSel.value);
    if (labelIn.value.trim()) q.set('label', labelIn.value.trim());
    if (cursor) q.set('cursor', cursor);
    if (!keepHistory) cursors = [];
    const s = q.toString();
    const target = `#/runs${s ? `?${s}` : ''}`;
    if (location.hash === target) load(); else location.hash = target;
  }

  function page(dir) {
    if (dir > 0) {
      if (!nextBtn.dataset.cursor) return;
      cursors.push(hashQuery().get('cursor'));
      go(nextBtn.dataset.cursor, true);
    } else {
      go(cursors.pop() ?? null, true);
    }
  }

  async function load(quiet = false) {
    clearTimeout(timer);
    const q = readQuery();
    const cursor = q.get('cursor');
    if (!quiet) tableHost.setAttribute('aria-busy', 'true');
    try {
      const { jobs, next } = await listJobs({ status: q.get('status') || '', label: q.get('label') || '', limit: PAGE, cursor });
      if (!alive) return;
      renderTable(jobs);
      nextBtn.disabled = !next;
      nextBtn.dataset.cursor = next || '';
      prevBtn.disabled = !cursor;
      pageInfo.textContent = jobs.length ? `${jobs.length} run${jobs.length === 1 ? '' : 's'} on this page` : '';
      // live: refresh while something is queued or running
      if (jobs.some((j) => j.status === 'running' || j.status === 'queued')) timer = setTimeout(() => load(true), 2000);
    } catch (e) {
      if (!alive) return;
      replace(tableHost, h('p', { class: 'error' }, e instanceof ApiError ? `Could not load the runs: ${e.message}` : String(e)));
      timer = setTimeout(() => load(true), 5000);
    } finally {
      tableHost.setAttribute('aria-busy', 'false');
    }
  }

  function renderTable(jobs) {
    if (!jobs.length) {
      replace(tableHost, h('p', { class: 'empty-state' }, 'No runs match. ', h('a', { href: '#/submit' }, 'Start a new run'), '.'));
      return;
    }
    const pick = (label) => { labelIn.value = label; go(); };
    const rows = jobs.map((j) => {
      const box = h('input', {
        type: 'checkbox', checked: selected.has(j.id), 'aria-label': `Select ${j.name || j.id} for comparison`,
        onchange: (ev) => { if (ev.target.checked) selected.add(j.id); else selected.delete(j.id); updateCompare(); },
      });
      const pss = j.summary && j.summary.particle_steps_per_second;
      const cached = cacheNote(j);
      return h('tr', { 'data-id': j.id, 'data-status': j.status },
        h('td', { class: 'sel', 'data-label': 'Compare' }, box),
        h('td', { 'data-label': 'Status' }, statusBadge(j.status),
          cached ? h('div', { class: 'small-text' }, h('a', { href: `#/runs/${encodeURIComponent(cached.of)}`, class: 'badge from-cache', title: cached.title }, cached.text)) : null),
        h('td', { 'data-label': 'Name' }, h('a', { href: `#/runs/${encodeURIComponent(j.id)}`, class: 'run-link' }, j.name || j.id), h('div', { class: 'muted mono small-text' }, j.id),
          j.sweep_id ? h('div', { class: 'small-text' }, h('a', { href: `#/sweeps/${encodeURIComponent(j.sweep_id)}`, class: 'sweep-link' }, 'sweep →')) : null),
        h('td', { 'data-label': 'Labels' }, labelChips(j.labels, pick)),
        h('td', { 'data-label': 'Created' }, timeEl(j.created_at)),
        h('td', { 'data-label': 'Finished' }, timeEl(j.finished_at)),
        h('td', { 'data-label': 'Wall time', class: 'num' }, duration(wallTime(j))),
        h('td', { 'data-label': 'Particle-steps/s', class: 'num' }, pss ? count(pss) : '–'),
        h('td', { 'data-label': 'Progress' }, j.status === 'running' || j.status === 'queued' ? progressBar(j) : j.status === 'completed' ? '100 %' : (j.message ? h('span', { class: 'muted', title: j.message }, truncate(j.message, 40)) : '–')));
    });
    replace(tableHost, h('table', { class: 'runs' },
      h('caption', { class: 'visually-hidden' }, 'Runs, newest first'),
      h('thead', {}, h('tr', {}, ['', 'Status', 'Name', 'Labels', 'Created', 'Finished', 'Wall time', 'Particle-steps/s', 'Progress'].map((t, i) => h('th', { scope: 'col', class: i >= 6 && i <= 7 ? 'num' : null }, i === 0 ? h('span', { class: 'visually-hidden' }, 'Select') : t)))),
      h('tbody', {}, rows)));
  }

  function updateCompare() {
    compareBtn.disabled = selected.size < 1;
    compareBtn.textContent = selected.size ? `Compare selected (${selected.size})` : 'Compare selected';
  }

  load();
  const destroy = () => { alive = false; clearTimeout(timer); };
  destroy.onQuery = () => load();
  return destroy;
}

function truncate(s, n) {
  return s.length > n ? `${s.slice(0, n - 1)}…` : s;
}
