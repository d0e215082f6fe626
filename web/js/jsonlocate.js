// Find where a JSON path (as the validator reports it: "materials.plate.poissons_ratio",
// "bodies.0.region" or "bodies[0].region") sits in the JSON text, so the editor can jump to
// the offending line. A tiny position-keeping JSON reader; it never throws on bad input
// (then the deepest path found so far, or line 1, is returned).

function parse(text) {
  let i = 0;
  const ws = () => { while (i < text.length && ' \t\r\n'.includes(text[i])) i++; };
  const str = () => {
    const start = i;
    i++; // opening quote
    let out = '';
    while (i < text.length && text[i] !== '"') {
      if (text[i] === '\\') {
        const c = text[i + 1];
        if (c === 'u') { out += String.fromCharCode(parseInt(text.slice(i + 2, i + 6), 16)); i += 6; continue; }
        out += { n: '\n', t: '\t', r: '\r', b: '\b', f: '\f' }[c] ?? c;
        i += 2;
        continue;
      }
      out += text[i++];
    }
    i++; // closing quote
    return { type: 'string', pos: start, value: out };
  };
  const value = () => {
    ws();
    const pos = i;
    const c = text[i];
    if (c === '{') {
      i++;
      const entries = [];
      ws();
      if (text[i] === '}') { i++; return { type: 'object', pos, entries }; }
      while (i < text.length) {
        ws();
        if (text[i] !== '"') throw new Error('key expected');
        const k = str();
        ws();
        if (text[i] !== ':') throw new Error(': expected');
        i++;
        entries.push({ key: k.value, pos: k.pos, value: null });
        entries[entries.length - 1].value = value();
        ws();
        if (text[i] === ',') { i++; continue; }
        if (text[i] === '}') { i++; break; }
        throw new Error(', or } expected');
      }
      return { type: 'object', pos, entries };
    }
    if (c === '[') {
      i++;
      const items = [];
      ws();
      if (text[i] === ']') { i++; return { type: 'array', pos, items }; }
      while (i < text.length) {
        items.push(value());
        ws();
        if (text[i] === ',') { i++; continue; }
        if (text[i] === ']') { i++; break; }
        throw new Error(', or ] expected');
      }
      return { type: 'array', pos, items };
    }
    if (c === '"') return str();
    const m = /^(-?\d+(\.\d+)?([eE][+-]?\d+)?|true|false|null)/.exec(text.slice(i, i + 64));
    if (!m) throw new Error('value expected');
    i += m[0].length;
    return { type: 'scalar', pos };
  };
  try {
    const root = value();
    ws();
    if (i < text.length) throw new Error('trailing text');
    return { root, errorPos: -1 };
  } catch {
    return { root: null, errorPos: Math.min(i, text.length) };
  }
}

/** Split a validator path into segments: "a.b[0].c" / "a.b.0.c" → ["a","b","0","c"]. */
export function splitPath(path) {
  return String(path || '')
    .replace(/^\$\.?/, '')
    .replace(/\[(\d+)\]/g, '.$1')
    .replace(/\["([^"]*)"\]/g, '.$1')
    .split('.')
    .filter((s) => s !== '');
}

/** Line number (1-based) of a character offset. */
export function lineOf(text, pos) {
  let n = 1;
  for (let k = 0; k < pos && k < text.length; k++) if (text.charCodeAt(k) === 10) n++;
  return n;
}

/**
 * Where `path` is in `text`: {line, pos, found} where found tells whether the whole path was
 * resolved (otherwise the position is that of the deepest existing parent, e.g. for a
 * missing required field).
 */
export function locate(text, path) {
  const { root } = parse(text);
  if (!root) return { line: 1, pos: 0, found: false };
  const segs = splitPath(path);
  let node = root, pos = root.pos, k = 0;
  while (k < segs.length) {
    let next = null, used = 1;
    if (node.type === 'object') {
      // keys may contain dots (material names): try the longest match first
      for (let n = segs.length - k; n >= 1 && !next; n--) {
        const key = segs.slice(k, k + n).join('.');
        const e = node.entries.find((x) => x.key === key);
        if (e) { next = e; used = n; }
      }
      if (next) { pos = next.pos; node = next.value; }
    } else if (node.type === 'array' && /^\d+$/.test(segs[k])) {
      const item = node.items[Number(segs[k])];
      if (item) { next = item; pos = item.pos; node = item; }
    }
    if (!next) return { line: lineOf(text, pos), pos, found: false };
    k += used;
  }
  return { line: lineOf(text, pos), pos, found: true };
}

/** Position of a JSON.parse SyntaxError in `text`, as {line, pos}, if the message tells. */
export function syntaxErrorPosition(text, err) {
  const msg = String(err && err.message);
  let m = /line (\d+) column (\d+)/.exec(msg);
  if (m) {
    const line = Number(m[1]);
    let pos = 0;
    for (let l = 1; l < line; l++) pos = text.indexOf('\n', pos) + 1;
    return { line, pos: pos + Number(m[2]) - 1 };
  }
  m = /position (\d+)/.exec(msg);
  if (m) { const pos = Number(m[1]); return { line: lineOf(text, pos), pos }; }
  // newer engines often leave the position out: find it with our own reader
  const { errorPos } = parse(text);
  return errorPos >= 0 ? { line: lineOf(text, errorPos), pos: errorPos } : null;
}
