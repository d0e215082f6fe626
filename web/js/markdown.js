// A small Markdown renderer for the repository's guides (`GET /docs/{name}.md`, shown at
// #/docs/{name}): headings (with ids), paragraphs, fenced code, tables, lists (nested by
// indentation), block quotes, rules; inline code, bold, italic, links. Everything is
// escaped first, so the output holds no markup of the source's own; links to other guides
// (`scenes.md#grid`) stay in the dashboard, `javascript:` and other schemes are dropped.
// Pure; tested in web/test/markdown.test.mjs.

/** Escape text for HTML. */
export function escapeHtml(s) {
  return String(s).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' }[c]));
}

/** The id of a heading, as GitHub makes it: lower case, punctuation dropped, spaces → '-'. */
export function headingId(text) {
  return String(text).toLowerCase().replace(/<[^>]*>/g, '').replace(/[^\p{L}\p{N}\s_-]/gu, '').trim().replace(/\s/g, '-');
}

/**
 * Where a link of a guide goes: `other.md#x` → `#/docs/other#x` (the dashboard's page of
 * that guide), `#x` → `#/docs/{current}#x`, http(s) and site paths as they are; anything
 * else (javascript:, data: …) → null.
 */
export function linkTarget(href, current = '') {
  const h = String(href).trim();
  const md = h.match(/^(?:\.\/|\.\.\/docs\/)?([A-Za-z0-9_-]+)\.md(#[^\s]*)?$/);
  if (md) return `#/docs/${md[1]}${md[2] ? md[2].replace('#', '~') : ''}`;
  if (h.startsWith('#')) return `#/docs/${current}${h.replace('#', '~')}`;
  if (/^https?:\/\//i.test(h) || /^\/(?!\/)/.test(h)) return h;
  return null;
}

/** Inline Markdown of one (escaped) line: code spans, links, bold, italic. */
export function inline(text, current = '') {
  const codes = [];
  let s = escapeHtml(text).replace(/`([^`]+)`/g, (_, c) => { codes.push(c); return `\u0000${codes.length - 1}\u0000`; });
  s = s.replace(/!?\[([^\]]+)\]\(([^)\s]+)\)/g, (_, label, href) => {
    const to = linkTarget(href.replace(/&amp;/g, '&'), current);
    return to ? `<a href="${escapeHtml(to)}">${label}</a>` : label;
  });
  s = s.replace(/\*\*([^*]+)\*\*/g, '<strong>$1</strong>')
    .replace(/(^|[^\w*])\*([^*\s][^*]*?)\*(?!\w)/g, '$1<em>$2</em>')
    .replace(/(^|[^\w])_([^_\s][^_]*?)_(?!\w)/g, '$1<em>$2</em>');
  return s.replace(/\u0000(\d+)\u0000/g, (_, i) => `<code>${codes[Number(i)]}</code>`);
}

function splitRow(line) {
  return line.trim().replace(/^\|/, '').replace(/\|$/, '').split(/(?<!\\)\|/).map((c) => c.trim().replace(/\\\|/g, '|'));
}

/** HTML of a Markdown document; `current` is the guide's name (for `#anchor` links). */
export function renderMarkdown(md, current = '') {
  const lines = String(md).replace(/\r\n?/g, '\n').split('\n');
  const out = [];
  let i = 0;
  const isBlockStart = (l) => /^(#{1,6}\s|```|>|\s*([-*+]|\d+[.)])\s|\s*\|)/.test(l) || /^(-{3,}|\*{3,})\s*$/.test(l);
  while (i < lines.length) {
    const line = lines[i];
    if (!line.trim()) { i++; continue; }
    let m;
    if ((m = line.match(/^(#{1,6})\s+(.*?)\s*#*\s*$/))) {
      const n = m[1].length;
      out.push(`<h${n} id="${escapeHtml(headingId(m[2]))}">${inline(m[2], current)}</h${n}>`);
      i++;
    } else if ((m = line.match(/^```\s*([\w+-]*)/))) {
      const body = [];
      i++;
      while (i < lines.length && !/^```/.test(lines[i])) body.push(lines[i++]);
      i++;
      out.push(`<pre class="json"${m[1] ? ` data-lang="${escapeHtml(m[1])}"` : ''}><code>${escapeHtml(body.join('\n'))}</code></pre>`);
    } else if (/^(-{3,}|\*{3,})\s*$/.test(line)) {
      out.push('<hr>');
      i++;
    } else if (/^\s*\|/.test(line) && i + 1 < lines.length && /^\s*\|?\s*:?-{2,}/.test(lines[i + 1])) {
      const head = splitRow(line);
      i += 2;
      const rows = [];
      while (i < lines.length && /^\s*\|/.test(lines[i])) rows.push(splitRow(lines[i++]));
      out.push(`<div class="doc-table-host"><table class="doc-table"><thead><tr>${head.map((c) => `<th scope="col">${inline(c, current)}</th>`).join('')}</tr></thead><tbody>${rows.map((r) => `<tr>${r.map((c) => `<td>${inline(c, current)}</td>`).join('')}</tr>`).join('')}</tbody></table></div>`);
    } else if (/^>/.test(line)) {
      const body = [];
      while (i < lines.length && /^>/.test(lines[i])) body.push(lines[i++].replace(/^>\s?/, ''));
      out.push(`<blockquote>${renderMarkdown(body.join('\n'), current)}</blockquote>`);
    } else if (/^\s*([-*+]|\d+[.)])\s/.test(line)) {
      const indent = line.match(/^\s*/)[0].length;
      const ordered = /^\s*\d/.test(line);
      const items = [];
      while (i < lines.length) {
        const l = lines[i];
        const ind = l.match(/^\s*/)[0].length;
        const item = l.match(/^\s*([-*+]|\d+[.)])\s+(.*)$/);
        if (item && ind === indent && /^\d/.test(item[1]) === ordered) { items.push([item[2]]); i++; continue; }
        if (item && ind === indent) break;
        if (!l.trim()) {
          // a blank line ends the list unless the list goes on after it
          const next = lines[i + 1] || '';
          const sameKind = ordered ? /^\s*\d+[.)]\s/.test(next) : /^\s*[-*+]\s/.test(next);
          if (next.match(/^\s*/)[0].length > indent || (sameKind && next.match(/^\s*/)[0].length === indent)) { i++; continue; }
          break;
        }
        if (ind > indent && items.length) { items[items.length - 1].push(l.slice(Math.min(ind, indent + 2))); i++; continue; }
        if (items.length && !isBlockStart(l)) { items[items.length - 1].push(l.trim()); i++; continue; }
        break;
      }
      const tag = ordered ? 'ol' : 'ul';
      out.push(`<${tag}>${items.map(([first, ...rest]) => {
        const nested = rest.findIndex((r) => /^\s*([-*+]|\d+[.)])\s/.test(r));
        const text = nested < 0 ? [first, ...rest] : [first, ...rest.slice(0, nested)];
        const sub = nested < 0 ? '' : renderMarkdown(rest.slice(nested).join('\n'), current);
        return `<li>${inline(text.join(' '), current)}${sub}</li>`;
      }).join('')}</${tag}>`);
    } else {
      const body = [];
      while (i < lines.length && lines[i].trim() && !isBlockStart(lines[i])) body.push(lines[i++].trim());
      if (!body.length) body.push(lines[i++].trim());
      out.push(`<p>${inline(body.join(' '), current)}</p>`);
    }
  }
  return out.join('\n');
}
