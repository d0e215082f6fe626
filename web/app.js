// Dashboard entry: hash routing (#/runs, #/runs/{id}, #/compare?ids=a,b, #/submit,
// #/gallery, #/sweeps, #/sweeps/{id}, #/docs/{name}).
// Each view is a function (main element, route params) that returns a cleanup function.

import { getToken, setToken } from './js/api.js';
import { notify } from './js/util.js';
import { runsView } from './js/views/runs.js';
import { runView } from './js/views/run.js';
import { compareView } from './js/views/compare.js';
import { submitView } from './js/views/submit.js';
import { sweepsView, sweepView } from './js/views/sweep.js';
import { galleryView } from './js/views/gallery.js';
import { docsView } from './js/views/docs.js';

const main = document.getElementById('main');
let cleanup = null;
let lastPath = null;

function route() {
  const hash = location.hash || '#/runs';
  const [path] = hash.slice(1).split('?');
  const parts = path.split('/').filter(Boolean);
  let view, params = {}, nav = parts[0] || 'runs';
  if (parts[0] === 'runs' && parts[1]) { view = runView; params = { id: decodeURIComponent(parts[1]) }; }
  else if (parts[0] === 'sweeps' && parts[1]) { view = sweepView; params = { id: decodeURIComponent(parts[1]) }; nav = 'sweeps'; }
  else if (parts[0] === 'sweeps') view = sweepsView;
  else if (parts[0] === 'compare') view = compareView;
  else if (parts[0] === 'submit') view = submitView;
  else if (parts[0] === 'gallery') view = galleryView;
  else if (parts[0] === 'docs') { view = docsView; params = { name: decodeURIComponent(parts[1] || 'scenes') }; nav = 'docs'; }
  else { view = runsView; nav = 'runs'; }
  for (const a of document.querySelectorAll('[data-nav]')) {
    if (a.dataset.nav === nav) a.setAttribute('aria-current', 'page'); else a.removeAttribute('aria-current');
  }
  // a view may update its own query (filters, selection) without being rebuilt
  if (path === lastPath && cleanup && cleanup.onQuery) { cleanup.onQuery(); return; }
  if (cleanup) { try { (cleanup.destroy || cleanup)(); } catch (e) { console.error(e); } }
  cleanup = null;
  const samePage = path === lastPath;
  lastPath = path;
  main.replaceChildren();
  try {
    cleanup = view(main, params) || null;
  } catch (e) {
    console.error(e);
  }
  if (!samePage) {
    window.scrollTo(0, 0);
    main.focus({ preventScroll: true });
  }
}

window.addEventListener('hashchange', route);
if (!location.hash) history.replaceState(null, '', '#/runs');
route();

// token form in the header
const tokenInput = document.getElementById('token-input');
tokenInput.value = getToken();
document.getElementById('token-form').addEventListener('submit', (ev) => {
  ev.preventDefault();
  setToken(tokenInput.value.trim());
  notify(tokenInput.value.trim() ? 'Token saved in this browser.' : 'Token cleared.');
  ev.target.closest('details').open = false;
});
document.getElementById('token-clear').addEventListener('click', () => {
  tokenInput.value = '';
  setToken('');
  notify('Token cleared.');
});
