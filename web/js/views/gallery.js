// #/gallery: the built-in example scenes (`GET /api/v1/scenes`) as cards: description, size
// (particles, steps, particle-steps) and the server's estimated wall time, with a one-click
// Run (POST /api/v1/jobs, then the run page), Edit (the scene editor) and Sweep (the sweep
// form with this scene).

import * as api from '../api.js';
import { h, replace, count, duration, notify, si } from '../util.js';

/** Short text of an estimate: `about 10 s`, `under a second`, '' when unknown. */
export function estimateText(seconds) {
  if (seconds === null || seconds === undefined || !Number.isFinite(Number(seconds))) return '';
  const s = Number(seconds);
  if (s < 1) return 'under a second';
  // an estimate: no false precision (whole seconds, then 5 s, then 10 s, then minutes)
  const r = s < 10 ? Math.round(s) : s < 60 ? Math.round(s / 5) * 5 : s < 3600 ? Math.round(s / 10) * 10 : Math.round(s / 60) * 60;
  return `about ${duration(r)}`;
}

/**
 * The description of an example split for its card: `{lead, rest}`, the lead being the
 * first sentence (up to the first '. ' after 20 characters; at most `max` characters, else
 * cut at a word and marked with …), the rest what follows ('' when nothing does).
 */
export function splitDescription(text, max = 220) {
  const t = String(text ?? '').trim();
  const m = t.slice(20).search(/\.\s/);
  let cut = m < 0 ? t.length : m + 21;
  if (cut > max) { cut = t.lastIndexOf(' ', max); if (cut < 20) cut = max; }
  const lead = t.slice(0, cut).trim();
  const rest = t.slice(cut).trim();
  return { lead: rest && !/\.$/.test(lead) ? `${lead.replace(/[,;:]$/, '')} …` : lead, rest };
}

export function galleryView(main) {
  let alive = true;
  const grid = h('div', { class: 'gallery', id: 'gallery', 'aria-live': 'polite' }, h('p', { class: 'muted' }, 'Loading…'));
  const basis = h('p', { class: 'muted small-text', id: 'gallery-basis' });
  replace(main,
    h('div', { class: 'page-head' }, h('h1', {}, 'Examples')),
    h('p', { class: 'muted' }, 'The scenes that come with the service. ', h('strong', {}, 'Run'),
      ' submits one as it is and opens its page; ', h('strong', {}, 'Edit'), ' opens it in the scene editor; ',
      h('strong', {}, 'Sweep'), ' starts a parameter sweep from it. The scene format: ', h('a', { href: '#/docs/scenes' }, 'the scene guide'), '.'),
    basis, grid);

  async function run(s, btn) {
    btn.disabled = true;
    try {
      const scene = { ...s.scene, name: s.scene.name || s.name };
      const job = await api.submitJob({ scene, labels: { example: s.name } });
      notify(`Run submitted: ${job.id}`);
      location.hash = `#/runs/${encodeURIComponent(job.id)}`;
    } catch (e) {
      if (!alive) return;
      notify(`Could not run ${s.name}: ${e.message}${e.status === 401 ? ' (set the API token at the top)' : ''}`, 'error');
      btn.disabled = false;
    }
  }

  function description(text) {
    if (!text) return h('p', { class: 'gallery-desc muted' }, 'No description.');
    const { lead, rest } = splitDescription(text);
    return h('div', { class: 'gallery-desc' }, h('p', {}, lead),
      rest ? h('details', {}, h('summary', {}, 'More'), h('p', { class: 'small-text' }, rest)) : null);
  }

  function card(s) {
    const cracks = Array.isArray(s.scene && s.scene.cracks) ? s.scene.cracks.length : 0;
    const end = s.scene && s.scene.time && s.scene.time.end;
    const est = estimateText(s.estimated_wall_seconds);
    const runBtn = h('button', { type: 'button', class: 'gallery-run', 'data-name': s.name }, 'Run');
    runBtn.addEventListener('click', () => run(s, runBtn));
    return h('article', { class: 'card gallery-card', 'data-name': s.name, 'aria-labelledby': `ex-${s.name}` },
      h('h2', { id: `ex-${s.name}`, class: 'mono' }, s.name),
      description(s.description),
      h('dl', { class: 'meta compact' },
        h('dt', {}, 'Size'), h('dd', { class: 'gallery-size' }, s.particles ? `${count(s.particles)} particles × ${count(s.steps)} steps = ${count(s.particle_steps)} particle-steps` : '–'),
        h('dt', {}, 'Simulated'), h('dd', {}, end ? `${si(end, 's')}${cracks ? `, ${cracks} crack${cracks === 1 ? '' : 's'}` : ''}` : '–'),
        h('dt', {}, 'Estimated'), h('dd', { class: 'gallery-estimate', 'data-seconds': s.estimated_wall_seconds ?? '' }, est ? `${est} of wall time` : '–')),
      h('div', { class: 'row wrap' }, runBtn,
        h('a', { class: 'button secondary', href: `#/submit?example=${encodeURIComponent(s.name)}` }, 'Edit'),
        h('a', { class: 'button secondary', href: `#/submit?example=${encodeURIComponent(s.name)}&sweep=1` }, 'Sweep')));
  }

  (async () => {
    let list;
    try {
      list = await api.listScenes();
    } catch (e) {
      if (alive) replace(grid, h('p', { class: 'error' }, `Could not load the examples: ${e.message}`));
      return;
    }
    if (!alive) return;
    const scenes = Array.isArray(list) ? list : (list.scenes || []);
    const b = scenes.find((s) => s.estimate_basis);
    basis.textContent = b ? `Wall-time estimates: particle-steps at ${count(b.estimate_particle_steps_per_second)} particle-steps/s (${b.estimate_basis}); the queue's wait is not included.` : '';
    replace(grid, scenes.length ? scenes.map(card) : h('p', { class: 'empty-state' }, 'This server has no example scenes.'));
  })();
  return () => { alive = false; };
}
