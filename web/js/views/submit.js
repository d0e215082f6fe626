// New run: start from a built-in example (or a copy of a run), edit the JSON, validate
// (each error listed with its path and marked at its line), see the run size, submit; or
// start a parameter sweep from the editor's scene or an example (POST /api/v1/sweeps).

import * as api from '../api.js';
import { h, replace, count, si, parseLabels, hashQuery, notify, prettyJson, orderScene } from '../util.js';
import { locate, syntaxErrorPosition } from '../jsonlocate.js';
import { numericPaths, sweepParameters } from '../sweep.js';

export function submitView(main) {
  let alive = true;
  let scenes = [];
  let marks = []; // error lines
  let validTimer = 0;

  const exampleSel = h('select', { id: 'example' }, h('option', { value: '' }, 'Loading…'));
  const exampleDesc = h('p', { class: 'muted', id: 'example-desc' });
  const textarea = h('textarea', {
    id: 'scene-json', class: 'editor-text', spellcheck: false, autocomplete: 'off', wrap: 'off',
    'aria-describedby': 'editor-help validation', 'aria-label': 'Scene JSON',
  });
  const gutter = h('div', { class: 'editor-gutter', 'aria-hidden': 'true' });
  const backdrop = h('div', { class: 'editor-backdrop', 'aria-hidden': 'true' });
  const editor = h('div', { class: 'editor' }, gutter, h('div', { class: 'editor-main' }, backdrop, textarea));
  const labelsIn = h('input', { id: 'labels', type: 'text', placeholder: 'sweep:toughness, owner:me', autocomplete: 'off', spellcheck: false });
  const prioIn = h('input', { id: 'priority', type: 'number', step: 1, value: 0 });
  const validateBtn = h('button', { type: 'button', id: 'validate-btn', class: 'secondary', onclick: () => validate(true) }, 'Validate');
  const submitBtn = h('button', { type: 'submit', id: 'submit-btn' }, 'Submit run');
  const formatBtn = h('button', { type: 'button', class: 'secondary', onclick: formatJson }, 'Format JSON');
  const result = h('div', { id: 'validation', class: 'validation', 'aria-live': 'polite' });

  const form = h('form', { class: 'submit-form', onsubmit: (ev) => { ev.preventDefault(); submit(); } },
    h('div', { class: 'field' }, h('label', { for: 'example' }, 'Start from an example'), exampleSel, exampleDesc),
    h('div', { class: 'field' },
      h('label', { for: 'scene-json' }, 'Scene (JSON, SI units)'),
      h('p', { id: 'editor-help', class: 'muted small-text' }, 'See ', h('a', { href: '#/docs/scenes', id: 'scene-guide-link' }, 'the scene format in the scene guide'), '. Tab inserts two spaces; Esc then Tab leaves the editor.'),
      editor),
    result,
    h('div', { class: 'row wrap' },
      h('div', { class: 'field' }, h('label', { for: 'labels' }, 'Labels (key:value, comma-separated)'), labelsIn),
      h('div', { class: 'field narrow' }, h('label', { for: 'priority' }, 'Priority'), prioIn)),
    h('div', { class: 'row wrap' }, validateBtn, formatBtn, submitBtn));

  // ---- sweep form ------------------------------------------------------------------------
  const sweepBase = h('select', { id: 'sweep-base' }, h('option', { value: '' }, 'the scene in the editor'));
  const sweepName = h('input', { id: 'sweep-name', type: 'text', placeholder: 'the scene’s name', autocomplete: 'off', spellcheck: false });
  const sweepRows = h('div', { class: 'sweep-params', id: 'sweep-params' });
  const pathList = h('datalist', { id: 'sweep-path-list' });
  const sweepResult = h('div', { id: 'sweep-result', 'aria-live': 'polite' });
  const sweepBtn = h('button', { type: 'submit', id: 'sweep-submit' }, 'Start sweep');
  let rowSeq = 0;
  function paramRow(path = '', values = '') {
    const n = ++rowSeq;
    const row = h('div', { class: 'row wrap sweep-param' },
      h('div', { class: 'field grow' }, h('label', { for: `sweep-path-${n}` }, 'Parameter path'),
        h('input', { id: `sweep-path-${n}`, class: 'sweep-path mono', type: 'text', list: 'sweep-path-list', value: path, placeholder: 'cracks.0.propagation.toughness', autocomplete: 'off', spellcheck: false })),
      h('div', { class: 'field grow' }, h('label', { for: `sweep-values-${n}` }, 'Values (comma-separated)'),
        h('input', { id: `sweep-values-${n}`, class: 'sweep-values mono', type: 'text', value: values, placeholder: '25, 100, 250', autocomplete: 'off', spellcheck: false })),
      h('button', { type: 'button', class: 'secondary small sweep-remove', 'aria-label': 'Remove this parameter', onclick: () => { row.remove(); if (!sweepRows.children.length) sweepRows.append(paramRow()); } }, 'Remove'));
    return row;
  }
  sweepRows.append(paramRow());
  const sweepForm = h('form', { class: 'card sweep-form', id: 'sweep-form', 'aria-labelledby': 'sweep-h', onsubmit: (ev) => { ev.preventDefault(); startSweep(); } },
    h('h2', { id: 'sweep-h' }, 'Start a sweep'),
    h('p', { class: 'muted small-text' }, 'One run for every combination of the values below, each a copy of the base scene with the parameters set (a dot path into the scene; numbers index arrays). The sweep’s page follows them all.'),
    h('div', { class: 'row wrap' },
      h('div', { class: 'field' }, h('label', { for: 'sweep-base' }, 'Base scene'), sweepBase),
      h('div', { class: 'field grow' }, h('label', { for: 'sweep-name' }, 'Sweep name (optional)'), sweepName)),
    sweepRows, pathList,
    h('div', { class: 'row wrap' },
      h('button', { type: 'button', class: 'secondary', id: 'sweep-add', onclick: () => { const r = paramRow(); sweepRows.append(r); r.querySelector('input').focus(); } }, 'Add parameter'),
      sweepBtn),
    sweepResult);

  /** The base scene of the sweep: an example's, or the editor's (parsed; errors shown). */
  function sweepScene() {
    const ex = scenes.find((x) => x.name === sweepBase.value);
    if (ex) return { ...ex.scene, name: ex.scene.name || ex.name };
    try {
      return JSON.parse(textarea.value);
    } catch (e) {
      throw new Error(`the scene in the editor is not valid JSON (${e.message})`);
    }
  }

  function updatePathList() {
    let scene = null;
    try { scene = sweepScene(); } catch { /* shown on submit */ }
    replace(pathList, scene ? numericPaths(scene).map((p) => h('option', { value: p })) : null);
  }
  sweepBase.addEventListener('change', updatePathList);
  sweepForm.addEventListener('input', () => sweepResult.replaceChildren());
  sweepForm.addEventListener('focusin', (ev) => { if (ev.target.classList.contains('sweep-path')) updatePathList(); });

  async function startSweep() {
    let req;
    try {
      const rows = [...sweepRows.querySelectorAll('.sweep-param')].map((r) => ({ path: r.querySelector('.sweep-path').value, values: r.querySelector('.sweep-values').value }));
      req = { scene: sweepScene(), parameters: sweepParameters(rows), priority: Number(prioIn.value) || 0, labels: parseLabels(labelsIn.value) };
      if (sweepName.value.trim()) req.name = sweepName.value.trim();
    } catch (e) {
      replace(sweepResult, h('p', { class: 'error', role: 'alert' }, e.message));
      return;
    }
    sweepBtn.disabled = true;
    try {
      const sw = await api.createSweep(req);
      notify(`Sweep started: ${sw.total ?? ''} runs`);
      location.hash = `#/sweeps/${encodeURIComponent(sw.id)}`;
    } catch (e) {
      if (!alive) return;
      const details = e.details && e.details.length ? h('ul', { class: 'error-list' }, e.details.map((d) => h('li', {}, h('span', { class: 'mono' }, d.path || '(sweep)'), `: ${d.message}`))) : null;
      replace(sweepResult, h('div', { class: 'errors', role: 'alert' }, h('p', {}, h('strong', {}, 'Could not start the sweep: '), e.message, e.status === 401 ? ' (set the API token at the top)' : ''), details));
    } finally {
      sweepBtn.disabled = false;
    }
  }

  replace(main, h('div', { class: 'page-head' }, h('h1', {}, 'New run'),
    h('div', { class: 'actions' }, h('a', { class: 'button secondary', href: '#/gallery' }, 'Example gallery'), h('a', { class: 'button secondary', href: '#sweep-form', onclick: (ev) => { ev.preventDefault(); sweepForm.scrollIntoView(); sweepForm.querySelector('.sweep-path').focus(); } }, 'Start a sweep'))),
  form, sweepForm);

  // ---- editor: line numbers and error-line highlight kept in step with the textarea -----
  function renderDecor() {
    const lines = textarea.value.split('\n');
    const bad = new Set(marks);
    const g = [];
    const b = [];
    for (let i = 1; i <= lines.length; i++) {
      g.push(bad.has(i) ? `<span class="bad">${i}</span>` : String(i));
      b.push(bad.has(i) ? `<mark data-line="${i}">${escapeHtml(lines[i - 1]) || ' '}</mark>` : escapeHtml(lines[i - 1]));
    }
    gutter.innerHTML = g.join('\n');
    backdrop.innerHTML = `${b.join('\n')}\n`;
    syncScroll();
  }
  function syncScroll() {
    backdrop.scrollTop = textarea.scrollTop;
    backdrop.scrollLeft = textarea.scrollLeft;
    gutter.scrollTop = textarea.scrollTop;
  }
  textarea.addEventListener('scroll', syncScroll);
  let escaped = false;
  textarea.addEventListener('keydown', (ev) => {
    if (ev.key === 'Escape') { escaped = true; return; }
    if (ev.key === 'Tab' && !ev.shiftKey && !escaped && !ev.ctrlKey && !ev.altKey && !ev.metaKey) {
      ev.preventDefault();
      const { selectionStart: s, selectionEnd: e } = textarea;
      textarea.setRangeText('  ', s, e, 'end');
      textarea.dispatchEvent(new Event('input'));
    }
    escaped = false;
  });
  textarea.addEventListener('input', () => {
    marks = [];
    renderDecor();
    clearTimeout(validTimer);
    validTimer = setTimeout(() => validate(false), 900);
  });

  /** Put the caret on `line` and scroll it into the middle of the editor. */
  function goToLine(line, pos) {
    const text = textarea.value;
    let start = 0;
    for (let l = 1; l < line; l++) start = text.indexOf('\n', start) + 1;
    let end = text.indexOf('\n', start);
    if (end < 0) end = text.length;
    textarea.focus({ preventScroll: true });
    textarea.setSelectionRange(pos !== undefined && pos >= start && pos <= end ? pos : start, end);
    const lh = parseFloat(getComputedStyle(textarea).lineHeight) || 18;
    textarea.scrollTop = Math.max(0, (line - 1) * lh - textarea.clientHeight / 2);
    syncScroll();
    editor.scrollIntoView({ block: 'nearest' });
  }

  function formatJson() {
    try {
      textarea.value = prettyJson(JSON.parse(textarea.value));
      marks = [];
      renderDecor();
    } catch (e) {
      showSyntaxError(e);
    }
  }

  // ---- validation -----------------------------------------------------------------------
  function showSyntaxError(e) {
    const at = syntaxErrorPosition(textarea.value, e);
    marks = at ? [at.line] : [];
    renderDecor();
    replace(result, h('div', { class: 'errors', role: 'alert' },
      h('p', {}, h('strong', {}, 'The text is not valid JSON. ')),
      h('ul', {}, h('li', {}, at ? h('button', { type: 'button', class: 'link', onclick: () => goToLine(at.line, at.pos) }, `line ${at.line}`) : null, `: ${e.message}`))));
  }

  function showErrors(err) {
    const text = textarea.value;
    const details = err.details && err.details.length ? err.details : [{ path: '', message: err.message }];
    const located = details.map((d) => ({ ...d, at: locate(text, d.path) }));
    marks = [...new Set(located.map((d) => d.at.line))];
    renderDecor();
    replace(result, h('div', { class: 'errors', role: 'alert' },
      h('p', {}, h('strong', {}, details.length === 1 ? 'The scene has a problem:' : `The scene has ${details.length} problems:`)),
      h('ul', { class: 'error-list' }, located.map((d) => h('li', {},
        h('button', { type: 'button', class: 'link mono', title: `Go to line ${d.at.line}`, onclick: () => goToLine(d.at.line) }, d.path || '(scene)'),
        h('span', { class: 'muted small-text' }, ` line ${d.at.line}${d.at.found ? '' : ' (missing here)'}`), ': ', d.message)))));
  }

  function parseText() {
    try {
      return JSON.parse(textarea.value);
    } catch (e) {
      showSyntaxError(e);
      return undefined;
    }
  }

  /** Validate with the server. Returns true when valid. `focusErrors` moves to the first one. */
  async function validate(focusErrors) {
    clearTimeout(validTimer);
    const scene = parseText();
    if (scene === undefined) return false;
    try {
      const r = await api.validateScene(JSON.stringify(scene));
      if (!alive) return false;
      marks = [];
      renderDecor();
      const steps = r.steps, particles = r.particles;
      replace(result, h('div', { class: 'ok', id: 'run-size' },
        h('p', {}, h('strong', {}, 'Valid. '), 'Run size:'),
        h('dl', { class: 'meta compact' },
          h('dt', {}, 'Particles'), h('dd', {}, count(particles)),
          h('dt', {}, 'Grid nodes'), h('dd', {}, count(r.grid_nodes)),
          h('dt', {}, 'Time step'), h('dd', {}, si(r.time_step, 's')),
          h('dt', {}, 'Steps'), h('dd', {}, count(steps)),
          h('dt', {}, 'Particle-steps'), h('dd', {}, count(particles * steps)))));
      return true;
    } catch (e) {
      if (!alive) return false;
      if (e.status === 422 || e.status === 400) {
        showErrors(e);
        if (focusErrors) { const b = result.querySelector('button'); if (b) b.focus(); }
      } else {
        replace(result, h('p', { class: 'error', role: 'alert' }, `Could not validate: ${e.message}`));
      }
      return false;
    }
  }

  async function submit() {
    const scene = parseText();
    if (scene === undefined) return;
    let labels;
    try {
      labels = parseLabels(labelsIn.value);
    } catch (e) {
      replace(result, h('p', { class: 'error', role: 'alert' }, e.message));
      labelsIn.focus();
      return;
    }
    submitBtn.disabled = true;
    try {
      const job = await api.submitJob({ scene, priority: Number(prioIn.value) || 0, labels });
      notify(`Run submitted: ${job.id}`);
      location.hash = `#/runs/${encodeURIComponent(job.id)}`;
    } catch (e) {
      if (!alive) return;
      if (e.status === 422 || e.status === 400) showErrors(e);
      else if (e.status === 401) {
        replace(result, h('p', { class: 'error', role: 'alert' }, `${e.message} — this server needs an API token: open “API token” at the top, paste it and save.`));
        const d = document.querySelector('details.token');
        if (d) { d.open = true; document.getElementById('token-input').focus(); }
      } else replace(result, h('p', { class: 'error', role: 'alert' }, `Could not submit: ${e.message}`));
    } finally {
      submitBtn.disabled = false;
    }
  }

  // ---- examples -------------------------------------------------------------------------
  function setText(obj) {
    textarea.value = prettyJson(orderScene(obj));
    marks = [];
    result.replaceChildren();
    renderDecor();
    textarea.scrollTop = 0;
    syncScroll();
  }

  exampleSel.addEventListener('change', () => {
    const s = scenes.find((x) => x.name === exampleSel.value);
    if (!s) return;
    // Nothing of the previous example (or copied run) stays: its name and description go
    // with it, and the "copy of a run" entry once another example is picked.
    const copy = exampleSel.querySelector('option[value=""]');
    if (copy) copy.remove();
    exampleDesc.textContent = s.description || '';
    const scene = { ...s.scene };
    scene.name = s.scene.name || s.name;
    if (s.scene.description) scene.description = s.scene.description; else delete scene.description;
    setText(scene);
    validate(false);
  });

  (async () => {
    const from = hashQuery().get('from');
    try {
      const list = await api.listScenes();
      if (!alive) return;
      scenes = Array.isArray(list) ? list : (list.scenes || []);
    } catch (e) {
      if (alive) notify(`Could not load the example scenes: ${e.message}`, 'error');
    }
    if (!alive) return;
    replace(exampleSel, from ? h('option', { value: '' }, 'copy of a run') : null,
      scenes.map((s) => h('option', { value: s.name }, s.name)));
    sweepBase.append(...scenes.map((s) => h('option', { value: s.name }, `example: ${s.name}`)));
    const wanted = hashQuery().get('example');
    if (hashQuery().get('sweep')) {
      if (wanted && scenes.some((s) => s.name === wanted)) sweepBase.value = wanted;
      requestAnimationFrame(() => { sweepForm.scrollIntoView(); const p = sweepForm.querySelector('.sweep-path'); if (p) p.focus({ preventScroll: true }); });
    }
    if (from) {
      try {
        const job = await api.getJob(from);
        if (!alive) return;
        exampleDesc.textContent = `Copy of run ${job.name || from}.`;
        setText(job.scene);
        validate(false);
        return;
      } catch (e) {
        notify(`Could not copy run ${from}: ${e.message}`, 'error');
      }
    }
    const first = scenes.find((s) => s.name === wanted) || scenes.find((s) => (s.scene.cracks || []).length) || scenes[0];
    if (first) {
      exampleSel.value = first.name;
      exampleSel.dispatchEvent(new Event('change'));
    } else renderDecor();
  })();

  return () => { alive = false; clearTimeout(validTimer); };
}

function escapeHtml(s) {
  return s.replace(/[&<>]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;' }[c]));
}
