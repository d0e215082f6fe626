// Compare runs: overlay the crack-tip speed and J curves of several runs, with a legend.
// The selection lives in the URL (#/compare?ids=a,b,c) so a comparison can be shared.

import * as api from '../api.js';
import { Plot, PALETTE, DASHES } from '../plot.js';
import { sceneWaveSpeeds, speedRefLines } from '../waves.js';
import { h, replace, hashQuery, timeUnit, statusBadge, dateTime, num } from '../util.js';
import { rowsOf, tipName } from './run.js';

export function compareView(main) {
  let alive = true;
  let plots = [];
  let timer = 0;

  const picker = h('fieldset', { class: 'picker' }, h('legend', {}, 'Runs to compare'), h('p', { class: 'muted' }, 'Loading runs…'));
  const chosenHost = h('div', { class: 'chosen' });
  const plotGrid = h('div', { class: 'plot-grid' });
  replace(main,
    h('div', { class: 'page-head' }, h('h1', {}, 'Compare runs')),
    h('details', { class: 'card', open: true, id: 'compare-picker' }, h('summary', {}, 'Choose runs'), picker),
    chosenHost, plotGrid);

  const ids = () => (hashQuery().get('ids') || '').split(',').map((s) => s.trim()).filter(Boolean);

  function setIds(list) {
    const q = list.length ? `?ids=${list.map(encodeURIComponent).join(',')}` : '';
    location.hash = `#/compare${q}`;
  }

  async function loadPicker() {
    try {
      const { jobs } = await api.listJobs({ limit: 100 });
      if (!alive) return;
      const cur = new Set(ids());
      const boxes = jobs.map((j) => {
        const cid = `cmp-${j.id}`;
        return h('div', { class: 'pick' },
          h('input', {
            type: 'checkbox', id: cid, value: j.id, checked: cur.has(j.id),
            onchange: () => {
              const sel = [...picker.querySelectorAll('input[type=checkbox]:checked')].map((x) => x.value);
              // keep the order in which runs were picked
              const keep = ids().filter((x) => sel.includes(x));
              setIds([...keep, ...sel.filter((x) => !keep.includes(x))]);
            },
          }),
          h('label', { for: cid }, statusBadge(j.status), ' ', h('b', {}, j.name || j.id), ' ',
            h('span', { class: 'muted small-text' }, `${dateTime(j.created_at)} · ${Object.entries(j.labels || {}).map(([k, v]) => `${k}:${v}`).join(' ')}`)));
      });
      replace(picker, h('legend', {}, 'Runs to compare (newest 100)'),
        jobs.length ? h('div', { class: 'pick-list' }, boxes) : h('p', { class: 'muted' }, 'No runs yet.'));
    } catch (e) {
      if (alive) replace(picker, h('legend', {}, 'Runs to compare'), h('p', { class: 'error' }, `Could not list runs: ${e.message}`));
    }
  }

  let shownKey = '';
  async function loadPlots(refresh = false) {
    clearTimeout(timer);
    const list = ids();
    // a live refresh of the same selection keeps the plots (zoom, hidden series)
    refresh = refresh && shownKey === list.join(',') && plots.length > 0;
    if (!refresh) {
      for (const p of plots) p.destroy();
      plots = [];
      plotGrid.replaceChildren();
    }
    for (const box of picker.querySelectorAll('input[type=checkbox]')) box.checked = list.includes(box.value);
    if (!list.length) {
      replace(chosenHost, h('p', { class: 'empty-state' }, 'Pick two or more runs above (or tick them in the runs list) to overlay their crack-tip speed and J curves.'));
      return;
    }
    if (!refresh) replace(chosenHost, h('p', { class: 'muted' }, 'Loading…'));
    const results = await Promise.all(list.map(async (id) => {
      try {
        const [job, tips] = await Promise.all([api.getJob(id), api.history(id, 'crack-tips').catch(() => [])]);
        return { id, job, tips: rowsOf(tips) };
      } catch (e) {
        return { id, error: e };
      }
    }));
    if (!alive) return;
    const ok = results.filter((r) => r.job);
    replace(chosenHost, h('ul', { class: 'chosen-list' }, results.map((r, i) => h('li', {},
      h('span', { class: 'swatch-dot', style: `background:${PALETTE[i % PALETTE.length]}`, 'aria-hidden': 'true' }),
      r.job ? [h('a', { href: `#/runs/${encodeURIComponent(r.id)}` }, r.job.name || r.id), ' ', statusBadge(r.job.status)] : h('span', { class: 'error' }, `${r.id}: ${r.error.message}`),
      ' ', h('button', { type: 'button', class: 'small secondary', 'aria-label': `Remove ${r.job ? r.job.name : r.id} from the comparison`, onclick: () => setIds(ids().filter((x) => x !== r.id)) }, 'Remove')))));
    const end = Math.max(...ok.map((r) => (r.job.scene && r.job.scene.time && r.job.scene.time.end) || 0), 1e-9);
    const xUnit = timeUnit(end);
    if (!refresh) {
      plots = [
        new Plot(plotGrid, { id: 'cmp-speed', fileStem: 'compare', title: 'Crack-tip speed', yLabel: 'speed', yUnit: 'm/s', yPrefix: false, yZero: true, xUnit, filter: 2, empty: 'No crack-tip data in these runs' }),
        new Plot(plotGrid, { id: 'cmp-length', fileStem: 'compare', title: 'Crack length', yLabel: 'crack length', yUnit: 'm', xUnit, empty: 'No crack-tip data in these runs' }),
        new Plot(plotGrid, { id: 'cmp-j', fileStem: 'compare', title: 'J-integral: J1 (solid), J2 (dashed)', yLabel: 'J', yUnit: 'J/m²', xUnit, filter: 0, empty: 'No crack-tip data in these runs' }),
      ];
      shownKey = list.join(',');
    }
    const [speedPlot, lengthPlot, jPlot] = plots;
    for (const p of plots) { p.setXUnit(xUnit); p.setXDomain(0, end); }
    // reference lines: once if every run has the same material speeds, else one set per run
    const sets = ok.map((r) => ({ r, s: sceneWaveSpeeds(r.job.scene) })).filter((x) => x.s);
    const distinct = [...new Map(sets.map((x) => [`${x.s.speeds.cL.toPrecision(6)}/${x.s.speeds.cS.toPrecision(6)}`, x])).values()];
    speedPlot.setRefLines(distinct.length === 1 ? speedRefLines(distinct[0].s.speeds)
      : distinct.flatMap((x) => speedRefLines(x.s.speeds, ` (${x.r.job.name || x.r.id})`)));
    results.forEach((r, i) => {
      if (!r.job) return;
      const color = PALETTE[i % PALETTE.length];
      const byTip = new Map();
      for (const row of r.tips) {
        const k = `${row.crack}/${row.tip}`;
        if (!byTip.has(k)) byTip.set(k, []);
        byTip.get(k).push(row);
      }
      const multi = r.tips.some((row) => Number(row.crack) > 0);
      let t = 0;
      for (const [k, rows] of byTip) {
        rows.sort((a, b) => a.time - b.time);
        const label = `${r.job.name || r.id}${byTip.size > 1 ? `, ${tipName(rows[0], multi)}` : ''}`;
        const dash = byTip.size > 1 ? DASHES[t % DASHES.length] : '';
        const xs = rows.map((x) => x.time);
        speedPlot.setData(`${r.id}/${k}`, xs, rows.map((x) => x.speed), { name: label, color, dash });
        lengthPlot.setData(`${r.id}/${k}`, xs, rows.map((x) => x.length), { name: label, color, dash });
        jPlot.setData(`${r.id}/${k}/1`, xs, rows.map((x) => x.j1), { name: `J1 ${label}`, color });
        jPlot.setData(`${r.id}/${k}/2`, xs, rows.map((x) => x.j2), { name: `J2 ${label}`, color, dash: DASHES[1] });
        t++;
      }
      const maxV = Math.max(0, ...r.tips.map((x) => Math.abs(x.speed) || 0));
      const sp = sceneWaveSpeeds(r.job.scene);
      const li = chosenHost.querySelectorAll('li')[i];
      if (li && maxV > 0) li.append(h('span', { class: 'muted small-text' }, ` peak ${num(maxV, 4)} m/s${sp ? ` = ${num(maxV / sp.speeds.cS, 3)} c_S` : ''}`));
    });
    // runs still going: refresh in a while
    if (ok.some((r) => r.job.status === 'running' || r.job.status === 'queued')) timer = setTimeout(() => { if (alive) loadPlots(true); }, 4000);
  }

  loadPicker().then(() => loadPlots());
  const destroy = () => { alive = false; clearTimeout(timer); for (const p of plots) p.destroy(); };
  destroy.onQuery = () => loadPlots(false);
  return destroy;
}
