// #/docs/{name}: a guide of the repository (`GET /docs/{name}.md`, the text of docs/{name}.md
// when the server was built) rendered by web/js/markdown.js; `#/docs/{name}~{heading id}`
// scrolls to a heading. The Markdown itself is linked for reading elsewhere.

import { docUrl, track } from '../api.js';
import { h, replace } from '../util.js';
import { renderMarkdown } from '../markdown.js';

export function docsView(main, { name: raw }) {
  let alive = true;
  const [name, anchor] = String(raw || 'scenes').split('~');
  const body = h('article', { class: 'doc card', id: 'doc-body' }, h('p', { class: 'muted' }, 'Loading…'));
  replace(main,
    h('p', { class: 'crumbs' }, h('a', { href: '#/submit' }, '← New run'), ' · ', h('a', { href: '#/gallery' }, 'Examples')),
    h('div', { class: 'page-head' }, h('h1', { class: 'visually-hidden' }, `Guide: ${name}`),
      h('a', { class: 'button secondary', id: 'doc-raw', href: docUrl(name), download: `${name}.md`, title: 'The guide as Markdown' }, `Markdown: ${name}.md`)),
    body);
  (async () => {
    let text;
    try {
      const res = await track(fetch(docUrl(name), { headers: { Accept: 'text/markdown' } }));
      if (!res.ok) throw new Error(res.status === 404 ? `this server has no guide ${name}.md` : `HTTP ${res.status}`);
      text = await res.text();
    } catch (e) {
      if (alive) replace(body, h('p', { class: 'error' }, `Could not load the guide: ${e.message}`));
      return;
    }
    if (!alive) return;
    body.innerHTML = renderMarkdown(text, name); // escaped by the renderer
    const first = body.querySelector('h1');
    document.title = `${first ? first.textContent : name} · mpm-fracture`;
    if (anchor) {
      const el = document.getElementById(anchor);
      if (el) el.scrollIntoView();
    }
  })();
  return () => { alive = false; document.title = 'mpm-fracture'; };
}
