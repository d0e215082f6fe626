// Client of the HTTP API (docs/service.md). Every call goes through `request`, which
// turns error bodies {error, message, details} into an ApiError.

/** Base path of the API. */
export const BASE = '/api/v1';
const TOKEN_KEY = 'fracture.token';

/** The Bearer token the user pasted (kept in localStorage), or ''. */
export function getToken() {
  try { return localStorage.getItem(TOKEN_KEY) || ''; } catch { return ''; }
}
export function setToken(t) {
  try {
    if (t) localStorage.setItem(TOKEN_KEY, t); else localStorage.removeItem(TOKEN_KEY);
  } catch { /* storage disabled: the token lasts for this page only */ }
}

/** An error answered by the API (or the network). */
export class ApiError extends Error {
  constructor(status, body) {
    super(body?.message || `HTTP ${status}`);
    this.status = status;
    this.kind = body?.error || (status === 0 ? 'network' : 'http');
    this.details = Array.isArray(body?.details) ? body.details : [];
  }
}

/** Reads of the server not yet answered: requests and loading pictures (see `settled`). */
const inFlight = new Set();

/** Counts `p` as in flight until it settles; returns `p`. */
export function track(p) {
  inFlight.add(p);
  const done = () => inFlight.delete(p);
  p.then(done, done);
  return p;
}

/**
 * Resolves once every tracked read so far has been answered (or failed), so that a page can
 * delete a run without its own reads of that run failing behind it.
 */
export async function settled() {
  while (inFlight.size) await Promise.allSettled([...inFlight]);
}

/** fetch + JSON with our error format. `body` objects are sent as JSON. */
export function request(method, path, opts = {}) {
  return track(requestOnce(method, path, opts));
}

async function requestOnce(method, path, { body, accept = 'application/json', raw = false } = {}) {
  const headers = { Accept: accept };
  const token = getToken();
  if (token) headers.Authorization = `Bearer ${token}`;
  let payload;
  if (body !== undefined) {
    headers['Content-Type'] = 'application/json';
    payload = typeof body === 'string' ? body : JSON.stringify(body);
  }
  let res;
  try {
    res = await fetch(BASE + path, { method, headers, body: payload });
  } catch (e) {
    throw new ApiError(0, { error: 'network', message: `cannot reach the server (${e.message})` });
  }
  if (!res.ok) {
    let b = null;
    try { b = await res.json(); } catch { /* not JSON */ }
    if (!b || typeof b !== 'object') b = { message: `${res.status} ${res.statusText}` };
    throw new ApiError(res.status, b);
  }
  if (raw) return res;
  if (res.status === 204) return null;
  const text = await res.text();
  return text ? JSON.parse(text) : null;
}

/**
 * One page of the job list. The list may come as an array (cursor in an `X-Next-Cursor` or
 * `Link: <...cursor=...>; rel="next"` header) or as an object {jobs|items, next_cursor}.
 */
export async function listJobs({ status, label, limit = 20, cursor } = {}) {
  const q = new URLSearchParams();
  if (status) q.set('status', status);
  if (label) q.set('label', label);
  if (limit) q.set('limit', String(limit));
  if (cursor) q.set('cursor', cursor);
  const res = await request('GET', `/jobs?${q}`, { raw: true });
  const body = await res.json();
  let jobs, next = null;
  if (Array.isArray(body)) {
    jobs = body;
  } else {
    jobs = body.jobs || body.items || body.data || [];
    next = body.next_cursor ?? body.next ?? body.cursor ?? null;
  }
  if (!next) next = res.headers.get('X-Next-Cursor');
  if (!next) {
    const link = res.headers.get('Link') || '';
    const m = link.match(/<([^>]*)>\s*;\s*rel="?next"?/);
    if (m) next = new URL(m[1], location.href).searchParams.get('cursor');
  }
  return { jobs, next: next || null };
}

export const getJob = (id) => request('GET', `/jobs/${encodeURIComponent(id)}`);
export const cancelJob = (id) => request('POST', `/jobs/${encodeURIComponent(id)}/cancel`);
export const rerunJob = (id) => request('POST', `/jobs/${encodeURIComponent(id)}/rerun`);
export const deleteJob = (id) => request('DELETE', `/jobs/${encodeURIComponent(id)}`);
export const submitJob = (req) => request('POST', '/jobs', { body: req });
export const listScenes = () => request('GET', '/scenes');
export const validateScene = (text) => request('POST', '/scenes/validate', { body: text });
export const listSnapshots = (id) => request('GET', `/jobs/${encodeURIComponent(id)}/snapshots`);
/** `POST /api/v1/sweeps` with {scene, parameters: {path: [values…]}, name?, labels?, priority?}. */
export const createSweep = (req) => request('POST', '/sweeps', { body: req });

/** History rows (`crack-tips` or `energy`), optionally only those after `since`. */
export function history(id, kind, since) {
  const q = since !== undefined && since !== null ? `?since=${encodeURIComponent(since)}` : '';
  return request('GET', `/jobs/${encodeURIComponent(id)}/${kind}${q}`);
}

/** The history as CSV text (Accept: text/csv). */
export async function historyCsv(id, kind) {
  const res = await request('GET', `/jobs/${encodeURIComponent(id)}/${kind}`, { accept: 'text/csv', raw: true });
  return res.blob();
}

/**
 * A snapshot picture; `opts` are render options of the query (`px_per_cell`, `width`,
 * `range`, …), `ext` `png` (the image) or `json` (its render report, with `aliased`).
 */
export function snapshotUrl(id, index, component, opts = {}, ext = 'png') {
  const q = new URLSearchParams(Object.entries(opts).filter(([, v]) => v !== undefined && v !== null && v !== '')).toString();
  return `${BASE}/jobs/${encodeURIComponent(id)}/snapshots/${index}/${encodeURIComponent(component)}.${ext}${q ? `?${q}` : ''}`;
}
export function mcapUrl(id) {
  return `${BASE}/jobs/${encodeURIComponent(id)}/fields.mcap`;
}
/** The crack path picture: x–y of every tip over time over the body outline (SVG). */
export function pathSvgUrl(id) {
  return `${BASE}/jobs/${encodeURIComponent(id)}/path.svg`;
}
/** A guide of the repository (`docs/{name}.md`, served as Markdown outside the API). */
export function docUrl(name) {
  return `/docs/${encodeURIComponent(name)}.md`;
}
/** The snapshots as a zipped VTK series (`fields.pvd` for ParaView). */
export function vtkUrl(id) {
  return `${BASE}/jobs/${encodeURIComponent(id)}/vtk.zip`;
}

/**
 * Subscribe to a job's Server-Sent Events. `handlers` maps event names (progress, crack_tip,
 * energy, snapshot, status) to functions of the parsed data; `onopen`/`onerror` are passed
 * through. Returns a function that closes the stream.
 */
export function subscribe(id, handlers) {
  const es = new EventSource(`${BASE}/jobs/${encodeURIComponent(id)}/events`);
  for (const name of ['progress', 'crack_tip', 'energy', 'snapshot', 'status', 'message', 'restart', 'restarted']) {
    if (!handlers[name]) continue;
    es.addEventListener(name, (ev) => {
      let data = ev.data;
      try { data = JSON.parse(ev.data); } catch { /* plain text */ }
      handlers[name](data);
    });
  }
  if (handlers.onopen) es.onopen = handlers.onopen;
  es.onerror = (e) => { if (handlers.onerror) handlers.onerror(e, es); };
  return () => es.close();
}
